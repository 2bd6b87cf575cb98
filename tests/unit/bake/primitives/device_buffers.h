// Buffer helpers of primitives_test on the executable's one OpenCL context
// (support/device_context.h).
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "device/context.h"
#include "support/device_context.h"

namespace luxel::pipeline::testing {

using ::luxel::testing::shared_context;

// A read-write device buffer holding `data`.
device::Buffer upload_rw(const std::vector<uint32_t>& data, const char* name);
// A device int (a live count).
device::Buffer upload_count(int count, const char* name = "count");
std::vector<uint32_t> read_back(const device::Buffer& buffer, size_t elements);
int read_count(const device::Buffer& buffer);

std::vector<uint32_t> random_keys(size_t n, uint32_t max_key, uint64_t seed);

}  // namespace luxel::pipeline::testing

// Aborts the test with the status message when a Status / Result is not OK.
#define ASSERT_OK(expr)                                              \
  do {                                                               \
    const auto& _st = (expr);                                        \
    ASSERT_TRUE(_st.is_ok()) << ::luxel::testing_status_string(_st); \
  } while (0)

namespace luxel {
inline std::string testing_status_string(const Status& s) {
  return s.to_string();
}
template <typename T>
std::string testing_status_string(const Result<T>& r) {
  return r.status().to_string();
}
}  // namespace luxel
