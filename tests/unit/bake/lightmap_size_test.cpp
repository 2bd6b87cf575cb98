// Lightmap sizes chosen for the user: without a size, the default texel
// density (atlas.h, kDefaultTexelDensity) and pages of at most
// max_resolution; under a fixed size, a layout that fits (several pages)
// instead of a refusal; and refusals that name the scene file and an option
// that exists. Whole glTF files through the importer, the layout and the
// job (job/bake_job.h), as the CLI and the daemon run them.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "../scene/gltf_builder.h"
#include "bake/lightmap_layout.h"
#include "job/bake_job.h"
#include "scene/gltf_import.h"
#include "settings/settings_schema.h"
#include "support/device_context.h"

namespace luxel {
namespace {

using nlohmann::json;
using test::GltfBuilder;

// An axis-aligned box of side `size` world units (metres): 12 triangles on 24
// vertices (hard edges), no TEXCOORD_1, so its lightmap UVs are generated.
json box(GltfBuilder& b, float size) {
  std::vector<float> pos;
  std::vector<uint32_t> idx;
  const float corners[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const auto base = static_cast<uint32_t>(pos.size() / 3);
      for (const auto& c : corners) {
        float p[3];
        p[axis] = static_cast<float>(side) * size;
        p[(axis + 1) % 3] = c[0] * size;
        p[(axis + 2) % 3] = c[1] * size;
        pos.insert(pos.end(), p, p + 3);
      }
      if (side == 1)
        idx.insert(idx.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
      else
        idx.insert(idx.end(), {base, base + 2, base + 1, base, base + 3, base + 2});
    }
  json prim = b.triangles(pos, idx, test::kUInt, false);
  prim["material"] = 0;
  return prim;
}

// `count` separate boxes of side `size`, 2 * size apart, written as NAME.
std::string boxes_file(test::TempDir& dir, const std::string& name, int count, float size) {
  GltfBuilder b;
  b.add_material({{"name", "white"}, {"pbrMetallicRoughness", {{"metallicFactor", 0.0}}}});
  for (int i = 0; i < count; ++i)
    b.add_node({{"name", "box" + std::to_string(i)},
                {"mesh", b.add_mesh("box" + std::to_string(i), {box(b, size)})},
                {"translation", {2.0 * size * i, 0, 0}}});
  return dir.write(name, b.glb());
}

scene::Scene import(const std::string& path) {
  auto s = scene::import_gltf_file(path);
  EXPECT_TRUE(s) << s.status().to_string();
  return s ? std::move(s.value()) : scene::Scene{};
}

atlas::Atlas layout_of(const scene::Scene& scene, const pipeline::BakeSettings& s) {
  auto l = pipeline::lay_out_lightmap(scene, s);
  EXPECT_TRUE(l) << l.status().to_string();
  return l ? l->atlas : atlas::Atlas{};
}

bool contains(const std::string& text, const std::string& needle) {
  return text.find(needle) != std::string::npos;
}

// Every "--option" a message names is a flag of the settings schema.
void expect_existing_options(const std::string& message) {
  const std::regex flag("--[a-z][a-z-]*");
  int named = 0;
  for (auto it = std::sregex_iterator(message.begin(), message.end(), flag);
       it != std::sregex_iterator(); ++it, ++named) {
    bool found = false;
    for (const pipeline::Setting& st : pipeline::settings_schema())
      found |= st.flag && it->str() == st.flag;
    EXPECT_TRUE(found) << it->str() << " is not an option, in: " << message;
  }
  EXPECT_GT(named, 0) << "no option named in: " << message;
}

// Without --resolution or --texel-density: 40 texels per unit, so a 10 m
// box's lightmap has about 10 times the side of a 1 m box's (a little less:
// the padding between charts does not scale); past --max-resolution (1024
// by default) the same density goes on several pages.
TEST(LightmapSize, DefaultSizeScalesWithTheScene) {
  const pipeline::BakeSettings d = pipeline::default_settings();
  EXPECT_EQ(d.atlas.resolution, 0);
  EXPECT_EQ(d.atlas.texel_density, atlas::kDefaultTexelDensity);
  EXPECT_EQ(d.atlas.max_resolution, atlas::kDefaultMaxResolution);
  test::TempDir dir;
  const scene::Scene small = import(boxes_file(dir, "small.glb", 1, 1));
  const scene::Scene large = import(boxes_file(dir, "large.glb", 1, 10));
  const atlas::Atlas one = layout_of(small, d);
  EXPECT_EQ(one.pages, 1);
  EXPECT_NEAR(one.texels_per_unit, 40, 1e-3);
  // Six faces of 40 x 40 texels and their padding.
  EXPECT_GE(one.width, 98);
  EXPECT_LE(one.width, 200);
  EXPECT_TRUE(one.warnings.empty());

  pipeline::BakeSettings wide = d;
  wide.atlas.max_resolution = 4096;
  const atlas::Atlas ten = layout_of(large, wide);
  EXPECT_EQ(ten.pages, 1);
  EXPECT_NEAR(ten.texels_per_unit, 40, 1e-3);
  const double ratio = double(ten.width) / one.width;
  EXPECT_GT(ratio, 8.5);
  EXPECT_LT(ratio, 10.5);

  // At the default page the one 10 m box (six 400 x 400 faces) cannot stay
  // on one page at 40: a page holds whole instances, so the density is
  // lowered, and said.
  const atlas::Atlas held = layout_of(large, d);
  EXPECT_EQ(held.width, 1024);
  EXPECT_EQ(held.pages, 1);
  EXPECT_LT(held.texels_per_unit, 40);
  ASSERT_EQ(held.warnings.size(), 1u);
  EXPECT_TRUE(contains(held.warnings[0], "texel density lowered from 40")) << held.warnings[0];
  expect_existing_options(held.warnings[0]);

  // Eight 5 m boxes (200 x 200 texels a face) need about 2 M texels: pages
  // of 1024 x 1024 at the density asked, no warning.
  const scene::Scene many = import(boxes_file(dir, "many.glb", 8, 5));
  const atlas::Atlas paged = layout_of(many, d);
  EXPECT_GT(paged.pages, 1);
  EXPECT_EQ(paged.width, 1024);
  EXPECT_EQ(paged.page_height(), 1024);
  EXPECT_NEAR(paged.texels_per_unit, 40, 1e-3);
  EXPECT_TRUE(paged.warnings.empty());
}

class LightmapSizeBake : public testing::DeviceTest<> {
 protected:
  static pipeline::BakeSettings settings() {
    pipeline::BakeSettings s = pipeline::default_settings();
    s.samples_per_texel = 4;
    s.max_bounces = 1;
    s.paths_per_iteration = 1u << 14;
    s.progress_interval_s = 1e9;
    s.lights.sky.kind = pipeline::SkySettings::Kind::kConstant;
    return s;
  }

  // Runs the job as the CLI does; `layout` gets the layout line.
  static Result<job::JobResult> run(const std::string& file, const scene::Scene& scene,
                                    const pipeline::BakeSettings& s, const std::string& out,
                                    std::string* layout = nullptr) {
    job::JobInput in{.scene = &scene, .settings = s, .scene_file = file};
    job::JobEvents ev;
    ev.hooks.on_layout = [layout](const std::string& line) {
      if (layout) *layout = line;
    };
    return job::run_bake_job(in, *ctx_, ev, out);
  }
};

std::string read_all(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// 40 boxes make 240 charts; each keeps at least one texel and 2 of padding,
// more than a 16 x 16 lightmap holds at any density. Refused before; now on
// several 16 x 16 pages, with a warning in the layout line and the
// manifest, and a lightmap whose covered texels are all finite and >= 0.
TEST_F(LightmapSizeBake, FixedSizeTooSmallForTheChartsBakesOnPages) {
  test::TempDir dir;
  const std::string file = boxes_file(dir, "crowd.glb", 40, 0.5f);
  const scene::Scene scene = import(file);
  pipeline::BakeSettings s = settings();
  s.atlas.resolution = 16;
  s.atlas.texel_density = 0;
  ASSERT_TRUE(pipeline::validate_settings(s).is_ok());
  std::string line;
  auto job = run(file, scene, s, dir.path() + "/out", &line);
  ASSERT_TRUE(job) << job.status().to_string();
  const pipeline::BakeResult& r = *job->lightmap;
  EXPECT_GT(r.atlas.pages, 1);
  EXPECT_EQ(r.atlas.width, 16);
  EXPECT_EQ(r.atlas.page_height(), 16);
  const std::string pages = std::to_string(r.atlas.pages) + " pages of 16x16";
  EXPECT_TRUE(contains(line, "; warning: the charts do not fit one 16x16 lightmap")) << line;
  EXPECT_TRUE(contains(line, pages)) << line;
  expect_existing_options(line);

  const json manifest = json::parse(read_all(job->written.manifest_json));
  bool warned = false;
  for (const auto& w : manifest["import_warnings"])
    warned |= contains(w.get<std::string>(), "lightmap layout: the charts do not fit") &&
              contains(w.get<std::string>(), pages);
  EXPECT_TRUE(warned) << manifest["import_warnings"].dump();
  EXPECT_EQ(manifest["pages"], r.atlas.pages);
  EXPECT_GT(manifest["texels_per_unit"].get<double>(), 0);

  size_t covered = 0;
  for (size_t t = 0; t < r.irradiance.size() / 4; ++t) {
    if (!(r.irradiance[4 * t + 3] > 0)) continue;
    ++covered;
    for (int c = 0; c < 3; ++c) {
      const float v = r.irradiance[4 * t + c];
      ASSERT_TRUE(std::isfinite(v) && v >= 0) << "texel " << t << " channel " << c << ": " << v;
    }
  }
  EXPECT_GE(covered, 240u);  // a texel a chart at least
}

// A file of points (or lines) has nothing to lightmap: the refusal names the
// file and says only triangles are baked.
TEST_F(LightmapSizeBake, PointsOnlyRefusalNamesTheFile) {
  test::TempDir dir;
  GltfBuilder b;
  json points = b.triangles({0, 0, 0, 1, 0, 0, 0, 1, 0}, {}, test::kUInt, false);
  points["mode"] = 0;
  b.add_node({{"name", "cloud"}, {"mesh", b.add_mesh("cloud", {points})}});
  const std::string file = dir.write("points.glb", b.glb());
  const scene::Scene scene = import(file);
  auto job = run(file, scene, settings(), dir.path() + "/out");
  ASSERT_FALSE(job);
  EXPECT_EQ(job.status().code(), StatusCode::kInvalidArgument);
  EXPECT_TRUE(contains(job.status().message(), "scene 'points.glb': ")) << job.status().message();
  EXPECT_TRUE(contains(job.status().message(), "only triangles are lightmapped"))
      << job.status().message();
}

// The file's TEXCOORD_1 on 40 instances of one mesh, packed (one rectangle
// per instance) at --uv existing into 16 x 16: no density fits; the
// refusal names the file and options that exist.
TEST_F(LightmapSizeBake, PackedRefusalNamesTheFileAndAnOption) {
  test::TempDir dir;
  GltfBuilder b;
  b.add_material({{"name", "white"}});
  json quad = b.triangles({0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 0, 0, 1, 1, 0, 0, 1, 0});
  quad["material"] = 0;
  const int mesh = b.add_mesh("quad", {quad});
  for (int i = 0; i < 40; ++i)
    b.add_node(
        {{"name", "q" + std::to_string(i)}, {"mesh", mesh}, {"translation", {2.0 * i, 0, 0}}});
  const std::string file = dir.write("tiles.gltf", b.gltf_embedded());
  const scene::Scene scene = import(file);
  pipeline::BakeSettings s = settings();
  s.atlas.resolution = 16;
  s.uv = pipeline::UvMode::kExisting;
  auto job = run(file, scene, s, dir.path() + "/out");
  ASSERT_FALSE(job);
  EXPECT_EQ(job.status().code(), StatusCode::kResourceExhausted);
  EXPECT_TRUE(contains(job.status().message(), "scene 'tiles.gltf': ")) << job.status().message();
  EXPECT_FALSE(contains(job.status().message(), "padding_texels"));
  expect_existing_options(job.status().message());
}

}  // namespace
}  // namespace luxel
