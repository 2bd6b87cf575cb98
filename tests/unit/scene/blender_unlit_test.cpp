// KHR_materials_unlit as an independent tool writes it: Blender 5.0.1's glTF
// exporter (blender_unlit_export.py, run here through the bpy module named
// by LUXEL_BPY_PYTHON) exports a Background-shader material as unlit, with
// its own fallback inputs (metallic 0, roughness 0.9). The importer must
// read it as a Lambertian surface of the Background colour.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "scene/gltf_import.h"

namespace luxel::scene {
namespace {

TEST(BlenderUnlit, ExportedUnlitMaterialIsLambertianBaseColour) {
  const char* python = std::getenv("LUXEL_BPY_PYTHON");
  const char* script = std::getenv("LUXEL_BLENDER_UNLIT_SCRIPT");
  ASSERT_TRUE(python && script) << "run through ctest (LUXEL_BPY_PYTHON is set there)";
  const std::string out = ::testing::TempDir() + "/luxel_blender_unlit.glb";
  std::filesystem::remove(out);
  const std::string cmd = std::string("'") + python + "' '" + script + "' -- '" + out + "'";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  auto r = import_gltf_file(out);
  ASSERT_TRUE(r.is_ok()) << r.status().to_string();
  EXPECT_TRUE(r->import_stats.warnings.empty()) << r->import_stats.warnings[0];
  ASSERT_GE(r->materials.size(), 1u);
  const Material& m = r->materials[0];
  EXPECT_EQ(m.name, "unlit_floor");
  EXPECT_NEAR(m.base_color_factor.x, 0.8, 1e-6);
  EXPECT_NEAR(m.base_color_factor.y, 0.55, 1e-6);
  EXPECT_NEAR(m.base_color_factor.z, 0.3, 1e-6);
  EXPECT_EQ(m.metallic_factor, 0.0f);
  EXPECT_EQ(m.dielectric_specular_f0().y, 0.0f) << "no specular layer";
  EXPECT_EQ(m.dielectric_specular_f90(), 0.0f);
  EXPECT_FALSE(m.is_emissive());
  ASSERT_EQ(r->instances.size(), 1u);
  EXPECT_EQ(r->meshes[0].triangle_count(), 2u);
}

}  // namespace
}  // namespace luxel::scene
