#include "accel/ray_gen.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "kernels/shared/ray_offset.h"

namespace luxel::accel {
namespace {

// PCG32 (O'Neill 2014): small, fast, reproducible across platforms.
class Pcg32 {
 public:
  explicit Pcg32(uint64_t seed) : state_(0), inc_((seed << 1u) | 1u) {
    next();
    state_ += seed ^ 0x853c49e6748fea9bull;
    next();
  }
  uint32_t next() {
    const uint64_t old = state_;
    state_ = old * 6364136223846793005ull + inc_;
    const uint32_t xorshifted = static_cast<uint32_t>(((old >> 18u) ^ old) >> 27u);
    const uint32_t rot = static_cast<uint32_t>(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
  }
  float uniform() { return static_cast<float>(next() >> 8) * (1.0f / 16777216.0f); }

 private:
  uint64_t state_, inc_;
};

struct Frame {
  Vec3 t, b, n;
};

Frame frame_from(Vec3 n) {
  // Duff et al. 2017, "Building an Orthonormal Basis, Revisited".
  const float sign = std::copysign(1.0f, n.z);
  const float a = -1.0f / (sign + n.z);
  const float b = n.x * n.y * a;
  return {{1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x}, {b, sign + n.y * n.y * a, -n.y}, n};
}

Vec3 uniform_sphere(Pcg32& rng) {
  const float z = 1.0f - 2.0f * rng.uniform();
  const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
  const float phi = 2.0f * std::numbers::pi_v<float> * rng.uniform();
  return {r * std::cos(phi), r * std::sin(phi), z};
}

Vec3 cosine_hemisphere(Pcg32& rng, const Frame& f) {
  const float r = std::sqrt(rng.uniform());
  const float phi = 2.0f * std::numbers::pi_v<float> * rng.uniform();
  const float x = r * std::cos(phi), y = r * std::sin(phi);
  const float z = std::sqrt(std::max(0.0f, 1.0f - x * x - y * y));
  return f.t * x + f.b * y + f.n * z;
}

// Area-weighted triangle picking by binary search over the prefix sum.
class SurfaceSampler {
 public:
  explicit SurfaceSampler(const TriangleSoup& soup) : soup_(soup) {
    cdf_.reserve(soup.size());
    double total = 0;
    for (size_t t = 0; t < soup.size(); ++t) {
      total += 0.5 * length(cross(soup.v(t, 1) - soup.v(t, 0), soup.v(t, 2) - soup.v(t, 0)));
      cdf_.push_back(total);
    }
  }
  // Point and geometric normal (random side) on a random triangle.
  void sample(Pcg32& rng, Vec3& p, Vec3& n) const {
    const double x = static_cast<double>(rng.uniform()) * cdf_.back();
    const size_t t = std::min<size_t>(
        static_cast<size_t>(std::upper_bound(cdf_.begin(), cdf_.end(), x) - cdf_.begin()),
        cdf_.size() - 1);
    float u = rng.uniform(), v = rng.uniform();
    if (u + v > 1.0f) {
      u = 1.0f - u;
      v = 1.0f - v;
    }
    const Vec3 a = soup_.v(t, 0), b = soup_.v(t, 1), c = soup_.v(t, 2);
    p = a + (b - a) * u + (c - a) * v;
    n = normalize(cross(b - a, c - a));
    if (rng.uniform() < 0.5f) n = n * -1.0f;
  }

 private:
  const TriangleSoup& soup_;
  std::vector<double> cdf_;
};

cl::LuxRay make_ray(Vec3 o, Vec3 d, float tmin, float tmax) {
  return {{o.x, o.y, o.z, tmin}, {d.x, d.y, d.z, tmax}};
}

Vec3 offset(Vec3 p, Vec3 n) {
  LUX_OFFSET_RAY_ORIGIN(p.x, p.y, p.z, n.x, n.y, n.z);
  return p;
}

}  // namespace

const char* ray_kind_name(RayKind kind) {
  switch (kind) {
    case RayKind::kCoherent:
      return "coherent";
    case RayKind::kIncoherent:
      return "incoherent";
    case RayKind::kRandom:
      return "random";
    case RayKind::kShadow:
      return "shadow";
  }
  return "?";
}

std::vector<cl::LuxRay> make_rays(const TriangleSoup& soup, RayKind kind, size_t count,
                                  uint64_t seed) {
  std::vector<cl::LuxRay> rays;
  rays.reserve(count);
  Pcg32 rng(seed * 4 + static_cast<uint64_t>(kind));
  const Bounds3 b = soup.bounds.empty() ? Bounds3{{-1, -1, -1}, {1, 1, 1}} : soup.bounds;
  const Vec3 centre = (b.lo + b.hi) * 0.5f;
  const bool has_surface = soup.size() > 0;

  if (kind == RayKind::kCoherent || (!has_surface && kind != RayKind::kRandom)) {
    // Six 90-degree cameras; side chosen so six faces hold `count` rays.
    const size_t side = std::max<size_t>(8, static_cast<size_t>(std::ceil(std::sqrt(count / 6.0))));
    static const Vec3 fwd[6] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
    static const Vec3 up[6] = {{0, 1, 0}, {0, 1, 0}, {0, 0, 1}, {0, 0, -1}, {0, 1, 0}, {0, 1, 0}};
    for (int face = 0; face < 6 && rays.size() < count; ++face) {
      const Vec3 right = cross(fwd[face], up[face]);
      for (size_t ty = 0; ty < side; ty += 8)
        for (size_t tx = 0; tx < side; tx += 8)
          for (size_t y = ty; y < std::min(side, ty + 8); ++y)
            for (size_t x = tx; x < std::min(side, tx + 8); ++x) {
              if (rays.size() >= count) break;
              const float sx =
                  2.0f * (static_cast<float>(x) + 0.5f) / static_cast<float>(side) - 1.0f;
              const float sy =
                  2.0f * (static_cast<float>(y) + 0.5f) / static_cast<float>(side) - 1.0f;
              rays.push_back(make_ray(centre, normalize(fwd[face] + right * sx + up[face] * sy),
                                      0.0f, INFINITY));
            }
    }
    return rays;
  }

  const SurfaceSampler sampler(soup);
  for (size_t i = 0; i < count; ++i) {
    switch (kind) {
      case RayKind::kRandom: {
        const Vec3 e = b.extent();
        const Vec3 o{b.lo.x + e.x * rng.uniform(), b.lo.y + e.y * rng.uniform(),
                     b.lo.z + e.z * rng.uniform()};
        rays.push_back(make_ray(o, uniform_sphere(rng), 0.0f, INFINITY));
        break;
      }
      case RayKind::kIncoherent: {
        Vec3 p, n;
        sampler.sample(rng, p, n);
        rays.push_back(
            make_ray(offset(p, n), cosine_hemisphere(rng, frame_from(n)), 0.0f, INFINITY));
        break;
      }
      case RayKind::kShadow: {
        Vec3 p, n, q, m;
        sampler.sample(rng, p, n);
        sampler.sample(rng, q, m);
        const Vec3 o = offset(p, dot(q - p, n) >= 0 ? n : n * -1.0f);
        const Vec3 target = offset(q, dot(p - q, m) >= 0 ? m : m * -1.0f);
        // Unnormalized direction: the segment is t in (0, 1).
        rays.push_back(make_ray(o, target - o, 0.0f, 1.0f - 1e-4f));
        break;
      }
      case RayKind::kCoherent:
        break;
    }
  }
  return rays;
}

}  // namespace luxel::accel
