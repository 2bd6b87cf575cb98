// Subcommands of the `luxel` CLI, declared once: LUXEL_CLI_COMMANDS expands
// into their declarations here and into the dispatch and the usage text in
// luxel.cpp, so a new subcommand is one entry here and its own file. Each
// returns the process exit code: 0 success, 1 runtime error (daemon,
// network, files), 2 usage error, 3 the bake failed or was cancelled.
#pragma once

#include <string>
#include <vector>

namespace luxel::cli {

// X(name, function, group, usage): group 0 runs in-process (client/*.cpp),
// group 1 on a luxeld daemon over gRPC (client/remote/, report.cpp and
// bake_options.cpp read either). `bake` is both: in-process with --local,
// otherwise on luxeld (bake_remote.cpp).
#define LUXEL_CLI_COMMANDS(X)                                                                      \
  X("inspect", run_inspect, 0,                                                                     \
    "  inspect SCENE [--device SPEC] [--rays N] [--seed S] [--no-trace]\n"                         \
    "        scene statistics, OpenCL device, BVH build, ray throughput of the\n"                  \
    "        OpenCL kernels and of Embree on the scene\n")                                         \
  X("bake", run_bake, 0,                                                                           \
    "  bake SCENE --local --out DIR [--samples N] [--time S] [--target-error E]\n"                 \
    "        [--bounces B] [--resolution N | --texel-density D] [--seed S] ...\n"                  \
    "        bake an irradiance lightmap in-process (luxel bake --help for all options)\n")        \
  X("devices", run_devices, 0,                                                                     \
    "  devices\n"                                                                                  \
    "        list OpenCL devices (SPEC for --device: gpu, cpu, P:D, or a name substring;\n"        \
    "        the LUXEL_DEVICE environment variable sets the default)\n")                           \
  X("upload", run_upload, 1,                                                                       \
    "  upload SCENE [--name N]\n"                                                                  \
    "        upload a .gltf (with its buffers and images) or .glb; print its id and statistics\n") \
  X(nullptr, run_bake, 1,                                                                          \
    "  bake SCENE --out DIR [settings] [--priority P] [--snapshots DIR] [--detach]\n"              \
    "        upload if needed, submit, watch with a progress bar, download the results\n")         \
  X("status", run_status, 1,                                                                       \
    "  status BAKE           state, progress, ETA and artifacts of a bake\n")                      \
  X("list", run_list, 1,                                                                           \
    "  list [--state S] | --scenes   bakes (optionally in state S) or scenes\n")                   \
  X("watch", run_watch, 1,                                                                         \
    "  watch BAKE [--snapshots DIR]  follow a bake; write its snapshots to DIR\n")                 \
  X("cancel", run_cancel, 1,                                                                       \
    "  cancel BAKE           cancel a queued or running bake (--finish: keep it, end now)\n")      \
  X("fetch", run_fetch, 1,                                                                         \
    "  fetch BAKE --out DIR [--artifact NAME]   download (and verify) results\n")                  \
  X("report", run_report, 1,                                                                       \
    "  report DIR|BAKE [--csv F] [--plot F.png]   error against time of a bake\n")                 \
  X("settings", run_settings, 1,                                                                   \
    "  settings [--json]     every bake setting: option, default, range, units\n")                 \
  X("health", run_health, 1,                                                                       \
    "  health [--service N]  is luxeld SERVING? (grpc.health.v1; exit 0 yes, 1 no)\n")

// Each subcommand's entry point (a name listed twice is declared once: the
// redeclaration is harmless).
#define LUXEL_CLI_DECLARE(name, function, group, usage) \
  int function(const std::vector<std::string>& args);
LUXEL_CLI_COMMANDS(LUXEL_CLI_DECLARE)
#undef LUXEL_CLI_DECLARE

}  // namespace luxel::cli
