#include "device_buffers.h"

namespace luxel::pipeline::testing {

device::Buffer upload_rw(const std::vector<uint32_t>& data, const char* name) {
  auto buf = shared_context().upload(data, name, CL_MEM_READ_WRITE);
  EXPECT_TRUE(buf.is_ok()) << buf.status().to_string();
  return buf.is_ok() ? std::move(buf.value()) : device::Buffer();
}

device::Buffer upload_count(int count, const char* name) {
  auto buf = shared_context().upload_bytes(&count, sizeof count, name, CL_MEM_READ_WRITE);
  EXPECT_TRUE(buf.is_ok()) << buf.status().to_string();
  return buf.is_ok() ? std::move(buf.value()) : device::Buffer();
}

std::vector<uint32_t> read_back(const device::Buffer& buffer, size_t elements) {
  std::vector<uint32_t> out(elements);
  const Status st = shared_context().read(buffer, out);
  EXPECT_TRUE(st.is_ok()) << st.to_string();
  return out;
}

int read_count(const device::Buffer& buffer) {
  int n = -12345;
  const Status st = shared_context().read(buffer, &n, sizeof n);
  EXPECT_TRUE(st.is_ok()) << st.to_string();
  return n;
}

std::vector<uint32_t> random_keys(size_t n, uint32_t max_key, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<uint32_t> dist(0, max_key);
  std::vector<uint32_t> keys(n);
  for (auto& k : keys) k = dist(rng);
  return keys;
}

}  // namespace luxel::pipeline::testing
