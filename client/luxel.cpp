// luxel: the Luxel command-line client.
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "commands.h"
#include "luxel_version.h"

namespace {

void usage(FILE* out) {
  std::fprintf(
      out,
      "luxel %s (%s): lightmap baker\n\n"
      "usage: luxel <command> [options]\n\n"
      "commands:\n"
      "  inspect SCENE [--device SPEC] [--rays N] [--seed S] [--no-trace]\n"
      "        scene statistics, OpenCL device, BVH build, ray throughput of the\n"
      "        OpenCL kernels and of Embree on the scene\n"
      "  bake SCENE --local --out DIR [--samples N] [--time S] [--target-error E]\n"
      "        [--bounces B] [--resolution N | --texel-density D] [--seed S] ...\n"
      "        bake an irradiance lightmap in-process (luxel bake --help for all options)\n"
      "  devices\n"
      "        list OpenCL devices (SPEC for --device: gpu, cpu, P:D, or a name substring;\n"
      "        the LUXEL_DEVICE environment variable sets the default)\n\n"
      "commands on a luxeld daemon (each: --help for its options):\n"
      "  upload SCENE [--name N]\n"
      "        upload a .gltf (with its buffers and images) or .glb; print its id and statistics\n"
      "  bake SCENE --out DIR [settings] [--priority P] [--snapshots DIR] [--detach]\n"
      "        upload if needed, submit, watch with a progress bar, download the results\n"
      "  status BAKE           state, progress, ETA and artifacts of a bake\n"
      "  list [--state S] | --scenes   bakes (optionally in state S) or scenes\n"
      "  watch BAKE [--snapshots DIR]  follow a bake; write its snapshots to DIR\n"
      "  cancel BAKE           cancel a queued or running bake (--finish: keep it, end now)\n"
      "  fetch BAKE --out DIR [--artifact NAME]   download (and verify) results\n"
      "  report DIR|BAKE [--csv F] [--plot F.png]   error against time of a bake\n"
      "  settings [--json]     every bake setting: option, default, range, units\n"
      "  health [--service N]  is luxeld SERVING? (grpc.health.v1; exit 0 yes, 1 no)\n"
      "  common options: --server HOST:PORT (default $LUXEL_SERVER or 127.0.0.1:50051),\n"
      "        --token T ($LUXEL_TOKEN), --tls-ca FILE, --tls, --timeout S, --json\n\n"
      "exit codes: 0 success, 1 error (daemon, network, files), 2 usage error,\n"
      "            3 the bake failed, was cancelled or interrupted\n",
      LUXEL_VERSION, LUXEL_GIT_REVISION);
}

}  // namespace

int main(int argc, char** argv) {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);  // progress lines appear as they are printed
  if (argc < 2) {
    usage(stderr);
    return 2;
  }
  const std::string cmd = argv[1];
  std::vector<std::string> args(argv + 2, argv + argc);
  if (cmd == "-h" || cmd == "--help" || cmd == "help") {
    usage(stdout);
    return 0;
  }
  if (cmd == "--version") {
    std::printf("luxel %s (%s)\n", LUXEL_VERSION, LUXEL_GIT_REVISION);
    return 0;
  }
  if (cmd == "inspect") return luxel::cli::run_inspect(args);
  if (cmd == "devices") return luxel::cli::run_devices(args);
  if (cmd == "bake") return luxel::cli::run_bake(args);
  if (cmd == "upload") return luxel::cli::run_upload(args);
  if (cmd == "status") return luxel::cli::run_status(args);
  if (cmd == "list") return luxel::cli::run_list(args);
  if (cmd == "watch") return luxel::cli::run_watch(args);
  if (cmd == "cancel") return luxel::cli::run_cancel(args);
  if (cmd == "fetch") return luxel::cli::run_fetch(args);
  if (cmd == "report") return luxel::cli::run_report(args);
  if (cmd == "settings") return luxel::cli::run_settings(args);
  if (cmd == "health") return luxel::cli::run_health(args);
  std::fprintf(stderr, "luxel: unknown command '%s'\n\n", cmd.c_str());
  usage(stderr);
  return 2;
}
