// Mirrored instances (glTF 2.0 §3.7.4: a node transform with a negative
// determinant reverses the winding of the front face) bake exactly like
// their unmirrored counterparts mirrored. Mirroring a whole scene is a
// symmetry of light transport, so a scene and its mirror image must give the
// same irradiance at corresponding surface points. Both bakes use the same
// TEXCOORD_1, so lightmap texel (x, y) is the same surface point in both and
// the comparison does not depend on the layout: every covered texel's
// luminance is z-tested with the standard errors both bakes report
// (independent seeds, Šidák-corrected over texels), and the sum of the
// differences over all texels is z-tested as a whole (a bias of a few
// percent anywhere shows there). Each comparison must also FAIL when one
// side is scaled by 2 %, so it cannot pass trivially.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>

#include "bake/bake.h"
#include "common/half.h"
#include "device/context.h"
#include "scene/gltf_import.h"
#include "support/device_context.h"
#include "support/test_scenes.h"

namespace luxel {
namespace {

struct Agreement {
  size_t texels = 0;
  double max_z = 0, bound = 0;  // per-texel |z| and the Šidák bound
  double pooled_z = 0;          // z of the summed differences
  double ratio = 0;             // sum of b over sum of a
  bool ok() const { return max_z <= bound && std::fabs(pooled_z) <= 4.0; }
};

double luminance(const pipeline::BakeResult& r, size_t t) {
  return 0.2126 * r.irradiance[t * 4] + 0.7152 * r.irradiance[t * 4 + 1] +
         0.0722 * r.irradiance[t * 4 + 2];
}

// Two-sample z-test of the luminance of every texel covered in both bakes
// (both must cover the same texels: the layout is the same). `scale_b`
// multiplies b (the injected error of the power check).
Agreement compare(const pipeline::BakeResult& a, const pipeline::BakeResult& b,
                  double scale_b = 1.0, double family_alpha = 1e-3) {
  Agreement v;
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  if (a.width != b.width || a.height != b.height) return v;
  std::vector<double> zs;
  double diff = 0, var = 0, sum_a = 0, sum_b = 0;
  for (size_t t = 0; t < size_t(a.width) * a.height; ++t) {
    EXPECT_EQ(a.irradiance[t * 4 + 3], b.irradiance[t * 4 + 3]) << "coverage of texel " << t;
    if (!(a.irradiance[t * 4 + 3] > 0) || a.samples[t] < 16 || b.samples[t] < 16) continue;
    const double la = luminance(a, t), lb = scale_b * luminance(b, t);
    // The reported relative standard error of the luminance mean; a floor of
    // 1e-5 relative covers fp32 accumulation where the variance is ~0.
    const double sa = a.rel_error[t] * la, sb = b.rel_error[t] * lb;
    const double floor = 1e-5 * std::max(la, lb);
    const double se2 = sa * sa + sb * sb + floor * floor;
    zs.push_back(se2 > 0 ? (lb - la) / std::sqrt(se2) : (la == lb ? 0 : INFINITY));
    diff += lb - la;
    var += se2;
    sum_a += la;
    sum_b += lb;
  }
  v.texels = zs.size();
  const double per_test = 1.0 - std::pow(1.0 - family_alpha, 1.0 / std::max<size_t>(zs.size(), 1));
  double lo = 0, hi = 40;  // inverse two-sided normal tail by bisection on erfc
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (std::erfc(mid / std::sqrt(2.0)) > per_test ? lo : hi) = mid;
  }
  v.bound = hi;
  for (double z : zs) v.max_z = std::max(v.max_z, std::fabs(z));
  v.pooled_z = var > 0 ? diff / std::sqrt(var) : 0;
  v.ratio = sum_a > 0 ? sum_b / sum_a : 0;
  std::printf("  %zu texels, max |z| %.2f (bound %.2f), mirrored / original %.5f, pooled z %.2f\n",
              v.texels, v.max_z, v.bound, v.ratio, v.pooled_z);
  return v;
}

// x -> -x.
constexpr Vec3 mirror_x(Vec3 p) {
  return {-p.x, p.y, p.z};
}
Mat4 mirror_x_matrix() {
  Mat4 m;
  m.at(0, 0) = -1;
  return m;
}

// The mesh's mirror image x -> -x as plain data: positions and normals
// mirrored, each triangle's vertices 1 and 2 swapped so that the winding
// still gives the front face, UVs per vertex unchanged. Under an identity
// transform it is the geometry a mirroring instance of `m` describes.
scene::Mesh mirrored_data(scene::Mesh m) {
  for (Vec3& p : m.positions) p = mirror_x(p);
  for (Vec3& n : m.normals) n = mirror_x(n);
  for (Vec4& t : m.tangents) t = {-t.x, t.y, t.z, -t.w};
  for (size_t t = 0; t + 2 < m.indices.size(); t += 3)
    std::swap(m.indices[t + 1], m.indices[t + 2]);
  return m;
}

// An open room lit only by a one-sided emitter (front face down) under a
// ceiling that its back side faces: floor, back wall, a red left wall, a
// ceiling, a tilted normal-mapped blocker and the emitter, each a quad with
// its own cell of the lightmap. Nothing in it is symmetric under x -> -x.
enum Quad { kFloor, kBackWall, kLeftWall, kCeiling, kBlocker, kEmitter, kQuads };

scene::Scene open_room() {
  scene::Scene s;
  s.source_name = "open_room";
  s.materials.push_back(testing::diffuse_material(0.7f));
  scene::Material red = testing::diffuse_material(0.6f);
  red.base_color_factor = {0.7f, 0.15f, 0.1f, 1};
  s.materials.push_back(red);
  s.materials.push_back(testing::diffuse_material(0.5f, 6.0f));  // one-sided emitter
  // The blocker's normal map tilts its normal along both tangent axes, so a
  // wrong bitangent sign under mirroring shows.
  scene::Texture tex;
  tex.name = "tilt";
  tex.width = tex.height = 1;
  tex.format = scene::TexelFormat::kRGBA16F;
  for (float v : {0.75f, 0.35f, 0.85f, 1.0f}) tex.rgba16f.push_back(float_to_half(v));
  s.textures.push_back(tex);
  scene::Material mapped = testing::diffuse_material(0.7f);
  mapped.normal_texture.texture = 0;
  s.materials.push_back(mapped);
  const float m = 0.02f, c = 1.0f / 3.0f;
  auto cell = [&](Vec3 o, Vec3 eu, Vec3 ev, int index, int material) {
    const float u0 = float(index % 3) * c, v0 = float(index / 3) * c;
    testing::add_quad(s, o, eu, ev, u0 + m, v0 + m, u0 + c - m, v0 + c - m, material);
  };
  cell({-1, 0, -1}, {0, 0, 2}, {2, 0, 0}, kFloor, 0);                        // faces +y
  cell({-1, 0, -1}, {2, 0, 0}, {0, 2, 0}, kBackWall, 0);                     // faces +z
  cell({-1, 0, -1}, {0, 2, 0}, {0, 0, 2}, kLeftWall, 1);                     // faces +x
  cell({-1, 2, -1}, {2, 0, 0}, {0, 0, 2}, kCeiling, 0);                      // faces -y
  cell({0.1f, 0.3f, -0.5f}, {0, 0.1f, 0.6f}, {0.5f, 0.2f, 0}, kBlocker, 3);  // faces up, tilted
  cell({-0.7f, 1.6f, -0.5f}, {0.6f, 0, 0}, {0, 0, 0.6f}, kEmitter, 2);       // faces -y
  return s;
}

class MirrorSymmetryTest : public testing::DeviceTest<> {
 protected:
  static pipeline::BakeSettings settings(uint32_t seed) {
    pipeline::BakeSettings s;
    s.atlas.resolution = 32;
    s.samples_per_texel = 256;
    s.max_bounces = 3;
    s.paths_per_iteration = 1u << 16;
    s.seed = seed;
    s.progress_interval_s = 1e9;
    return s;
  }

