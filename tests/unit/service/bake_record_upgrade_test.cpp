// A bake record written before encoding, solver and target_metric were typed
// fields (comma-joined strings) loads with the same settings, so a bake queued
// before an upgrade resumes unchanged.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "api/settings_translate.h"
#include "service/bake_store.h"

namespace luxel::service {
namespace {

TEST(BakeRecordUpgrade, StringSettingsBecomeTypedFields) {
  namespace fs = std::filesystem;
  const fs::path dir =
      fs::temp_directory_path() / ("luxel_record_upgrade_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const std::string id(32, 'a');
  fs::create_directories(dir / "bakes" / id);
  std::ofstream(dir / "bakes" / id / "record.json")
      << R"({"format": "luxel.bake_record.v1", "seq": 1,
    "info": {"bakeId": ")"
      << id << R"(", "sceneId": ")" << std::string(64, 'b') << R"(",
      "state": "BAKE_STATE_SUCCEEDED",
      "settings": {"samplesPerTexel": 16, "encoding": "irradiance,sh2,sg6-hemi",
                   "solver": "progressive-nn", "targetMetric": "rmse",
                   "referenceBakeId": ")"
      << std::string(32, 'c') << R"("}}})";
  auto store = BakeStore::open(dir.string());
  ASSERT_TRUE(store) << store.status().message();
  auto info = store.value()->get(id);
  ASSERT_TRUE(info) << info.status().message();
  const v1::BakeSettings& s = info->settings();
  ASSERT_EQ(s.encodings_size(), 3);
  EXPECT_EQ(s.encodings(0), v1::ENCODING_IRRADIANCE);
  EXPECT_EQ(s.encodings(1), v1::ENCODING_SH2);
  EXPECT_EQ(s.encodings(2), v1::ENCODING_SG6_HEMI);
  EXPECT_EQ(s.solver(), v1::SOLVER_PROGRESSIVE_NN);
  EXPECT_EQ(s.target_metric(), v1::TARGET_METRIC_RMSE);
  auto engine = to_engine_settings(s, SettingsLimits{});
  ASSERT_TRUE(engine) << engine.status().message();
  EXPECT_EQ(engine->encodings.names, (std::vector<std::string>{"sh2", "sg6-hemi"}));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace luxel::service
