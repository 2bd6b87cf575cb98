// luxel: the Luxel command-line client.
#include <cstdio>
#include "luxel_version.h"
#include <cstring>
#include <string>
#include <vector>

#include "commands.h"

namespace {

void usage(FILE* out) {
  std::fprintf(out,
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
               "        the LUXEL_DEVICE environment variable sets the default)\n",
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
  std::fprintf(stderr, "luxel: unknown command '%s'\n\n", cmd.c_str());
  usage(stderr);
  return 2;
}