  pipeline::BakeResult bake(const scene::Scene& s, uint32_t seed) {
    auto r = pipeline::bake(s, settings(seed), *ctx_);
    EXPECT_TRUE(r) << r.status().to_string();
    if (!r) return {};
    EXPECT_EQ(r.value().atlas.mode, atlas::AtlasMode::kShared)
        << "the layout must be the file's TEXCOORD_1";
    return std::move(r.value());
  }
};

// The user's report: the Cornell box with its root node given scale
// (-1, 1, 1) came out darker and differently lit than the original.
TEST_F(MirrorSymmetryTest, CornellBoxMirroredThroughItsRootNode) {
  const std::string dir = LUXEL_SCENES_DIR;
  std::ifstream in(dir + "/cornell_box.gltf");
  ASSERT_TRUE(in) << "cannot read cornell_box.gltf";
  std::stringstream text;
  text << in.rdbuf();
  nlohmann::json doc = nlohmann::json::parse(text.str());
  const int root = doc["scenes"][0]["nodes"][0];
  ASSERT_TRUE(doc["nodes"][root].contains("mesh"));
  ASSERT_FALSE(doc["nodes"][root].contains("matrix") || doc["nodes"][root].contains("scale"));
  auto original = scene::import_gltf_memory(text.str(), dir, "cornell_box.gltf");
  ASSERT_TRUE(original) << original.status().to_string();
  doc["nodes"][root]["scale"] = {-1.0, 1.0, 1.0};
  auto mirrored = scene::import_gltf_memory(doc.dump(), dir, "cornell_box_mirrored.gltf");
  ASSERT_TRUE(mirrored) << mirrored.status().to_string();
  ASSERT_EQ(mirrored.value().instances.size(), 1u);
  ASSERT_LT(determinant3x3(mirrored.value().instances[0].object_to_world), 0);

  const pipeline::BakeResult a = bake(original.value(), 7);
  const pipeline::BakeResult b = bake(mirrored.value(), 8);
  ASSERT_GT(a.covered_texels, 400u);
  EXPECT_TRUE(compare(a, b).ok());
  EXPECT_FALSE(compare(a, b, 1.02).ok()) << "a 2 % difference must be detected";
}

// A single mirrored instance among unmirrored ones. The whole open room is
// mirrored x -> -x; all of its quads but one are given as mirrored plain data
// under the identity, and that one keeps the original mesh under a mirroring
// instance transform: the blocker (a mirrored receiver), then the one-sided
// emitter (a mirrored light, which next-event estimation and BSDF-sampled
// hits must both see from its front only).
TEST_F(MirrorSymmetryTest, SingleMirroredInstanceAmongUnmirroredOnes) {
  const scene::Scene room = open_room();
  const pipeline::BakeResult a = bake(room, 7);
  ASSERT_GT(a.covered_texels, 500u);
  ASSERT_NE(a.features.find("emissive"), std::string::npos) << a.features;
  for (int mirrored_quad : {int(kBlocker), int(kEmitter)}) {
    SCOPED_TRACE(mirrored_quad == kBlocker ? "mirrored blocker" : "mirrored emitter");
    scene::Scene image = room;
    int negative = 0;
    for (scene::Instance& inst : image.instances) {
      if (inst.mesh == mirrored_quad) {
        inst.object_to_world = mirror_x_matrix();
      } else {
        image.meshes[static_cast<size_t>(inst.mesh)] =
            mirrored_data(image.meshes[static_cast<size_t>(inst.mesh)]);
      }
      if (determinant3x3(inst.object_to_world) < 0) ++negative;
    }
    ASSERT_EQ(negative, 1);
    const pipeline::BakeResult b = bake(image, 8);
    EXPECT_TRUE(compare(a, b).ok());
    EXPECT_FALSE(compare(a, b, 1.02).ok()) << "a 2 % difference must be detected";
  }
}

}  // namespace
}  // namespace luxel
