#include "reference/reference_bsdf.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>

namespace luxel::reference {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDielectricF0 = 0.04;  // Appendix B: ior 1.5, ((1.5 - 1) / (1.5 + 1))^2

double dot(const Dir3& a, const Dir3& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}

Dir3 normalized(const Dir3& a) {
  const double l = std::sqrt(dot(a, a));
  return {a.x / l, a.y / l, a.z / l};
}

double schlick(double f0, double cos_theta) {
  const double c = 1.0 - std::clamp(cos_theta, 0.0, 1.0);
  const double c2 = c * c;
  return f0 + (1.0 - f0) * c2 * c2 * c;
}

// Kulla-Conty: the colour of the multiply scattered light for Schlick's F,
// whose hemispherical average 2 int F(mu) mu dmu is f0 + (1 - f0) / 21.
double kulla_conty_fms(double f0, double e_avg) {
  const double f_avg = f0 + (1.0 - f0) / 21.0;
  return f_avg * f_avg * e_avg / (1.0 - f_avg * (1.0 - e_avg));
}

// Gauss-Legendre nodes and weights on [0, 1] (Newton on P_n).
struct GaussLegendre {
  std::vector<double> x, w;
  explicit GaussLegendre(int n) {
    for (int i = 0; i < n; ++i) {
      double z = std::cos(kPi * (i + 0.75) / (n + 0.5)), dp = 0;
      for (int it = 0; it < 100; ++it) {
        double p0 = 1, p1 = 0;
        for (int k = 1; k <= n; ++k) {
          const double p2 = p1;
          p1 = p0;
          p0 = ((2.0 * k - 1) * z * p1 - (k - 1.0) * p2) / k;
        }
        dp = n * (z * p0 - p1) / (z * z - 1);
        const double dz = p0 / dp;
        z -= dz;
        if (std::abs(dz) < 1e-15) break;
      }
      x.push_back(0.5 * (1 - z));
      w.push_back(1.0 / ((1 - z * z) * dp * dp));  // 2 / ((1 - z^2) P'^2), halved for [0, 1]
    }
  }
};

// Composite rule: `panels` equal panels of an n-point Gauss-Legendre rule.
struct CompositeRule {
  std::vector<double> x, w;
  CompositeRule(int panels, int n) {
    const GaussLegendre g(n);
    for (int p = 0; p < panels; ++p)
      for (int i = 0; i < n; ++i) {
        x.push_back((p + g.x[static_cast<size_t>(i)]) / panels);
        w.push_back(g.w[static_cast<size_t>(i)] / panels);
      }
  }
};

}  // namespace

double ggx_d(double cos_h, double alpha) {
  if (cos_h <= 0) return 0;
  const double a2 = alpha * alpha;
  const double t = cos_h * cos_h * (a2 - 1.0) + 1.0;
  return a2 / (kPi * t * t);
}

double ggx_lambda(const Dir3& w, double alpha) {
  // (sqrt(1 + a) - 1) / 2 = a / (2 (sqrt(1 + a) + 1)), a = alpha^2 tan^2.
  const double a = alpha * alpha * (w.x * w.x + w.y * w.y) / (w.z * w.z);
  return a / (2.0 * (std::sqrt(1.0 + a) + 1.0));
}

double ggx_g2(const Dir3& wo, const Dir3& wi, double alpha) {
  return 1.0 / (1.0 + ggx_lambda(wo, alpha) + ggx_lambda(wi, alpha));
}

double GgxAlbedo::quadrature(double mu, double alpha) {
  // E(mu) = int D G2 / (4 mu mu_i) mu_i dw_i; with w_i the reflection of wo
  // about h, dw_i = 4 (wo.h) dw_h, so E = int G2 (wo.h) / mu D(h) dw_h. The
  // GGX measure D(h) h.z dw_h is du dphi / (2 pi) with tan^2 theta_h =
  // alpha^2 u / (1 - u); u = 1 - (1 - t)^2 removes the 1 / h.z singularity
  // at u -> 1, leaving a bounded integrand in (t, phi). wo lies in the xz
  // plane, so phi in [0, pi] counts twice.
  static const CompositeRule rule_t(48, 6), rule_phi(48, 6);
  mu = std::clamp(mu, 1e-9, 1.0);
  const Dir3 wo{std::sqrt(std::max(0.0, 1.0 - mu * mu)), 0.0, mu};
  const double a2 = alpha * alpha, lambda_o = ggx_lambda(wo, alpha);
  double sum = 0;
  for (size_t i = 0; i < rule_t.x.size(); ++i) {
    const double t = rule_t.x[i], s = 1.0 - t, u = 1.0 - s * s;
    const double q = std::sqrt(s * s + a2 * u);  // = s / cos theta_h
    const double cos_h = s / q, sin_h = std::sqrt(a2 * u) / q;
    const double jacobian = 2.0 * q;  // du / dt / cos theta_h
    double row = 0;
    for (size_t j = 0; j < rule_phi.x.size(); ++j) {
      const double phi = kPi * rule_phi.x[j];
      const Dir3 h{sin_h * std::cos(phi), sin_h * std::sin(phi), cos_h};
      const double oh = dot(wo, h);
      if (oh <= 0) continue;
      const Dir3 wi{2 * oh * h.x - wo.x, 2 * oh * h.y - wo.y, 2 * oh * h.z - wo.z};
      if (wi.z <= 0) continue;
      row += rule_phi.w[j] / (1.0 + lambda_o + ggx_lambda(wi, alpha)) * oh;
    }
    sum += rule_t.w[i] * jacobian * row;
  }
  // phi weights sum to 1 over [0, pi]: the 1 / (2 pi) of the measure times
  // pi (the range) times 2 (symmetry).
  return sum / mu;
}

