#include "support/device_context.h"

#include <cstdio>
#include <cstdlib>
#include <memory>

namespace luxel::testing {

device::Context& shared_context() {
  static std::unique_ptr<device::Context> ctx = [] {
    auto created = device::Context::create();
    if (!created) {
      std::fprintf(stderr, "no OpenCL device: %s\n", created.status().to_string().c_str());
      std::abort();
    }
    return std::move(created.value());
  }();
  return *ctx;
}

}  // namespace luxel::testing
