// Where a measurement was taken: recorded with every benchmark result so runs
// can be compared across machines and versions.
#pragma once

#include <string>

namespace luxel {

struct MachineInfo {
  std::string cpu_model;  // /proc/cpuinfo "model name"
  unsigned hardware_threads = 0;
  std::string os;             // uname sysname + release
  std::string luxel_version;  // version (git revision)
};

MachineInfo machine_info();
// One line: "AMD EPYC ... (2 threads), Linux 6.1, luxel 0.1.0 (abc123)".
std::string describe(const MachineInfo& m);

}  // namespace luxel
