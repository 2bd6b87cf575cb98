// The host-memory estimate at submit (bake/host_memory.h) against a real
// bake job (bake, denoise, outputs) on the default device: the process's
// peak resident set (VmHWM) grows by no more than the estimate, and by at
// least a stated fraction of it, so the estimate is an upper bound that
// means something. Bytes only, no timing. Its own executable: VmHWM is the
// peak of the whole process.
#include "bake/host_memory.h"

#include <gtest/gtest.h>
#include <malloc.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "bake/resource_estimate.h"
#include "job/bake_job.h"
#include "scene/gltf_import.h"
#include "settings/settings_schema.h"
#include "support/device_context.h"

namespace luxel {
namespace {

using pipeline::BakeSettings;

// A line of /proc/self/status in bytes ("VmHWM:   123 kB").
size_t status_bytes(const std::string& key) {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind(key + ":", 0) == 0) return std::stoull(line.substr(key.size() + 1)) * 1024;
  return 0;
}

// The peak can only be reset by writing 5 to /proc/self/clear_refs (Linux
// 4.0+); without it the test measures from the process's own peak.
bool reset_peak() {
  std::ofstream out("/proc/self/clear_refs");
  out << "5";
  out.flush();
  return static_cast<bool>(out);
}

BakeSettings many_encodings(int resolution) {
  BakeSettings s = pipeline::default_settings();
  s.atlas.resolution = resolution;
  s.atlas.texel_density = 0;
  s.samples_per_texel = 1;
  s.max_bounces = 1;
  s.progress_interval_s = 1e9;
  s.denoise = pipeline::Denoise::kOff;
  s.encodings.names = {"sh2", "sg12", "sg9-hemi"};
  return s;
}

class HostMemoryTest : public testing::DeviceTest<> {};

TEST_F(HostMemoryTest, EstimateBoundsThePeakOfARealBake) {
  const std::string dir = LUXEL_SCENES_DIR;
  auto scene = scene::import_gltf_file(dir + "/cornell_box.gltf");
  ASSERT_TRUE(scene) << scene.status().to_string();
  const std::filesystem::path out =
      std::filesystem::temp_directory_path() / ("luxel-host-memory-" + std::to_string(getpid()));
  struct Remove {
    std::filesystem::path p;
    ~Remove() {
      std::error_code ec;
      std::filesystem::remove_all(p, ec);
    }
  } remove{out};
  auto run = [&](const BakeSettings& s, const std::string& sub) {
    job::JobInput in{.scene = &scene.value(), .settings = s};
    return job::run_bake_job(in, *ctx_, {}, (out / sub).string());
  };
  // Kernels built and caches warm before the measured bake: what the
  // process keeps after its first bake is no part of a bake's estimate.
  ASSERT_TRUE(run(many_encodings(64), "warm"));

  const BakeSettings s = many_encodings(1024);
  const auto device = pipeline::DeviceLimits::of(ctx_->info());
  auto e = pipeline::estimate_bake_resources(scene.value(), s, device);
  ASSERT_TRUE(e) << e.status().to_string();
  auto h = pipeline::estimate_host_memory(e.value(), s, !device.is_gpu, false);
  ASSERT_TRUE(h) << h.status().to_string();
  // The result images alone: 1024^2 texels x (4 + 1 + 1 + 27 + 36 + 27) floats.
  EXPECT_EQ(h.value().result_bytes, size_t{1024} * 1024 * 96 * 4);

  malloc_trim(0);
  const bool reset = reset_peak();
  const size_t before = status_bytes("VmRSS");
  const size_t peak_before = status_bytes("VmHWM");
  ASSERT_GT(before, 0u);
  auto job = run(s, "measured");
  ASSERT_TRUE(job) << job.status().to_string();
  const size_t peak = status_bytes("VmHWM");
  if (!reset && peak == peak_before) GTEST_SKIP() << "the process's peak predates the bake";
  const size_t growth = peak - before;
  const size_t estimate = h.value().total();
  // An upper bound ...
  EXPECT_LE(growth, estimate) << "estimate " << h.value().describe();
  // ... within a factor of 3 of what the bake took.
  EXPECT_GE(growth * 3, estimate) << "estimate " << h.value().describe() << ", measured " << growth;
  std::printf("host memory: estimate %zu bytes (%s), measured VmHWM growth %zu bytes\n", estimate,
              h.value().describe().c_str(), growth);
}

TEST(HostMemory, RefusalNamesTheSettingsAndTheBytes) {
  pipeline::ResourceEstimate e;
  e.min_texels = uint64_t{4096} * 4096;
  e.budget = size_t{4} << 30;
  e.per_texel_bytes = 64;
  BakeSettings s = many_encodings(4096);
  s.encodings.names = {"sh1", "sh2", "sg6", "sg9", "sg12", "sg6-hemi", "sg9-hemi", "sg12-hemi"};
  auto h = pipeline::estimate_host_memory(e, s, true, true);
  ASSERT_TRUE(h);
  // 16.7 M texels x (6 + 3 x 67) floats of result images alone.
  EXPECT_EQ(h.value().result_bytes, size_t{4096} * 4096 * 207 * 4);
  const Status st =
      pipeline::check_host_memory(h.value(), s, size_t{1} << 30, "luxeld --host-memory-budget");
  ASSERT_EQ(st.code(), StatusCode::kResourceExhausted);
  for (const char* part : {"settings.resolution 4096", "settings.encodings 'sh1,sh2,sg6,sg9,sg12",
                           "settings.denoise 'off'", "1073741824 bytes",
                           "luxeld --host-memory-budget", "result images"})
    EXPECT_NE(st.message().find(part), std::string::npos) << part << " in " << st.message();
  EXPECT_TRUE(pipeline::check_host_memory(h.value(), s, h.value().total(), "x").is_ok());
  EXPECT_TRUE(pipeline::check_host_memory(h.value(), s, 0, "x").is_ok());
}

TEST(HostMemory, MachineMemoryIsReadAndHalved) {
  const uint64_t total = pipeline::host_memory_bytes();
  EXPECT_GT(total, uint64_t{64} << 20);
  EXPECT_EQ(pipeline::default_host_memory_budget(), total / 2);
}

}  // namespace
}  // namespace luxel
