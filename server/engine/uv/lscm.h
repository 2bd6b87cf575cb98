// Least squares conformal maps (Lévy, Petitjean, Ray, Maillot 2002).
#pragma once

#include "uv/parametrize.h"

namespace luxel::uv {

// Fills chart.uv with the LSCM parametrization (§3.2: per triangle the
// discrete Cauchy-Riemann residual sum_j W_j U_j / sqrt(d_T), eq. 6-7, in its
// real form; two vertices pinned, §3.3, the pair extremal along the chart's
// longest bounding-box axis). The sparse least-squares problem is solved
// through its normal equations with a sparse Cholesky (LDL^T) factorisation.
// Positions are centred and scaled to unit extent first, so the solve is
// independent of the mesh's scale and offset. The map preserves the
// orientation of the 3D winding. Returns false when the factorisation fails or
// the solution is not finite (the caller splits the chart).
bool solve_lscm(LocalChart& chart);

}  // namespace luxel::uv
