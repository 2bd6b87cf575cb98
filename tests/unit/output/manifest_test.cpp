// Manifest JSON: full round trip, validation errors that name the field.
#include "output/manifest.h"

#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "luxel_version.h"
#include "temp_dir.h"

namespace luxel::output {
namespace {

using testing::read_bytes;
using testing::TempDir;
using testing::write_bytes;

Manifest full_manifest() {
  Manifest m;
  m.luxel_version = "0.1.0";
  m.git_revision = "abc1234-dirty";
  m.scene_name = "sponza \"atrium\"";
  m.scene_sha256 = std::string(64, 'e');
  m.width = 512;
  m.height = 256;
  m.encoding = "irradiance";
  m.units =
      "irradiance E in W/m^2 (radiometric; glTF emissive radiance and light intensities taken 1:1)";
  m.uv_set = "TEXCOORD_1";
  m.atlas_mode = "packed";
  m.instances.push_back({"floor", 0, 2, {0.5f, 0.25f}, {0.0f, 0.125f}, {0, 32, 256, 64}});
  m.instances.push_back({"wall", 3, -1, {0.3f, 0.7f}, {0.5f, 0.0f}, {256, 0, 256, 256}});
  m.files.push_back({"irradiance", "irradiance.exr", "exr", "RGB irradiance, A coverage"});
  m.files.push_back({"preview", "preview.png", "png", ""});
  m.files.push_back({"samples", "samples.exr", "exr", "samples per texel"});
  m.settings = {{"samples", "1024"}, {"bounces", "4"}, {"seed", "7"}, {"filter", "box"}};
  m.features = "LUX_POINT_LIGHTS LUX_SORT";
  m.device = "pthread-cpu (PoCL 3.1)";
  m.import_warnings = {
      "extension KHR_materials_ior is used by the file and not supported",
      "material 'x' (material[0]): material extension KHR_materials_clearcoat is not supported"};
  m.stats.seconds = 12.5;
  m.stats.paths = (1ull << 60) + 3;
  m.stats.mean_spp = 1023.75;
  m.stats.min_spp = 1000;
  m.stats.error_estimate = std::nan("");
  m.stats.nonfinite_dropped = 17;
  m.stats.termination = "samples";
  m.stats.covered_texels = 99999;
  m.dilation_texels = 4;
  m.texels_per_unit = 12.375;
  m.denoise_json = R"({"iterations":5,"method":"atrous","sigma_luminance":2.0})";
  m.seam_stitch_json = R"({"irradiance_after":{"rms_abs":0.25},"stitched_edges":3})";
  return m;
}

TEST(Manifest, RoundTripKeepsEveryField) {
  TempDir dir("manifest");
  const std::string path = dir.file("manifest.json");
  const Manifest m = full_manifest();
  ASSERT_TRUE(write_manifest(path, m).is_ok());
  EXPECT_TRUE(dir.temporaries().empty());
  const nlohmann::json raw = nlohmann::json::parse(read_bytes(path));
  EXPECT_EQ(raw.at("format"), "luxel-lightmap-manifest");
  EXPECT_EQ(raw.at("version"), 1);
  EXPECT_TRUE(raw.at("stats").at("error_estimate").is_null()) << "NaN is written as null";

  auto r = read_manifest(path);
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  const Manifest& got = r.value();
  EXPECT_EQ(got.luxel_version, m.luxel_version);
  EXPECT_EQ(got.git_revision, m.git_revision);
  EXPECT_EQ(got.scene_name, m.scene_name);
  EXPECT_EQ(got.scene_sha256, m.scene_sha256);
  EXPECT_EQ(got.width, m.width);
  EXPECT_EQ(got.height, m.height);
  EXPECT_EQ(got.encoding, m.encoding);
  EXPECT_EQ(got.units, m.units);
  EXPECT_EQ(got.uv_set, m.uv_set);
  EXPECT_EQ(got.atlas_mode, m.atlas_mode);
  ASSERT_EQ(got.instances.size(), m.instances.size());
  for (size_t i = 0; i < m.instances.size(); ++i) {
    const auto &a = got.instances[i], &b = m.instances[i];
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.node, b.node);
    EXPECT_EQ(a.mesh, b.mesh);
    for (int k = 0; k < 2; ++k) {
      EXPECT_EQ(a.scale[k], b.scale[k]);
      EXPECT_EQ(a.offset[k], b.offset[k]);
    }
    for (int k = 0; k < 4; ++k) EXPECT_EQ(a.rect[k], b.rect[k]);
  }
  ASSERT_EQ(got.files.size(), m.files.size());
  for (size_t i = 0; i < m.files.size(); ++i) {
    EXPECT_EQ(got.files[i].role, m.files[i].role);
    EXPECT_EQ(got.files[i].path, m.files[i].path);
    EXPECT_EQ(got.files[i].format, m.files[i].format);
    EXPECT_EQ(got.files[i].description, m.files[i].description);
  }
  EXPECT_EQ(got.settings, m.settings);
  EXPECT_EQ(got.features, m.features);
  EXPECT_EQ(got.device, m.device);
  EXPECT_EQ(got.import_warnings, m.import_warnings);
  EXPECT_EQ(got.stats.seconds, m.stats.seconds);
  EXPECT_EQ(got.stats.paths, m.stats.paths);
  EXPECT_EQ(got.stats.mean_spp, m.stats.mean_spp);
  EXPECT_EQ(got.stats.min_spp, m.stats.min_spp);
  EXPECT_TRUE(std::isnan(got.stats.error_estimate));
  EXPECT_EQ(got.stats.nonfinite_dropped, m.stats.nonfinite_dropped);
  EXPECT_EQ(got.stats.termination, m.stats.termination);
  EXPECT_EQ(got.stats.covered_texels, m.stats.covered_texels);
  EXPECT_EQ(got.dilation_texels, m.dilation_texels);
  EXPECT_EQ(got.texels_per_unit, m.texels_per_unit);
  EXPECT_EQ(nlohmann::json::parse(got.denoise_json), nlohmann::json::parse(m.denoise_json));
  EXPECT_EQ(got.seam_stitch_json, m.seam_stitch_json);
}

TEST(Manifest, DefaultsCarryThisBuildsVersion) {
  const Manifest m;
  EXPECT_EQ(m.luxel_version, LUXEL_VERSION);
  EXPECT_EQ(m.git_revision, LUXEL_GIT_REVISION);
}

// Writes `edit` applied to a valid manifest and expects read_manifest to fail
// with INVALID_ARGUMENT naming `field`.
void expect_field_error(const std::function<void(nlohmann::json&)>& edit,
                        const std::string& field) {
  TempDir dir("manifest-bad");
  auto text = manifest_to_json(full_manifest());
  ASSERT_TRUE(text.is_ok()) << text.status().to_string();
  nlohmann::json j = nlohmann::json::parse(*text);
  edit(j);
  const std::string path = dir.file("manifest.json");
  write_bytes(path, j.dump(2));
  auto r = read_manifest(path);
  ASSERT_FALSE(r.is_ok()) << "accepted a manifest with a bad '" << field << "'";
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument) << r.status().to_string();
  EXPECT_NE(r.status().message().find("'" + field + "'"), std::string::npos)
      << r.status().message();
  EXPECT_NE(r.status().message().find(path), std::string::npos) << r.status().message();
}

