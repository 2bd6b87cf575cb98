// Whether a direction survives normalisation in single precision on every
// thread. Its squared length must be a finite, normal float: an infinite
// length normalises to zero, and a denormal one (a direction of about
// 1e-20 or less) is 0 on a thread that flushes denormals to zero, as
// Embree's do, so a check on one thread would pass what the bake on
// another refuses. The settings check (settings.sun.direction) and the
// light table (shading/punctual_lights.cpp) share this one rule.
#pragma once

#include <cmath>
#include <limits>

#include "common/math.h"

namespace luxel {

inline bool normalizable(Vec3 v) {
  const float d = dot(v, v);
  return is_finite(v) && std::isfinite(d) && d >= std::numeric_limits<float>::min();
}

}  // namespace luxel