GgxAlbedo::GgxAlbedo(double roughness) : roughness_(roughness), e_(kNodes) {
  const double alpha = roughness * roughness;
  for (int i = 0; i < kNodes; ++i) {
    const double x = static_cast<double>(i) / (kNodes - 1);
    e_[static_cast<size_t>(i)] = quadrature(x * x, alpha);
  }
  // E_avg = 2 int E(mu) mu dmu = 4 int E(x) x^3 dx (mu = x^2): a 3-point
  // Gauss-Legendre rule per cell is exact for the linear E(x) times x^3.
  const GaussLegendre g(3);
  const double h = 1.0 / (kNodes - 1);
  double sum = 0;
  for (int i = 0; i + 1 < kNodes; ++i)
    for (size_t k = 0; k < 3; ++k) {
      const double s = g.x[k], x = (i + s) * h;
      const double e = (1 - s) * e_[static_cast<size_t>(i)] + s * e_[static_cast<size_t>(i) + 1];
      sum += g.w[k] * h * 4.0 * e * x * x * x;
    }
  e_avg_ = sum;
}

std::shared_ptr<const GgxAlbedo> GgxAlbedo::get(double roughness) {
  static std::mutex mutex;
  static std::map<double, std::shared_ptr<const GgxAlbedo>> cache;
  const std::lock_guard<std::mutex> lock(mutex);
  auto& slot = cache[roughness];
  if (!slot) slot = std::make_shared<const GgxAlbedo>(roughness);
  return slot;
}

double GgxAlbedo::operator()(double mu) const {
  const double x = std::sqrt(std::clamp(mu, 0.0, 1.0)) * (kNodes - 1);
  const int i = std::min(static_cast<int>(x), kNodes - 2);
  const double t = x - i;
  return (1 - t) * e_[static_cast<size_t>(i)] + t * e_[static_cast<size_t>(i) + 1];
}

Rgb GgxBrdf::eval(const Dir3& wo, const Dir3& wi) const {
  if (wo.z <= 0 || wi.z <= 0) return {};
  const Dir3 h = normalized({wo.x + wi.x, wo.y + wi.y, wo.z + wi.z});
  const double oh = dot(wo, h), alpha = roughness * roughness;
  const double spec = ggx_d(h.z, alpha) * ggx_g2(wo, wi, alpha) / (4.0 * wo.z * wi.z);
  const double m = metallic;
  double ms = 0, e_avg = 0;  // compensation: (1 - E(wo.z)) (1 - E(wi.z)) / (pi (1 - E_avg))
  if (model == BrdfModel::kGltf) {
    e_avg = albedo->average();
    if (1.0 - e_avg > 1e-12)
      ms = (1.0 - (*albedo)(wo.z)) * (1.0 - (*albedo)(wi.z)) / (kPi * (1.0 - e_avg));
  }
  Rgb f;
  for (int c = 0; c < 3; ++c) {
    const double b = base[c];
    double v;
    if (model == BrdfModel::kPreviousDiffuseWeight) {
      const double f0 = (1 - m) * kDielectricF0 + m * b;
      v = schlick(f0, oh) * spec + (1 - m) * b / kPi * (1.0 - schlick(f0, wo.z));
    } else {
      const double metal = schlick(b, oh) * spec;
      const double fd = schlick(kDielectricF0, oh);
      const double dielectric = fd * spec + (1.0 - fd) * b / kPi;
      v = (1 - m) * dielectric + m * metal;
      if (ms > 0)
        v += ((1 - m) * kulla_conty_fms(kDielectricF0, e_avg) + m * kulla_conty_fms(b, e_avg)) * ms;
    }
    (c == 0 ? f.r : (c == 1 ? f.g : f.b)) = v;
  }
  return f;
}

Dir3 GgxBrdf::sample(const Dir3& wo, double u_choice, double u1, double u2) const {
  const double phi = 2.0 * kPi * u2;
  if (u_choice < p_ggx()) {
    // h from D(h) h.z: tan^2 theta_h = alpha^2 u / (1 - u); wi = reflect(wo, h).
    const double a2 = roughness * roughness * roughness * roughness;
    const double tan2 = a2 * u1 / (1.0 - u1);
    const double cos_h = 1.0 / std::sqrt(1.0 + tan2), sin_h = std::sqrt(tan2) * cos_h;
    const Dir3 h{sin_h * std::cos(phi), sin_h * std::sin(phi), cos_h};
    const double oh = dot(wo, h);
    return {2 * oh * h.x - wo.x, 2 * oh * h.y - wo.y, 2 * oh * h.z - wo.z};
  }
  const double r = std::sqrt(u1);
  return {r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0, 1.0 - u1))};
}

double GgxBrdf::pdf(const Dir3& wo, const Dir3& wi) const {
  if (wo.z <= 0 || wi.z <= 0) return 0;
  // Both above the horizon: h = normalize(wo + wi) is the one half vector
  // with h.z > 0 that reflects wo into wi, and wo.h > 0; the reflection's
  // Jacobian is 1 / (4 wo.h).
  const Dir3 h = normalized({wo.x + wi.x, wo.y + wi.y, wo.z + wi.z});
  const double p_ggx_dir =
      ggx_d(h.z, roughness * roughness) * h.z / (4.0 * std::max(dot(wo, h), 1e-300));
  return (1.0 - p_ggx()) * wi.z / kPi + p_ggx() * p_ggx_dir;
}

}  // namespace luxel::reference
