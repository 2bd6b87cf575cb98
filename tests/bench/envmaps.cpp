// Procedural HDR environment maps and sampling helpers for bench_encode
// (see envmaps.h for the conventions and the description of each map).
#include "envmaps.h"

#include <algorithm>
#include <cmath>

namespace luxel::bench {
namespace {

constexpr double kPi = 3.14159265358979323846;

Vec3 from_elevation_azimuth(double elevation_deg, double azimuth_deg) {
  const double e = elevation_deg * kPi / 180.0, a = azimuth_deg * kPi / 180.0;
  return {float(std::cos(e) * std::cos(a)), float(std::cos(e) * std::sin(a)), float(std::sin(e))};
}

Rgb scale(Rgb c, double s) {
  return {float(c.r * s), float(c.g * s), float(c.b * s)};
}
Rgb add(Rgb a, Rgb b) {
  return {a.r + b.r, a.g + b.g, a.b + b.b};
}
Rgb mix(Rgb a, Rgb b, double t) {
  return add(scale(a, 1.0 - t), scale(b, t));
}
// Colour c rescaled to luminance y.
Rgb with_luminance(Rgb c, double y) {
  return scale(c, y / double(luminance(c)));
}

double smoothstep(double e0, double e1, double x) {
  const double t = std::clamp((x - e0) / (e1 - e0), 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

// A planar rectangle at unit distance along `center`, half-extents a (along
// the horizontal tangent) and b (along the other tangent), seen from the
// origin: true when d passes through it.
bool in_rectangle(Vec3 d, Vec3 center, double a, double b) {
  const double dc = dot(d, center);
  if (dc <= 0.0) return false;
  Vec3 t1 = cross(Vec3{0, 0, 1}, center);
  t1 = length(t1) < 1e-6f ? Vec3{1, 0, 0} : normalize(t1);
  const Vec3 t2 = cross(center, t1);
  return std::abs(dot(d, t1) / dc) <= a && std::abs(dot(d, t2) / dc) <= b;
}

// ---- The sunny sky's constants.
constexpr double kSunRadius = 1.0 * kPi / 180.0;  // angular radius (rad)
constexpr double kSunLuminance = 1e5;
constexpr double kSunElevationDeg = 40.0, kSunAzimuthDeg = 30.0;

}  // namespace

const char* EnvMap::name() const {
  switch (kind_) {
    case EnvMapKind::kOvercast:
      return "overcast";
    case EnvMapKind::kSunny:
      return "sunny";
    case EnvMapKind::kClearSky:
      return "clear-sky";
    case EnvMapKind::kStudio:
      return "studio";
    case EnvMapKind::kWindow:
      return "window";
  }
  return "?";
}

Rgb EnvMap::analytic(Vec3 d) const {
  const double z = d.z;
  switch (kind_) {
    case EnvMapKind::kOvercast: {
      // CIE standard overcast sky (Moon & Spencer): L = Lz (1 + 2 cos theta) / 3.
      if (z >= 0.0) return with_luminance({0.93f, 0.96f, 1.0f}, (1.0 + 2.0 * z) / 3.0);
      // Lambertian ground, albedo 0.3, under that sky: E = 7 pi / 9 Lz.
      return with_luminance({1.0f, 0.93f, 0.85f}, 0.3 * 7.0 / 9.0);
    }
    case EnvMapKind::kSunny:
    case EnvMapKind::kClearSky: {
      const double cos_gamma = std::clamp(double(dot(d, sun_)), -1.0, 1.0);
      if (z >= 0.0) {
        if (kind_ == EnvMapKind::kSunny && cos_gamma >= std::cos(kSunRadius))
          return with_luminance({1.0f, 0.96f, 0.90f}, kSunLuminance);
        const double gamma = std::acos(cos_gamma);
        // Horizon brightening and a blue zenith (luminance ~0.83 -> ~0.28),
        // plus a circumsolar glow (Preetham-like in spirit, not in detail).
        Rgb sky = mix({0.76f, 0.836f, 0.95f}, {0.12f, 0.28f, 0.75f}, std::sqrt(z));
        sky = add(sky, scale({1.0f, 0.85f, 0.6f}, 3.0 * std::exp(-gamma / 0.1)));
        sky = add(sky, scale({1.0f, 0.9f, 0.8f}, 0.3 * std::exp(-gamma / 0.6)));
        return sky;
      }
      // Ground, albedo 0.2, lit by the sun (1e5 x its solid angle x sin of
      // its elevation) and the sky (about pi x 0.55).
      const double sun_solid_angle = 2.0 * kPi * (1.0 - std::cos(kSunRadius));
      const double e =
          kSunLuminance * sun_solid_angle * std::sin(kSunElevationDeg * kPi / 180.0) + kPi * 0.55;
      return with_luminance({0.9f, 0.8f, 0.65f}, 0.2 / kPi * e);
    }
    case EnvMapKind::kStudio: {
      struct Light {
        double elevation, azimuth, a, b;
        Rgb colour;
      };
      static const Light kLights[] = {
          {35, 45, 0.30, 0.40, {30.0f, 26.4f, 21.6f}},   // warm key
          {15, 200, 0.45, 0.30, {3.3f, 4.2f, 6.0f}},     // cool fill
          {55, 300, 0.06, 0.45, {40.0f, 10.0f, 18.0f}},  // red-magenta strip rim
          {90, 0, 0.12, 0.12, {60.0f, 60.0f, 60.0f}},    // small white top light
      };
      for (const Light& l : kLights) {
        if (in_rectangle(d, from_elevation_azimuth(l.elevation, l.azimuth), l.a, l.b))
          return l.colour;
      }
      return z >= 0.0 ? Rgb{0.02f, 0.02f, 0.02f} : Rgb{0.03f, 0.029f, 0.028f};
    }
    case EnvMapKind::kWindow: {
      if (z >= 0.0) {
        // Window in the wall x = 1: |y| <= 0.55, 0.08 <= z <= 0.9 on that plane.
        if (d.x > 0.0f) {
          const double py = d.y / d.x, pz = d.z / d.x;
          if (std::abs(py) <= 0.55 && pz >= 0.08 && pz <= 0.9)
            return scale({0.75f, 0.85f, 1.0f}, 3.0 + 5.0 * (pz - 0.08) / 0.82);
        }
        // Walls, and a ceiling brightened by the floor bounce.
        return scale({0.09f, 0.085f, 0.08f}, 0.8 + 0.7 * z * z);
      }
      // Floor z = -1: warm base and a sunlit patch under the window.
      const double px = d.x / -z, py = d.y / -z;
      const double patch = smoothstep(0.1, 0.3, px) * (1.0 - smoothstep(0.9, 1.1, px)) *
                           (1.0 - smoothstep(0.4, 0.6, std::abs(py)));
      return add(scale({0.55f, 0.4f, 0.28f}, 0.35), scale({1.0f, 0.78f, 0.55f}, 2.5 * patch));
    }
  }
  return {};
}

double EnvMap::texel_solid_angle(int y) const {
  const double c0 = std::cos(kPi * y / height_), c1 = std::cos(kPi * (y + 1) / height_);
  return 2.0 * kPi / width_ * (c0 - c1);
}

Vec3 EnvMap::texel_center(int x, int y) const {
  const double c0 = std::cos(kPi * y / height_), c1 = std::cos(kPi * (y + 1) / height_);
  const double z = 0.5 * (c0 + c1), r = std::sqrt(std::max(0.0, 1.0 - z * z));
  const double phi = 2.0 * kPi * (x + 0.5) / width_;
  return {float(r * std::cos(phi)), float(r * std::sin(phi)), float(z)};
}

void EnvMap::texel_of(Vec3 d, int& x, int& y) const {
  const double theta = std::acos(std::clamp(double(d.z), -1.0, 1.0));
  double phi = std::atan2(double(d.y), double(d.x));
  if (phi < 0.0) phi += 2.0 * kPi;
  x = std::clamp(int(phi / (2.0 * kPi) * width_), 0, width_ - 1);
  y = std::clamp(int(theta / kPi * height_), 0, height_ - 1);
}

Rgb EnvMap::radiance(Vec3 d) const {
  int x, y;
  texel_of(d, x, y);
  return texel(x, y);
}

float EnvMap::luminance(Vec3 d) const {
  return bench::luminance(radiance(d));
}

EnvMap EnvMap::generate(EnvMapKind kind, int width, int height, int supersample) {
  EnvMap m;
  m.kind_ = kind;
  m.width_ = width;
  m.height_ = height;
  if (kind == EnvMapKind::kSunny || kind == EnvMapKind::kClearSky) {
    // Centre the disc on a texel so its brightest texel is fully covered.
    int x, y;
    m.texel_of(from_elevation_azimuth(kSunElevationDeg, kSunAzimuthDeg), x, y);
    m.sun_ = m.texel_center(x, y);
  }
  m.texels_.resize(size_t(width) * size_t(height));
  m.max_luminance_ = 0.0f;
  m.min_luminance_ = INFINITY;
  const int s = supersample;
  for (int y = 0; y < height; ++y) {
    const double c0 = std::cos(kPi * y / height), c1 = std::cos(kPi * (y + 1) / height);
    for (int x = 0; x < width; ++x) {
      double r = 0, g = 0, b = 0;
      for (int i = 0; i < s; ++i) {
        // Uniform in cos theta and phi = uniform in solid angle.
        const double z = c0 + (c1 - c0) * (i + 0.5) / s,
                     rho = std::sqrt(std::max(0.0, 1.0 - z * z));
        for (int j = 0; j < s; ++j) {
          const double phi = 2.0 * kPi * (x + (j + 0.5) / s) / width;
          const Rgb c =
              m.analytic({float(rho * std::cos(phi)), float(rho * std::sin(phi)), float(z)});
          r += c.r;
          g += c.g;
          b += c.b;
        }
      }
      const Rgb avg{float(r / (s * s)), float(g / (s * s)), float(b / (s * s))};
      m.texels_[size_t(y) * size_t(width) + size_t(x)] = avg;
      m.max_luminance_ = std::max(m.max_luminance_, bench::luminance(avg));
      m.min_luminance_ = std::min(m.min_luminance_, bench::luminance(avg));
    }
  }
  return m;
}

EnvQuadrature EnvQuadrature::build(const EnvMap& map, bool upper_only, int q) {
  // Gauss-Legendre nodes and weights on [-1, 1] for q = 1, 2, 3.
  static const double kNodes[3][3] = {{0.0, 0, 0},
                                      {-0.5773502691896258, 0.5773502691896258, 0},
                                      {-0.7745966692414834, 0.0, 0.7745966692414834}};
  static const double kWeights[3][3] = {
      {2.0, 0, 0}, {1.0, 1.0, 0}, {5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0}};
  q = std::clamp(q, 1, 3);
  const double* nodes = kNodes[q - 1];
  const double* weights = kWeights[q - 1];
  const int w = map.width(), h = map.height(), rows = upper_only ? h / 2 : h;
  EnvQuadrature quad;
  quad.directions.reserve(size_t(w) * size_t(rows) * size_t(q * q));
  quad.weights.reserve(quad.directions.capacity());
  quad.values.reserve(quad.directions.capacity());
  for (int y = 0; y < rows; ++y) {
    const double c0 = std::cos(kPi * y / h), c1 = std::cos(kPi * (y + 1) / h);
    const double dphi = 2.0 * kPi / w;
    for (int x = 0; x < w; ++x) {
      const double value = luminance(map.texel(x, y));
      for (int i = 0; i < q; ++i) {
        const double z = 0.5 * (c0 + c1) + 0.5 * (c0 - c1) * nodes[i];
        const double rho = std::sqrt(std::max(0.0, 1.0 - z * z));
        for (int j = 0; j < q; ++j) {
          const double phi = dphi * (x + 0.5 + 0.5 * nodes[j]);
          quad.directions.push_back(
              {float(rho * std::cos(phi)), float(rho * std::sin(phi)), float(z)});
          // (c0 - c1) / 2 * w_i  x  dphi / 2 * w_j
          quad.weights.push_back(0.25 * (c0 - c1) * dphi * weights[i] * weights[j]);
          quad.values.push_back(value);
        }
      }
    }
  }
  for (double wk : quad.weights) quad.area += wk;
  return quad;
}

uint64_t Rng::next_u64() {
  uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

uint64_t mix_seed(uint64_t a, uint64_t b, uint64_t c, uint64_t d) {
  Rng r(a * 0x9E3779B97F4A7C15ull ^ b);
  uint64_t s = r.next_u64() ^ c;
  Rng r2(s);
  s = r2.next_u64() ^ d;
  Rng r3(s);
  return r3.next_u64();
}

Vec3 uniform_direction(double u1, double u2, bool hemisphere) {
  const double z = hemisphere ? u1 : 1.0 - 2.0 * u1;
  const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  const double phi = 2.0 * kPi * u2;
  return {float(r * std::cos(phi)), float(r * std::sin(phi)), float(z)};
}

double radical_inverse(uint32_t i, uint32_t base) {
  double inv = 1.0 / base, f = inv, result = 0.0;
  while (i > 0) {
    result += f * (i % base);
    i /= base;
    f *= inv;
  }
  return result;
}

std::vector<Vec3> random_directions(int n, uint64_t seed, bool hemisphere) {
  Rng rng(seed);
  std::vector<Vec3> dirs;
  dirs.reserve(size_t(n));
  for (int i = 0; i < n; ++i) {
    const double u1 = rng.next_double(), u2 = rng.next_double();
    dirs.push_back(uniform_direction(u1, u2, hemisphere));
  }
  return dirs;
}

std::vector<Vec3> halton_directions(int n, bool hemisphere, double offset_u, double offset_v) {
  std::vector<Vec3> dirs;
  dirs.reserve(size_t(n));
  for (int i = 0; i < n; ++i) {
    double u = radical_inverse(uint32_t(i + 1), 2) + offset_u;
    double v = radical_inverse(uint32_t(i + 1), 3) + offset_v;
    u -= std::floor(u);
    v -= std::floor(v);
    dirs.push_back(uniform_direction(u, v, hemisphere));
  }
  return dirs;
}

std::vector<Vec3> hammersley_directions(int n, bool hemisphere) {
  std::vector<Vec3> dirs;
  dirs.reserve(size_t(n));
  for (int i = 0; i < n; ++i)
    dirs.push_back(uniform_direction((i + 0.5) / n, radical_inverse(uint32_t(i), 2), hemisphere));
  return dirs;
}

std::vector<Vec3> fibonacci_directions(int n, bool hemisphere) {
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  std::vector<Vec3> dirs;
  dirs.reserve(size_t(n));
  for (int i = 0; i < n; ++i) {
    const double z = hemisphere ? 1.0 - (i + 0.5) / n : 1.0 - 2.0 * (i + 0.5) / n;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    dirs.push_back({float(r * std::cos(golden * i)), float(r * std::sin(golden * i)), float(z)});
  }
  return dirs;
}

}  // namespace luxel::bench
