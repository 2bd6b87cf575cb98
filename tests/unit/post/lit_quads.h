// Closed-form scenes of the lightmap denoiser tests (denoise_test,
// oidn_test): plane quads lit by rectangular Lambertian emitters, whose
// irradiance has a closed form (Lambert's polygon formula), and the error of
// a baked map against it.
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

#include "atlas/sample_info.h"
#include "kernels/shared/sample_info.h"
#include "support/test_scenes.h"

namespace luxel::testing {

// Irradiance at x (normal n) from a Lambertian polygon of radiance le
// (Lambert 1760; Arvo 1995, Eq. 6): E = le/2 |sum_i theta_i n.unit(r_i x r_i+1)|.
inline double polygon_irradiance(const Vec3 (&poly)[4], Vec3 x, Vec3 n, double le) {
  double sum = 0;
  for (int i = 0; i < 4; ++i) {
    const Vec3 a = normalize(poly[i] - x), b = normalize(poly[(i + 1) % 4] - x);
    const double theta = std::acos(std::clamp(double(dot(a, b)), -1.0, 1.0));
    sum += theta * double(dot(n, normalize(cross(a, b))));
  }
  return 0.5 * le * std::fabs(sum);
}

// A plane quad at y = 0 (world x in [x0, x0 + 2], z in [-1, 1]) on atlas
// [u0, u1] x [v0, v1], and a size x size emitter `height` above its centre
// facing down, on atlas [eu0, eu0 + 0.1] x [0.9, 1].
struct LitQuad {
  float x0, u0, u1, v0, v1, eu0;
  float le, size, height;
  Vec3 emitter[4];
};

inline void add_lit_quad(scene::Scene& s, LitQuad& q, int plane_material, int emitter_material) {
  testing::add_quad(s, {q.x0, 0, -1}, {0, 0, 2}, {2, 0, 0}, q.u0, q.v0, q.u1, q.v1, plane_material);
  const Vec3 o{q.x0 + 1 - 0.5f * q.size, q.height, -0.5f * q.size};
  // Front = cross(eu, ev) = -y: the emitter faces the plane.
  const Vec3 eu{q.size, 0, 0}, ev{0, 0, q.size};
  testing::add_quad(s, o, eu, ev, q.eu0, 0.9f, q.eu0 + 0.1f, 1.0f, emitter_material);
  q.emitter[0] = o;
  q.emitter[1] = o + eu;
  q.emitter[2] = o + eu + ev;
  q.emitter[3] = o + ev;
}

// Two emitter-lit plane quads side by side in the atlas, 200 units apart in
// the world (neither emitter lights the other quad measurably); the
// second's emitter is `contrast` times brighter. Emitters of side `size`,
// `height` above their quad.
struct TwoCharts {
  scene::Scene scene;
  LitQuad q[2];
};

inline TwoCharts two_charts(float contrast, float size, float height) {
  TwoCharts t;
  t.scene.source_name = "two_charts";
  t.scene.materials.push_back(testing::diffuse_material(0.5f));
  t.scene.materials.push_back(testing::diffuse_material(0.0f, 2.0f));
  t.scene.materials.push_back(testing::diffuse_material(0.0f, 2.0f * contrast));
  t.q[0] = {-1, 0, 0.5f, 0, 0.75f, 0.1f, 2.0f, size, height, {}};
  t.q[1] = {199, 0.5f, 1, 0, 0.75f, 0.6f, 2.0f * contrast, size, height, {}};
  add_lit_quad(t.scene, t.q[0], 0, 1);
  add_lit_quad(t.scene, t.q[1], 0, 2);
  return t;
}

// The closed form, averaged over the texel's valid sample positions (what
// the bake estimates); NaN for texels off the planes or on both.
struct Expected {
  std::vector<double> e;  // per texel
  std::vector<int> quad;  // 0 / 1, -1 elsewhere
};

inline Expected expected_irradiance(const TwoCharts& t, const atlas::Atlas& atlas,
                                    const atlas::SampleInfo& info, int quads) {
  Expected out;
  const size_t n = size_t(info.width) * size_t(info.height);
  out.e.assign(n, std::nan(""));
  out.quad.assign(n, -1);
  for (uint32_t texel : info.covered_texels) {
    const uint32_t valid = cl::lux_sample_info_count(info.words.data(), info.offsets[texel]);
    double sum = 0;
    int quad = -1;
    for (uint32_t r = 0; r < valid; ++r) {
      const atlas::SamplePoint sp = atlas::sample_point(info, texel, r);
      // Instances: plane 0, emitter 0, plane 1, emitter 1. Texels whose
      // samples lie on two planes (the corner sample of a border texel) are
      // left out: no single closed form describes them.
      if (sp.instance % 2 != 0 || int(sp.instance / 2) >= quads ||
          (r > 0 && int(sp.instance / 2) != quad)) {
        quad = -1;
        break;
      }
      quad = int(sp.instance / 2);
      const LitQuad& q = t.q[quad];
      const double u = sp.x / atlas.width, v = sp.y / atlas.height;
      // add_quad: u along eu = +z, v along ev = +x.
      const Vec3 x{float(q.x0 + 2 * (v - q.v0) / (q.v1 - q.v0)), 0,
                   float(-1 + 2 * (u - q.u0) / (q.u1 - q.u0))};
      sum += polygon_irradiance(q.emitter, x, {0, 1, 0}, q.le);
    }
    if (quad < 0) continue;
    out.e[texel] = sum / valid;
    out.quad[texel] = quad;
  }
  return out;
}

struct Errors {
  double rmse = 0, mean_ratio = 0;
  size_t texels = 0;
};

// RMSE of the green channel over the texels `take` accepts, and the ratio of
// the mean estimate to the mean closed form there.
inline Errors errors(const std::vector<float>& rgba, const Expected& ex,
                     const std::function<bool(uint32_t)>& take) {
  Errors e;
  double sq = 0, sum = 0, sum_ref = 0;
  for (uint32_t t = 0; t < ex.e.size(); ++t) {
    if (std::isnan(ex.e[t]) || !take(t)) continue;
    const double d = rgba[size_t(t) * 4 + 1] - ex.e[t];
    sq += d * d;
    sum += rgba[size_t(t) * 4 + 1];
    sum_ref += ex.e[t];
    ++e.texels;
  }
  e.rmse = std::sqrt(sq / std::max<size_t>(e.texels, 1));
  e.mean_ratio = sum / sum_ref;
  return e;
}

}  // namespace luxel::testing
