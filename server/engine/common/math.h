// Small host-side vector/matrix types. Device-facing layouts live in
// kernels/shared/; these are for import, validation and BVH construction.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>

namespace luxel {

struct Vec2 {
  float x = 0, y = 0;
};

struct Vec3 {
  float x = 0, y = 0, z = 0;
  float& operator[](int i) { return (&x)[i]; }
  float operator[](int i) const { return (&x)[i]; }
};

struct Vec4 {
  float x = 0, y = 0, z = 0, w = 0;
};

inline Vec3 operator+(Vec3 a, Vec3 b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
inline Vec3 operator-(Vec3 a, Vec3 b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
inline Vec3 operator*(Vec3 a, float s) {
  return {a.x * s, a.y * s, a.z * s};
}
inline Vec3 operator*(float s, Vec3 a) {
  return a * s;
}
inline float dot(Vec3 a, Vec3 b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
inline Vec3 cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float length(Vec3 a) {
  return std::sqrt(dot(a, a));
}
inline Vec3 normalize(Vec3 a) {
  const float l = length(a);
  return l > 0 ? a * (1.0f / l) : Vec3{0, 0, 1};
}
inline Vec3 vmin(Vec3 a, Vec3 b) {
  return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
}
inline Vec3 vmax(Vec3 a, Vec3 b) {
  return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
}
inline bool is_finite(Vec3 a) {
  return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}

struct Bounds3 {
  Vec3 lo{INFINITY, INFINITY, INFINITY};
  Vec3 hi{-INFINITY, -INFINITY, -INFINITY};
  void extend(Vec3 p) {
    lo = vmin(lo, p);
    hi = vmax(hi, p);
  }
  void extend(const Bounds3& b) {
    lo = vmin(lo, b.lo);
    hi = vmax(hi, b.hi);
  }
  bool empty() const { return lo.x > hi.x; }
  Vec3 extent() const { return hi - lo; }
};

// Column-major 4x4 affine transform in double (composition of deep node
// hierarchies at large coordinates loses less precision in double).
struct Mat4 {
  std::array<double, 16> m{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  double& at(int row, int col) { return m[static_cast<size_t>(col * 4 + row)]; }
  double at(int row, int col) const { return m[static_cast<size_t>(col * 4 + row)]; }
};

Mat4 operator*(const Mat4& a, const Mat4& b);
Vec3 transform_point(const Mat4& m, Vec3 p);
// Normals transform by the inverse transpose (so they stay on the front face
// under a mirroring transform too); returns a normalized vector.
Vec3 transform_normal(const Mat4& m, Vec3 n);
Vec3 transform_vector(const Mat4& m, Vec3 v);
// The area of the object-space triangle a, b, c once m transforms it (an
// instance's triangle in world space), computed in double throughout.
double transformed_triangle_area(const Mat4& m, Vec3 a, Vec3 b, Vec3 c);
Mat4 inverse(const Mat4& m);
double determinant3x3(const Mat4& m);
// The winding rule of instances (glTF 2.0 §3.7.4): the front face of a
// triangle is counter-clockwise in object space, and a node transform whose
// 3x3 part has a negative determinant (a mirroring one) makes it the
// clockwise face in world space. Returns the sign that turns the world
// winding normal cross(v1 - v0, v2 - v0) into the front normal: +1, or -1
// under a mirroring transform. Everything that needs a triangle's front side
// (vertex normals, emitter sides, bitangent signs) follows this one rule.
float front_face_sign(const Mat4& m);
// glTF TRS: translation, rotation quaternion (x, y, z, w), scale.
Mat4 mat4_from_trs(const double t[3], const double q[4], const double s[3]);

}  // namespace luxel