TEST(Manifest, ReadErrorsNameTheField) {
  using J = nlohmann::json;
  expect_field_error([](J& j) { j.erase("width"); }, "width");
  expect_field_error([](J& j) { j["height"] = 0; }, "height");
  expect_field_error([](J& j) { j["width"] = "512"; }, "width");
  expect_field_error([](J& j) { j["format"] = "something-else"; }, "format");
  expect_field_error([](J& j) { j.erase("format"); }, "format");
  expect_field_error([](J& j) { j["version"] = 2; }, "version");
  expect_field_error([](J& j) { j["units"] = ""; }, "units");
  expect_field_error([](J& j) { j["atlas_mode"] = "tiled"; }, "atlas_mode");
  expect_field_error([](J& j) { j["instances"][1]["rect"] = {0, 0}; }, "instances[1].rect");
  expect_field_error(
      [](J& j) {
        j["instances"][0]["rect"] = {500, 0, 64, 8};
      },
      "instances[0].rect");
  expect_field_error([](J& j) { j["instances"][1]["node"] = 3.5; }, "instances[1].node");
  expect_field_error([](J& j) { j["instances"][0]["scale"] = {1, nullptr}; }, "instances[0].scale");
  expect_field_error([](J& j) { j["instances"][0].erase("name"); }, "instances[0].name");
  expect_field_error([](J& j) { j["files"][2]["role"] = ""; }, "files[2].role");
  expect_field_error([](J& j) { j["files"] = J::object(); }, "files");
  expect_field_error([](J& j) { j["settings"]["samples"] = 1024; }, "settings.samples");
  expect_field_error([](J& j) { j["stats"]["paths"] = -1; }, "stats.paths");
  expect_field_error([](J& j) { j["stats"].erase("termination"); }, "stats.termination");
  expect_field_error([](J& j) { j["dilation_texels"] = -2; }, "dilation_texels");
}

TEST(Manifest, UnknownMembersAreIgnored) {
  auto text = manifest_to_json(full_manifest());
  ASSERT_TRUE(text.is_ok());
  nlohmann::json j = nlohmann::json::parse(*text);
  j["future_member"] = {1, 2, 3};
  auto r = manifest_from_json(j.dump(), "test");
  EXPECT_TRUE(r.is_ok()) << r.status().to_string();
}

TEST(Manifest, MissingAndMalformedFiles) {
  TempDir dir("manifest-files");
  EXPECT_EQ(read_manifest(dir.file("none.json")).status().code(), StatusCode::kNotFound);
  write_bytes(dir.file("truncated.json"), "{\"format\": \"luxel-lightmap-manif");
  auto r = read_manifest(dir.file("truncated.json"));
  EXPECT_EQ(r.status().code(), StatusCode::kDataLoss) << r.status().to_string();
  write_bytes(dir.file("array.json"), "[1, 2]");
  EXPECT_EQ(read_manifest(dir.file("array.json")).status().code(), StatusCode::kInvalidArgument);
}

TEST(Manifest, InvalidManifestIsNotWritten) {
  TempDir dir("manifest-invalid");
  Manifest m = full_manifest();
  m.width = 0;
  const std::string path = dir.file("manifest.json");
  const Status st = write_manifest(path, m);
  EXPECT_EQ(st.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(st.message().find("'width'"), std::string::npos) << st.message();
  EXPECT_FALSE(std::filesystem::exists(path));
  m = full_manifest();
  m.instances[0].scale[0] = std::nanf("");
  EXPECT_NE(write_manifest(path, m).message().find("instances[0].scale"), std::string::npos);
  EXPECT_EQ(write_manifest(dir.file("missing/manifest.json"), full_manifest()).code(),
            StatusCode::kInvalidArgument);
  EXPECT_TRUE(dir.temporaries().empty());
}

}  // namespace
}  // namespace luxel::output
