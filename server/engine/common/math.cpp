#include "common/math.h"

namespace luxel {

Mat4 operator*(const Mat4& a, const Mat4& b) {
  Mat4 r;
  for (int row = 0; row < 4; ++row)
    for (int col = 0; col < 4; ++col) {
      double s = 0;
      for (int k = 0; k < 4; ++k) s += a.at(row, k) * b.at(k, col);
      r.at(row, col) = s;
    }
  return r;
}

Vec3 transform_point(const Mat4& m, Vec3 p) {
  Vec3 r;
  for (int i = 0; i < 3; ++i)
    r[i] = static_cast<float>(m.at(i, 0) * p.x + m.at(i, 1) * p.y + m.at(i, 2) * p.z + m.at(i, 3));
  return r;
}

double transformed_triangle_area(const Mat4& m, Vec3 a, Vec3 b, Vec3 c) {
  auto p = [&](Vec3 v, int r) {
    return m.at(r, 0) * static_cast<double>(v.x) + m.at(r, 1) * static_cast<double>(v.y) +
           m.at(r, 2) * static_cast<double>(v.z) + m.at(r, 3);
  };
  double pa[3], pb[3], pc[3];
  for (int r = 0; r < 3; ++r) {
    pa[r] = p(a, r);
    pb[r] = p(b, r);
    pc[r] = p(c, r);
  }
  const double e1[3] = {pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]};
  const double e2[3] = {pc[0] - pa[0], pc[1] - pa[1], pc[2] - pa[2]};
  const double x = e1[1] * e2[2] - e1[2] * e2[1], y = e1[2] * e2[0] - e1[0] * e2[2],
               z = e1[0] * e2[1] - e1[1] * e2[0];
  return 0.5 * std::sqrt(x * x + y * y + z * z);
}

Vec3 transform_vector(const Mat4& m, Vec3 v) {
  Vec3 r;
  for (int i = 0; i < 3; ++i)
    r[i] = static_cast<float>(m.at(i, 0) * v.x + m.at(i, 1) * v.y + m.at(i, 2) * v.z);
  return r;
}

double determinant3x3(const Mat4& m) {
  return m.at(0, 0) * (m.at(1, 1) * m.at(2, 2) - m.at(1, 2) * m.at(2, 1)) -
         m.at(0, 1) * (m.at(1, 0) * m.at(2, 2) - m.at(1, 2) * m.at(2, 0)) +
         m.at(0, 2) * (m.at(1, 0) * m.at(2, 1) - m.at(1, 1) * m.at(2, 0));
}

float front_face_sign(const Mat4& m) {
  return determinant3x3(m) < 0 ? -1.0f : 1.0f;
}

Vec3 transform_normal(const Mat4& m, Vec3 n) {
  // Cofactor matrix = det * inverse-transpose; the scale drops out on
  // normalize and the cofactor form stays valid for singular (flattening)
  // transforms. The sign of det does not drop out: a mirroring transform
  // (det < 0) would turn every normal to the back face, so it is divided out.
  const double sign = front_face_sign(m);
  double c[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const int i1 = (i + 1) % 3, i2 = (i + 2) % 3, j1 = (j + 1) % 3, j2 = (j + 2) % 3;
      c[i][j] = m.at(i1, j1) * m.at(i2, j2) - m.at(i1, j2) * m.at(i2, j1);
    }
  Vec3 r;
  for (int i = 0; i < 3; ++i)
    r[i] = static_cast<float>(sign * (c[i][0] * n.x + c[i][1] * n.y + c[i][2] * n.z));
  return normalize(r);
}

Mat4 inverse(const Mat4& a) {
  // Gauss-Jordan with partial pivoting; affine inputs are well behaved.
  double m[4][8];
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) {
      m[r][c] = a.at(r, c);
      m[r][c + 4] = r == c ? 1.0 : 0.0;
    }
  for (int col = 0; col < 4; ++col) {
    int piv = col;
    for (int r = col + 1; r < 4; ++r)
      if (std::fabs(m[r][col]) > std::fabs(m[piv][col])) piv = r;
    if (piv != col)
      for (int c = 0; c < 8; ++c) std::swap(m[col][c], m[piv][c]);
    const double d = m[col][col];
    if (d == 0) return Mat4{};
    for (int c = 0; c < 8; ++c) m[col][c] /= d;
    for (int r = 0; r < 4; ++r)
      if (r != col) {
        const double f = m[r][col];
        for (int c = 0; c < 8; ++c) m[r][c] -= f * m[col][c];
      }
  }
  Mat4 out;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) out.at(r, c) = m[r][c + 4];
  return out;
}

Mat4 mat4_from_trs(const double t[3], const double q[4], const double s[3]) {
  const double x = q[0], y = q[1], z = q[2], w = q[3];
  Mat4 r;
  r.at(0, 0) = (1 - 2 * (y * y + z * z)) * s[0];
  r.at(1, 0) = (2 * (x * y + z * w)) * s[0];
  r.at(2, 0) = (2 * (x * z - y * w)) * s[0];
  r.at(0, 1) = (2 * (x * y - z * w)) * s[1];
  r.at(1, 1) = (1 - 2 * (x * x + z * z)) * s[1];
  r.at(2, 1) = (2 * (y * z + x * w)) * s[1];
  r.at(0, 2) = (2 * (x * z + y * w)) * s[2];
  r.at(1, 2) = (2 * (y * z - x * w)) * s[2];
  r.at(2, 2) = (1 - 2 * (x * x + y * y)) * s[2];
  r.at(0, 3) = t[0];
  r.at(1, 3) = t[1];
  r.at(2, 3) = t[2];
  return r;
}

}  // namespace luxel
