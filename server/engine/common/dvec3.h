// Double-precision 3-vectors for host-side precomputation (sampling tables,
// angular bounds, generated lookup tables), where float's 24 bits are not
// enough to integrate or bound safely. Device data stays in common/math.h's
// float Vec3.
#pragma once

#include <algorithm>
#include <cmath>

namespace luxel {

struct DVec3 {
  double x = 0, y = 0, z = 0;
};

inline DVec3 operator+(DVec3 a, DVec3 b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
inline DVec3 operator-(DVec3 a, DVec3 b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
inline DVec3 operator*(DVec3 a, double s) {
  return {a.x * s, a.y * s, a.z * s};
}
inline double dot(DVec3 a, DVec3 b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
inline DVec3 cross(DVec3 a, DVec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline DVec3 normalize(DVec3 a) {
  return a * (1.0 / std::sqrt(dot(a, a)));
}
// Angle between two unit vectors, in radians.
inline double angle_between(DVec3 a, DVec3 b) {
  return std::acos(std::clamp(dot(a, b), -1.0, 1.0));
}

}  // namespace luxel
