#include "common/machine_info.h"

#include <sys/utsname.h>

#include <fstream>
#include <thread>

#include "luxel_version.h"

namespace luxel {

MachineInfo machine_info() {
  MachineInfo m;
  std::ifstream cpuinfo("/proc/cpuinfo");
  std::string line;
  while (std::getline(cpuinfo, line)) {
    if (line.rfind("model name", 0) == 0) {
      const size_t colon = line.find(':');
      if (colon != std::string::npos) m.cpu_model = line.substr(colon + 2);
      break;
    }
  }
  if (m.cpu_model.empty()) m.cpu_model = "unknown CPU";
  m.hardware_threads = std::thread::hardware_concurrency();
  utsname u{};
  if (uname(&u) == 0) m.os = std::string(u.sysname) + " " + u.release;
  m.luxel_version = std::string(LUXEL_VERSION) + " (" + LUXEL_GIT_REVISION + ")";
  return m;
}

std::string describe(const MachineInfo& m) {
  return m.cpu_model + " (" + std::to_string(m.hardware_threads) + " threads), " + m.os +
         ", luxel " + m.luxel_version;
}

}  // namespace luxel
