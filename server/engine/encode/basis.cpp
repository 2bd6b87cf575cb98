#include "encode/basis.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <nlohmann/json.hpp>

#include "kernels/shared/bases.h"

namespace luxel::encode {
namespace {

constexpr double kPi = 3.14159265358979323846;

Vec3 unit(double x, double y, double z) {
  const double l = std::sqrt(x * x + y * y + z * z);
  return {static_cast<float>(x / l), static_cast<float>(y / l), static_cast<float>(z / l)};
}

const char* domain_name(BasisDomain d) {
  return d == BasisDomain::kSphere ? "sphere" : "hemisphere (z >= 0)";
}

}  // namespace

std::vector<Vec3> spherical_fibonacci(int count, BasisDomain domain) {
  const double golden_angle = kPi * (3.0 - std::sqrt(5.0));
  std::vector<Vec3> dirs;
  for (int i = 0; i < count; ++i) {
    const double z =
        domain == BasisDomain::kSphere ? 1.0 - (2.0 * i + 1.0) / count : 1.0 - (i + 0.5) / count;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = golden_angle * i;
    dirs.push_back(unit(r * std::cos(phi), r * std::sin(phi), z));
  }
  return dirs;
}

std::vector<Vec3> icosahedron_vertices() {
  const double p = 0.5 * (1.0 + std::sqrt(5.0));
  std::vector<Vec3> v;
  for (double a : {-1.0, 1.0}) {
    for (double b : {-p, p}) {
      v.push_back(unit(0, a, b));
      v.push_back(unit(a, b, 0));
      v.push_back(unit(b, 0, a));
    }
  }
  return v;
}

std::vector<Vec3> ambient_dice_hemisphere_vertices() {
  // §8.3.1: an icosahedron rotated so the mean of these nine points is +z;
  // the three omitted vertices are the antipodes of v1..v3.
  static const double kTable[9][3] = {
      {0.5257, -0.3035, 0.7947},   {-0.5257, -0.3035, 0.7947}, {0.0, 0.6071, 0.7947},
      {0.8507, 0.4911, 0.1876},    {-0.8507, 0.4911, 0.1876},  {0.0, -0.9822, 0.1876},
      {-0.8507, -0.4911, -0.1876}, {0.8507, -0.4911, -0.1876}, {0.0, 0.9822, -0.1876}};
  std::vector<Vec3> v;
  for (const auto& r : kTable) v.push_back(unit(r[0], r[1], r[2]));
  return v;
}

Result<SphericalBasis> SphericalBasis::create(const BasisSpec& spec) {
  SphericalBasis b;
  b.spec_ = spec;
  switch (spec.kind) {
    case BasisKind::kShL1:
      b.count_ = LUX_SH_L1_COUNT;
      break;
    case BasisKind::kShL2:
      b.count_ = LUX_SH_L2_COUNT;
      break;
    case BasisKind::kSphericalGaussian:
      if (spec.lobe_count != 6 && spec.lobe_count != 9 && spec.lobe_count != 12)
        return invalid_argument(
            strprintf("spherical Gaussian lobe count %d: expected 6, 9 or 12", spec.lobe_count));
      if (!(spec.sharpness > 0.0f) || !std::isfinite(spec.sharpness))
        return invalid_argument(
            strprintf("spherical Gaussian sharpness %g: must be finite and > 0", spec.sharpness));
      b.directions_ = spherical_fibonacci(spec.lobe_count, spec.lobe_layout);
      b.count_ = spec.lobe_count;
      break;
    case BasisKind::kAmbientDice:
      if (spec.lobe_count == 12) {
        b.directions_ = icosahedron_vertices();
      } else if (spec.lobe_count == 9) {
        b.directions_ = ambient_dice_hemisphere_vertices();
      } else {
        return invalid_argument(
            strprintf("Ambient Dice vertex count %d: expected 12 or 9", spec.lobe_count));
      }
      b.count_ = spec.lobe_count;
      break;
  }
  return b;
}

Result<SphericalBasis> SphericalBasis::from_name(std::string_view name, float sg_sharpness) {
  BasisSpec s;
  std::string n(name);
  if (std::find(kEncodingNames.begin(), kEncodingNames.end(), name) == kEncodingNames.end())
    return invalid_argument(
        strprintf("unknown encoding '%s': expected sh1, sh2, sg6/9/12[-hemi] or ambient-dice9/12",
                  n.c_str()));
  if (n == "sh1") {
    s.kind = BasisKind::kShL1;
  } else if (n == "sh2") {
    s.kind = BasisKind::kShL2;
  } else if (n.rfind("ambient-dice", 0) == 0) {
    s.kind = BasisKind::kAmbientDice;
    s.lobe_count = std::atoi(n.c_str() + 12);
  } else if (n.rfind("sg", 0) == 0) {
    s.kind = BasisKind::kSphericalGaussian;
    s.sharpness = sg_sharpness;
    s.lobe_count = std::atoi(n.c_str() + 2);
    if (n.size() > 5 && n.substr(n.size() - 5) == "-hemi") s.lobe_layout = BasisDomain::kHemisphere;
  } else {
    return invalid_argument(
        strprintf("unknown encoding '%s': expected sh1, sh2, sg6/9/12[-hemi] or ambient-dice9/12",
                  n.c_str()));
  }
  return create(s);
}

void SphericalBasis::evaluate(Vec3 w, float* out) const {
  switch (spec_.kind) {
    case BasisKind::kShL1:
    case BasisKind::kShL2:
      lux_sh_eval(w.x, w.y, w.z, count_, out);
      return;
    case BasisKind::kSphericalGaussian:
      for (int i = 0; i < count_; ++i)
        out[i] = lux_sg_eval(dot(directions_[size_t(i)], w), spec_.sharpness);
      return;
    case BasisKind::kAmbientDice:
      for (int i = 0; i < count_; ++i) out[i] = lux_ad_cosine_lobe(dot(directions_[size_t(i)], w));
      return;
  }
}

std::vector<float> SphericalBasis::evaluate(Vec3 w) const {
  std::vector<float> out(static_cast<size_t>(count_));
  evaluate(w, out.data());
  return out;
}

float SphericalBasis::diffuse_irradiance(const float* c, Vec3 n) const {
  float e = 0.0f;
  switch (spec_.kind) {
    case BasisKind::kShL1:
    case BasisKind::kShL2:
      return lux_sh_diffuse_irradiance(c, count_, n.x, n.y, n.z);
    case BasisKind::kSphericalGaussian:
      for (int i = 0; i < count_; ++i)
        e += c[i] * lux_sg_diffuse_irradiance_hill(dot(directions_[size_t(i)], n), spec_.sharpness);
      return e;
    case BasisKind::kAmbientDice:
      // Eq. 8.15 yields E / pi (the thesis integrates against cos / pi).
      for (int i = 0; i < count_; ++i)
        e += c[i] * lux_ad_diffuse_fit(dot(directions_[size_t(i)], n));
      return LUX_BASES_PI * e;
  }
  return e;
}

BasisDescription SphericalBasis::describe() const {
  BasisDescription d;
  d.directions = directions_;
  d.fit_domain = domain_name(spec_.fit_domain);
  switch (spec_.kind) {
    case BasisKind::kShL1:
    case BasisKind::kShL2:
      d.name = spec_.kind == BasisKind::kShL1 ? "sh1" : "sh2";
      d.function =
          "real orthonormal spherical harmonics, order l*(l+1)+m: Y00; Y1-1~y, Y10~z, Y11~x; "
          "Y2-2~xy, Y2-1~yz, Y20~3z^2-1, Y21~xz, Y22~x^2-y^2 (Ramamoorthi-Hanrahan 2001)";
      d.normalisation =
          "radiance L(w) = sum_i c_i Y_i(w); irradiance E(n) = sum_i A_l(i) c_i Y_i(n), "
          "A = (pi, 2pi/3, pi/4)";
      d.layout = "none";
      break;
    case BasisKind::kSphericalGaussian:
      d.name =
          strprintf("sg%d%s", count_, spec_.lobe_layout == BasisDomain::kHemisphere ? "-hemi" : "");
      d.function = "B_i(w) = exp(lambda * (dot(w, p_i) - 1)) (thesis Eq. 8.2)";
      d.normalisation =
          "radiance L(w) = sum_i c_i B_i(w); irradiance by Hill's fit (Pettineo 2016, "
          "SGIrradianceFitted)";
      d.layout =
          spec_.lobe_layout == BasisDomain::kSphere
              ? "spherical Fibonacci: z_i = 1 - (2i+1)/N, phi_i = i * pi * (3 - sqrt 5)"
              : "hemispherical Fibonacci: z_i = 1 - (i+0.5)/N, phi_i = i * pi * (3 - sqrt 5)";
      d.sharpness = spec_.sharpness;
      break;
    case BasisKind::kAmbientDice:
      d.name = strprintf("ambient-dice%d", count_);
      d.function = "B_i(w) = 0.35 x^2 + 0.25 x^4, x = max(dot(w, v_i), 0) (thesis Eq. 8.3/8.4)";
      d.normalisation =
          "radiance L(w) = sum_i c_i B_i(w); irradiance E(n) = pi * sum_i c_i * "
          "(0.05981 + 0.12918 t + 0.07056 t^2), t = dot(n, v_i) (Eq. 8.14/8.15)";
      d.layout = count_ == 12
                     ? "regular icosahedron (0, +-1, +-phi) and cyclic permutations, normalised"
                     : "nine-vertex hemisphere set of thesis §8.3.1, normalised";
      break;
  }
  return d;
}

std::string BasisDescription::to_json() const {
  nlohmann::json j;
  j["name"] = name;
  j["function"] = function;
  j["normalisation"] = normalisation;
  j["layout"] = layout;
  j["fit_domain"] = fit_domain;
  if (sharpness > 0.0f) j["sharpness"] = sharpness;
  nlohmann::json dirs = nlohmann::json::array();
  for (const Vec3& v : directions) dirs.push_back({v.x, v.y, v.z});
  j["directions"] = dirs;
  return j.dump();
}

}  // namespace luxel::encode
