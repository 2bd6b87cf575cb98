#include "reference/cpu_lightmap_tracer.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <thread>

#include "atlas/sample_info.h"
#include "common/clock.h"
#include "reference/pcg32.h"
#include "reference/reference_bsdf.h"
#include "reference/reference_scene.h"

namespace luxel::reference {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Orthonormal basis around unit n (Duff et al., "Building an Orthonormal
// Basis, Revisited", JCGT 2017).
void basis(Vec3 n, Vec3* t, Vec3* b) {
  const float sign = std::copysign(1.0f, n.z);
  const float a = -1.0f / (sign + n.z);
  const float c = n.x * n.y * a;
  *t = {1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x};
  *b = {c, sign + n.y * n.y * a, -n.y};
}

// Cosine-weighted direction about n (pdf cos / pi): uniform on the disc by
// polar coordinates, projected up to the hemisphere (Malley's method).
Vec3 cosine_direction(Vec3 n, Pcg32& rng) {
  const double u1 = rng.uniform(), u2 = rng.uniform();
  const double r = std::sqrt(u1), phi = 2.0 * kPi * u2;
  const double z = std::sqrt(std::max(0.0, 1.0 - u1));
  Vec3 t, b;
  basis(n, &t, &b);
  return normalize(t * static_cast<float>(r * std::cos(phi)) +
                   b * static_cast<float>(r * std::sin(phi)) + n * static_cast<float>(z));
}

struct Job {
  const scene::Scene& scene;
  const atlas::Atlas& atlas;
  const atlas::SampleInfo& info;
  const ReferenceScene& rs;
  const ReferenceSettings& settings;
};

// Emitted radiance arriving at x from one area-sampled emitter point, times
// cos(n_s, wi), divided by the solid-angle pdf: an unbiased estimate of
// integral L_e(first hit along wi) cos(n_s, wi) dwi over directions above
// both the shading and the geometric surface. *wi_out: the sampled direction
// (set when the result is not black).
Rgb direct_light(const ReferenceScene& rs, const SurfacePoint& x, Pcg32& rng, Vec3* wi_out) {
  if (!rs.has_emitters()) return {};
  const double u_select = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
  const EmitterSample e = rs.sample_emitter(u_select, u1, u2);
  const double dx = double{e.p.x} - x.p.x, dy = double{e.p.y} - x.p.y, dz = double{e.p.z} - x.p.z;
  const double dist2 = dx * dx + dy * dy + dz * dz;
  if (!(dist2 > 0)) return {};
  const double dist = std::sqrt(dist2);
  const Vec3 wi{static_cast<float>(dx / dist), static_cast<float>(dy / dist),
                static_cast<float>(dz / dist)};
  if (dot(wi, x.ng) <= 0) return {};
  const double cos_x = dot(wi, x.ns);
  if (cos_x <= 0) return {};
  const ReferenceMaterial& m = rs.material(e.material);
  double cos_l = -dot(wi, e.ng_front);
  if (cos_l <= 0) {
    if (!m.double_sided) return {};
    cos_l = -cos_l;
  }
  // Shadow ray from the offset origin straight to the light point, stopping
  // just short of it (the light's own triangle must not count).
  const Vec3 org = rs.offset_origin(x, wi);
  if (rs.occluded(org, e.p - org, 1.0f - 1e-4f)) return {};
  *wi_out = wi;
  return m.emission * (cos_x * cos_l / (dist2 * e.pdf_area));
}

// The local shading frame of a vertex (z = shading normal), in double.
struct Frame {
  Vec3 t, b, n;
  explicit Frame(Vec3 ns) : n(ns) { basis(ns, &t, &b); }
  Dir3 to_local(Vec3 w) const {
    auto d = [](Vec3 a, Vec3 c) {
      return double{a.x} * c.x + double{a.y} * c.y + double{a.z} * c.z;
    };
    return {d(w, t), d(w, b), d(w, n)};
  }
  Vec3 to_world(const Dir3& w) const {
    return normalize(t * static_cast<float>(w.x) + b * static_cast<float>(w.y) +
                     n * static_cast<float>(w.z));
  }
};

// One path from texel point x0: E(x0) estimate (see the header).
Rgb trace_path(const Job& job, SurfacePoint x, Pcg32& rng) {
  const ReferenceScene& rs = job.rs;
  const int max_bounces = job.settings.max_bounces;
  Rgb irradiance;
  Rgb throughput = Rgb::gray(1.0);
  Vec3 wo{0, 0, 0};  // towards the previous vertex (vertices k >= 1)
  for (int k = 0;; ++k) {
    const ReferenceMaterial& mat = rs.material(x.material);
    Vec3 wi;
    if (k > 0 && mat.ggx) {
      // The glTF BRDF: NEE with f(wo, wi), then an extension ray from the
      // BRDF's own sampling mixture, weighted by f cos / pdf.
      const GgxBrdf brdf = mat.brdf(job.settings.brdf);
      const Frame frame(x.ns);
      const Dir3 wo_local = frame.to_local(wo);
      Vec3 wl;
      const Rgb light = direct_light(rs, x, rng, &wl);
      if (!light.is_black())
        irradiance += throughput * brdf.eval(wo_local, frame.to_local(wl)) * light;
      if (k == max_bounces) break;
      const double u_choice = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
      const Dir3 sampled = brdf.sample(wo_local, u_choice, u1, u2);
      if (sampled.z <= 0) break;  // below the shading surface: contributes 0
      wi = frame.to_world(sampled);
      if (dot(wi, x.ng) <= 0) break;  // under the geometric surface: contributes 0
      const Dir3 wi_local = frame.to_local(wi);
      const double pdf = brdf.pdf(wo_local, wi_local);
      if (!(pdf > 0)) break;
      throughput = throughput * brdf.eval(wo_local, wi_local) * (wi_local.z / pdf);
    } else {
      // Vertex 0 is the sensor (E = integral L cos: "f" = 1); later vertices
      // reflect with the Lambert BRDF albedo / pi.
      const Rgb f = k == 0 ? Rgb::gray(1.0) : mat.albedo * (1.0 / kPi);
      Vec3 wl;
      irradiance += throughput * f * direct_light(rs, x, rng, &wl);
      if (k == max_bounces) break;
      wi = cosine_direction(x.ns, rng);
      if (dot(wi, x.ng) <= 0) break;  // under the geometric surface: contributes 0
      // Weight of a cosine-sampled direction: sensor pi (= cos / pdf); Lambert
      // albedo (= f cos / pdf with f = albedo / pi).
      throughput = k == 0 ? throughput * kPi : throughput * mat.albedo;
    }
    SurfacePoint hit;
    if (!rs.intersect(rs.offset_origin(x, wi), wi, &hit)) break;
    // Shade a surface hit from behind like its front: the frame faces the ray.
    if (dot(wi, hit.ng) > 0) {
      hit.ng = hit.ng * -1.0f;
      hit.ns = hit.ns * -1.0f;
    }
    wo = wi * -1.0f;
    x = hit;
  }
  return irradiance;
}

// Running mean and M2 (Welford) of one texel's samples, per channel.
struct TexelStats {
  double mean[kChannels] = {0, 0, 0, 0};
  double m2[kChannels] = {0, 0, 0, 0};
  uint32_t n = 0;
  void add(const Rgb& c) {
    const double x[kChannels] = {c.r, c.g, c.b, c.luminance()};
    ++n;
    for (int i = 0; i < kChannels; ++i) {
      const double delta = x[i] - mean[i];
      mean[i] += delta / n;
      m2[i] += delta * (x[i] - mean[i]);
    }
  }
};

TexelStats bake_texel(const Job& job, uint32_t texel) {
  const uint32_t offset = job.info.offsets[texel];
  const uint32_t valid = static_cast<uint32_t>(std::popcount(job.info.words[offset]) +
                                               std::popcount(job.info.words[offset + 1]));
  Pcg32 rng(job.settings.seed, texel);
  TexelStats stats;
  for (uint32_t i = 0; i < job.settings.samples_per_texel; ++i) {
    // Listing 4.2: one of the texel's valid sample positions, uniformly.
    const atlas::SamplePoint sp = atlas::sample_point(job.info, texel, rng.bounded(valid));
    const Vec3 w = atlas::atlas_barycentrics(
        atlas::texel_triangle(job.scene, job.atlas, sp.instance, sp.triangle), sp.x, sp.y);
    const SurfacePoint x =
        job.rs.surface_at(job.rs.world_triangle(sp.instance, sp.triangle), w.x, w.y, w.z);
    stats.add(trace_path(job, x, rng));
  }
  return stats;
}

}  // namespace

double ReferenceLightmap::std_error(size_t texel, int channel) const {
  const uint32_t n = samples[texel];
  return n > 0 ? std::sqrt(variance[texel * kChannels + channel] / n) : 0.0;
}

Result<ReferenceLightmap> bake_reference(const scene::Scene& scene, const atlas::Atlas& atlas,
                                         const ReferenceSettings& settings) {
  if (settings.samples_per_texel < 2)
    return invalid_argument("reference settings.samples_per_texel: must be >= 2 (variance)");
  if (settings.max_bounces < 0 || settings.max_bounces > 64)
    return invalid_argument(strprintf("reference settings.max_bounces: must be in [0, 64], got %d",
                                      settings.max_bounces));
  if (settings.threads < 1) return invalid_argument("reference settings.threads: must be >= 1");
  const auto t0 = std::chrono::steady_clock::now();
  auto info = atlas::build_sample_info(scene, atlas);
  if (!info) return info.status();
  auto rs = ReferenceScene::create(scene);
  if (!rs) return rs.status();
  const Job job{scene, atlas, info.value(), *rs.value(), settings};

  ReferenceLightmap out;
  out.width = atlas.width;
  out.height = atlas.height;
  const size_t texels = static_cast<size_t>(atlas.width) * static_cast<size_t>(atlas.height);
  out.coverage.assign(texels, 0.0f);
  out.samples.assign(texels, 0);
  out.mean.assign(texels * kChannels, 0.0);
  out.variance.assign(texels * kChannels, 0.0);

  const std::vector<uint32_t>& covered = job.info.covered_texels;
  std::atomic<size_t> next{0};
  auto worker = [&] {
    for (size_t i; (i = next.fetch_add(1)) < covered.size();) {
      const uint32_t texel = covered[i];
      const TexelStats s = bake_texel(job, texel);
      const uint32_t off = job.info.offsets[texel];
      out.coverage[texel] = static_cast<float>(std::popcount(job.info.words[off]) +
                                               std::popcount(job.info.words[off + 1])) /
                            64.0f;
      out.samples[texel] = s.n;
      for (int c = 0; c < kChannels; ++c) {
        out.mean[size_t{texel} * kChannels + c] = s.mean[c];
        out.variance[size_t{texel} * kChannels + c] = s.n > 1 ? s.m2[c] / (s.n - 1) : 0.0;
      }
    }
  };
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < settings.threads; ++t) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();

  out.paths = uint64_t{settings.samples_per_texel} * covered.size();
  out.seconds = seconds_since(t0);
  return out;
}

}  // namespace luxel::reference
