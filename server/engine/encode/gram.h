// Gram matrices G_ij = integral over the domain of B_i B_j (thesis Eq. 7.3)
// and the quadrature used to compute them where no closed form exists.
#pragma once

#include <functional>
#include <vector>

#include "common/status.h"
#include "encode/basis.h"

namespace luxel::encode {

// Product Gauss-Legendre rule: n_z nodes in z = cos(theta) over [-1, 1]
// (sphere) or [0, 1] (hemisphere) times 2 n_z uniform azimuths. Exact for
// polynomials of degree < 2 n_z; weights sum to the domain's area.
struct SphereQuadrature {
  std::vector<Vec3> directions;
  std::vector<double> weights;
  static SphereQuadrature build(BasisDomain domain, int n_z);
};

// Row-major size() x size() matrices in double.
using GramMatrix = std::vector<double>;

// Closed forms: SH over the sphere -> identity (Eq. 8.1); SG over the sphere:
// integral of exp(l1 (w.p1 - 1)) exp(l2 (w.p2 - 1)) = 4 pi e^{-l1-l2}
// sinh|r| / |r|, r = l1 p1 + l2 p2. Anything else (hemisphere domains, Ambient
// Dice's clamped lobes) has no closed form here: InvalidArgument naming the basis.
Result<GramMatrix> gram_analytic(const SphericalBasis& basis);

// Quadrature over spec().fit_domain with the given rule resolution.
GramMatrix gram_numeric(const SphericalBasis& basis, int n_z = 128);

// Analytic when available, numeric otherwise.
GramMatrix gram(const SphericalBasis& basis);

// Raw moments m_i = integral over fit_domain of f B_i (right side of Eq. 7.3).
std::vector<double> project(const SphericalBasis& basis, const std::function<double(Vec3)>& f,
                            int n_z = 128);

// Solves G x = rhs for symmetric positive definite G by Cholesky (double).
Result<std::vector<double>> solve_spd(const GramMatrix& g, std::vector<double> rhs);

// Least-squares coefficients of f over fit_domain: G^-1 m (Eq. 7.3).
Result<std::vector<float>> fit_least_squares(const SphericalBasis& basis,
                                             const std::function<double(Vec3)>& f, int n_z = 128);

}  // namespace luxel::encode
