// Subcommands of the `luxel` CLI. Each returns the process exit code:
// 0 success, 1 runtime error (daemon, network, files), 2 usage error,
// 3 the bake failed or was cancelled.
#pragma once

#include <string>
#include <vector>

namespace luxel::cli {

// In-process (client/*.cpp).
int run_inspect(const std::vector<std::string>& args);
int run_devices(const std::vector<std::string>& args);
// `luxel bake`: in-process with --local, otherwise on luxeld (bake_remote.cpp).
int run_bake(const std::vector<std::string>& args);

// On a luxeld daemon over gRPC (client/remote/).
int run_upload(const std::vector<std::string>& args);
int run_status(const std::vector<std::string>& args);
int run_list(const std::vector<std::string>& args);
int run_watch(const std::vector<std::string>& args);
int run_cancel(const std::vector<std::string>& args);
int run_fetch(const std::vector<std::string>& args);
// `luxel health`: grpc.health.v1 Check, exit 0 when SERVING (health.cpp).
int run_health(const std::vector<std::string>& args);
// `luxel report DIR|BAKE`: error against time (report.cpp; a folder or luxeld).
int run_report(const std::vector<std::string>& args);
// `luxel settings [--json]`: the bake settings schema (bake_options.cpp).
int run_settings(const std::vector<std::string>& args);

}  // namespace luxel::cli
