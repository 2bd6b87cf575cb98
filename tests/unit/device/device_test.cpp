// Device layer on the real OpenCL driver (PoCL in CI).
#include <gtest/gtest.h>
#include <stdlib.h>

#include <filesystem>
#include <fstream>
#include <vector>

#include "device/context.h"
#include "device/feature_set.h"
#include "device/kernel_sources.h"
#include "device/program_cache.h"

namespace luxel::device {
namespace {

namespace fs = std::filesystem;

std::unique_ptr<Context> make_context() {
  auto ctx = Context::create("");
  EXPECT_TRUE(ctx.is_ok()) << ctx.status().to_string();
  return ctx.is_ok() ? std::move(ctx.value()) : nullptr;
}

// A scoped environment variable.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const std::string& value) : name_(name) {
    if (const char* old = getenv(name)) old_ = old, had_ = true;
    setenv(name, value.c_str(), 1);
  }
  ~ScopedEnv() {
    if (had_)
      setenv(name_, old_.c_str(), 1);
    else
      unsetenv(name_);
  }

 private:
  const char* name_;
  std::string old_;
  bool had_ = false;
};

fs::path temp_dir(const std::string& tag) {
  fs::path p = fs::temp_directory_path() / ("luxel-" + tag + "-" + std::to_string(getpid()));
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

TEST(DeviceChoice, ListsAtLeastOneDeviceAndDescribesIt) {
  auto devices = list_devices();
  ASSERT_TRUE(devices.is_ok()) << devices.status().to_string();
  ASSERT_FALSE(devices->empty());
  EXPECT_FALSE(devices->front().device_name.empty());
  EXPECT_NE(devices->front().describe().find(devices->front().device_name), std::string::npos);
}

TEST(DeviceChoice, SpecsSelectOrFailWithTheDeviceList) {
  auto by_index = choose_device("0:0");
  ASSERT_TRUE(by_index.is_ok()) << by_index.status().to_string();
  EXPECT_EQ(by_index->platform_index, 0);
  auto missing = choose_device("7:7");
  ASSERT_FALSE(missing.is_ok());
  EXPECT_EQ(missing.status().code(), StatusCode::kNotFound);
  EXPECT_NE(missing.status().message().find("7:7"), std::string::npos);
  EXPECT_NE(missing.status().message().find(by_index->device_name), std::string::npos)
      << "the error lists the devices there are";
  auto by_name = choose_device(by_index->device_name.substr(0, 4));
  ASSERT_TRUE(by_name.is_ok());
  {
    ScopedEnv env("LUXEL_DEVICE", "no-such-device-xyz");
    auto from_env = choose_device("");
    ASSERT_FALSE(from_env.is_ok());
    EXPECT_NE(from_env.status().message().find("LUXEL_DEVICE"), std::string::npos);
  }
}

TEST(KernelSources, EmbeddedIncludesExpandOnceWithLineMarkers) {
  auto src = expand_kernel_source("intersect.cl");
  ASSERT_TRUE(src.is_ok()) << src.status().to_string();
  EXPECT_NE(src->find("#line 1 \"shared/geometry.h\""), std::string::npos);
  EXPECT_EQ(src->find("#include \"shared/"), std::string::npos);
  // geometry.h is included from three places but expanded once.
  const std::string marker = "#line 1 \"shared/geometry.h\"";
  EXPECT_EQ(src->find(marker), src->rfind(marker));
  auto missing = expand_kernel_source("does_not_exist.cl");
  ASSERT_FALSE(missing.is_ok());
  EXPECT_NE(missing.status().message().find("does_not_exist.cl"), std::string::npos);
}

TEST(KernelSources, DevelopmentFolderOverridesEmbeddedCopies) {
  const fs::path dir = temp_dir("kdir");
  std::ofstream(dir / "fill.cl")
      << "__kernel void fill_int(__global int* o, const int v, const int n)"
         " { if ((int)get_global_id(0) < n) o[get_global_id(0)] = v + 1; }\n";
  ScopedEnv env("LUXEL_KERNEL_DIR", dir.string());
  auto text = read_kernel_file("fill.cl");
  ASSERT_TRUE(text.is_ok());
  EXPECT_NE(text->find("v + 1"), std::string::npos);
  fs::remove_all(dir);
}

TEST(Launch, NamedLaunchesAreTimedAndResultsCorrect) {
  auto ctx = make_context();
  ASSERT_TRUE(ctx);
  auto program = ctx->programs().get("fill.cl", FeatureSet());
  ASSERT_TRUE(program.is_ok()) << program.status().to_string();
  auto kernel = program.value()->kernel("fill_int");
  ASSERT_TRUE(kernel.is_ok());
  const int n = 1000;
  auto buf = ctx->alloc(n * sizeof(int), "out");
  ASSERT_TRUE(buf.is_ok());
  ASSERT_TRUE(kernel->set_args(buf.value(), 7, n).is_ok());
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(ctx->launch(kernel.value(), n, 64).is_ok());
  std::vector<int> out(n, 0);
  ASSERT_TRUE(ctx->read(buf.value(), out).is_ok());
  ASSERT_TRUE(ctx->finish().is_ok());
  for (int v : out) ASSERT_EQ(v, 7);
  const auto& stats = ctx->timer().stats();
  ASSERT_EQ(stats.count("fill_int"), 1u);
  EXPECT_EQ(stats.at("fill_int").launches, 3u);
  EXPECT_GE(stats.at("fill_int").total_ms, 0.0);
  EXPECT_NE(ctx->timer().table().find("fill_int"), std::string::npos);
}

TEST(Launch, BadArgumentsReturnNamedErrors) {
  auto ctx = make_context();
  ASSERT_TRUE(ctx);
  auto program = ctx->programs().get("fill.cl", FeatureSet());
  ASSERT_TRUE(program.is_ok());
  auto missing = program.value()->kernel("no_such_kernel");
  ASSERT_FALSE(missing.is_ok());
  EXPECT_NE(missing.status().message().find("CL_INVALID_KERNEL_NAME"), std::string::npos);
  auto kernel = program.value()->kernel("fill_int");
  ASSERT_TRUE(kernel.is_ok());
  // Argument 1 is an int; a double is the wrong size.
  Status st = kernel->set_args(Buffer(), 1.0);
  ASSERT_FALSE(st.is_ok());
  EXPECT_NE(st.message().find("fill_int"), std::string::npos);
  EXPECT_NE(st.message().find("argument 1"), std::string::npos);
  EXPECT_NE(st.message().find("CL_INVALID_ARG_SIZE"), std::string::npos);
}

TEST(ProgramCache, SecondContextLoadsTheBinaryFromDisk) {
  const fs::path cache = temp_dir("cache");
  ScopedEnv env("LUXEL_CACHE_DIR", cache.string());
  FeatureSet f;
  f.set(Feature::STACK_SIZE, 3);  // any option: fill.cl reads none
  std::string key;
  {
    auto ctx = make_context();
    ASSERT_TRUE(ctx);
    auto p = ctx->programs().get("fill.cl", f);
    ASSERT_TRUE(p.is_ok()) << p.status().to_string();
    EXPECT_FALSE(p.value()->from_disk_cache());
    key = p.value()->key();
    // Same process: the in-memory program is returned.
    auto again = ctx->programs().get("fill.cl", f);
    ASSERT_TRUE(again.is_ok());
    EXPECT_EQ(again.value(), p.value());
    // Different options: a different key.
    auto other = ctx->programs().get("fill.cl", FeatureSet());
    ASSERT_TRUE(other.is_ok());
    EXPECT_NE(other.value()->key(), key);
  }
  EXPECT_TRUE(fs::exists(cache / (key + ".bin")));
  auto ctx = make_context();
  ASSERT_TRUE(ctx);
  auto p = ctx->programs().get("fill.cl", f);
  ASSERT_TRUE(p.is_ok());
  EXPECT_TRUE(p.value()->from_disk_cache());
  EXPECT_EQ(p.value()->key(), key);
  auto k = p.value()->kernel("fill_int");
  EXPECT_TRUE(k.is_ok());
  fs::remove_all(cache);
}

TEST(ProgramCache, FailedBuildKeepsLogAndExpandedSource) {
  const fs::path cache = temp_dir("cache-fail");
  const fs::path kdir = temp_dir("kdir-fail");
  std::ofstream(kdir / "broken.cl")
      << "__kernel void broken(__global int* o) { o[0] = undeclared_thing; }\n";
  ScopedEnv env_cache("LUXEL_CACHE_DIR", cache.string());
  ScopedEnv env_k("LUXEL_KERNEL_DIR", kdir.string());
  auto ctx = make_context();
  ASSERT_TRUE(ctx);
  auto p = ctx->programs().get("broken.cl", FeatureSet());
  ASSERT_FALSE(p.is_ok());
  const std::string& msg = p.status().message();
  EXPECT_NE(msg.find("broken.cl"), std::string::npos);
  EXPECT_NE(msg.find("CL_BUILD_PROGRAM_FAILURE"), std::string::npos);
  EXPECT_NE(msg.find("undeclared_thing"), std::string::npos)
      << "the build log is in the message: " << msg;
  size_t kept = 0;
  for (const auto& e : fs::directory_iterator(cache / "failed")) {
    kept++;
    if (e.path().extension() == ".cl") {
      std::ifstream f(e.path());
      std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
      EXPECT_NE(text.find("undeclared_thing"), std::string::npos);
    }
  }
  EXPECT_EQ(kept, 2u);
  fs::remove_all(cache);
  fs::remove_all(kdir);
}

TEST(Buffers, OversizedAllocationIsResourceExhaustedAndNamed) {
  auto ctx = make_context();
  ASSERT_TRUE(ctx);
  auto b = ctx->alloc(ctx->info().max_alloc_bytes + 1, "huge lightmap");
  ASSERT_FALSE(b.is_ok());
  EXPECT_EQ(b.status().code(), StatusCode::kResourceExhausted);
  EXPECT_NE(b.status().message().find("huge lightmap"), std::string::npos);
}

}  // namespace
}  // namespace luxel::device
