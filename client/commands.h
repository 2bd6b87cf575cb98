// Subcommands of the `luxel` CLI. Each returns the process exit code.
#pragma once

#include <string>
#include <vector>

namespace luxel::cli {

int run_inspect(const std::vector<std::string>& args);
int run_devices(const std::vector<std::string>& args);
int run_bake(const std::vector<std::string>& args);

}  // namespace luxel::cli
