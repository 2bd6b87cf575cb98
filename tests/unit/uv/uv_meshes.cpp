#include "uv_meshes.h"

#include <cmath>
#include <numbers>

namespace luxel::uv::testing {

constexpr float kPi = std::numbers::pi_v<float>;

uint32_t add_vertex(scene::Mesh& m, Vec3 p, Vec3 n) {
  m.positions.push_back(p);
  m.normals.push_back(normalize(n));
  m.uv0.push_back({});
  m.uv1.push_back({});
  return static_cast<uint32_t>(m.positions.size() - 1);
}

void add_triangle(scene::Mesh& m, uint32_t a, uint32_t b, uint32_t c, int32_t material) {
  m.indices.insert(m.indices.end(), {a, b, c});
  m.triangle_material.push_back(material);
}

void add_flat_quad(scene::Mesh& m, Vec3 a, Vec3 b, Vec3 c, Vec3 d, int32_t material) {
  const Vec3 n = normalize(cross(b - a, c - a));
  const uint32_t i = add_vertex(m, a, n), j = add_vertex(m, b, n), k = add_vertex(m, c, n),
                 l = add_vertex(m, d, n);
  add_triangle(m, i, j, k, material);
  add_triangle(m, i, k, l, material);
}

scene::Mesh sphere(float radius, int rings, int segments) {
  scene::Mesh m;
  m.name = "sphere";
  const uint32_t north = add_vertex(m, {0, 0, radius}, {0, 0, 1});
  for (int r = 1; r < rings; ++r) {
    const float th = kPi * float(r) / float(rings);
    for (int s = 0; s < segments; ++s) {
      const float ph = 2 * kPi * float(s) / float(segments);
      const Vec3 n{std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)};
      add_vertex(m, n * radius, n);
    }
  }
  const uint32_t south = add_vertex(m, {0, 0, -radius}, {0, 0, -1});
  auto ring = [&](int r, int s) { return 1 + uint32_t((r - 1) * segments + (s % segments)); };
  for (int s = 0; s < segments; ++s) {
    add_triangle(m, north, ring(1, s), ring(1, s + 1));
    add_triangle(m, south, ring(rings - 1, s + 1), ring(rings - 1, s));
  }
  for (int r = 1; r + 1 < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      add_triangle(m, ring(r, s), ring(r + 1, s), ring(r + 1, s + 1));
      add_triangle(m, ring(r, s), ring(r + 1, s + 1), ring(r, s + 1));
    }
  return m;
}

scene::Mesh torus(float major, float minor, int rings, int segments) {
  scene::Mesh m;
  m.name = "torus";
  for (int i = 0; i < rings; ++i) {
    const float a = 2 * kPi * float(i) / float(rings);
    for (int j = 0; j < segments; ++j) {
      const float b = 2 * kPi * float(j) / float(segments);
      const Vec3 n{std::cos(b) * std::cos(a), std::cos(b) * std::sin(a), std::sin(b)};
      const Vec3 c{major * std::cos(a), major * std::sin(a), 0};
      add_vertex(m, c + n * minor, n);
    }
  }
  auto v = [&](int i, int j) { return uint32_t((i % rings) * segments + (j % segments)); };
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      add_triangle(m, v(i, j), v(i + 1, j), v(i + 1, j + 1));
      add_triangle(m, v(i, j), v(i + 1, j + 1), v(i, j + 1));
    }
  return m;
}

scene::Mesh capped_cylinder(float radius, float height, int segments, int stacks) {
  scene::Mesh m;
  m.name = "cylinder";
  auto rim = [&](int s) {
    const float ph = 2 * kPi * float(s % segments) / float(segments);
    return Vec3{std::cos(ph), std::sin(ph), 0};
  };
  const uint32_t base = static_cast<uint32_t>(m.positions.size());
  for (int k = 0; k <= stacks; ++k)
    for (int s = 0; s < segments; ++s)
      add_vertex(m, rim(s) * radius + Vec3{0, 0, height * float(k) / float(stacks)}, rim(s));
  auto v = [&](int k, int s) { return base + uint32_t(k * segments + s % segments); };
  for (int k = 0; k < stacks; ++k)
    for (int s = 0; s < segments; ++s) {
      add_triangle(m, v(k, s), v(k, s + 1), v(k + 1, s + 1));
      add_triangle(m, v(k, s), v(k + 1, s + 1), v(k + 1, s));
    }
  // Caps: fans with their own vertices and the cap normal.
  for (int top = 0; top < 2; ++top) {
    const Vec3 n{0, 0, top ? 1.0f : -1.0f};
    const Vec3 z{0, 0, top ? height : 0.0f};
    const uint32_t centre = add_vertex(m, z, n);
    const uint32_t first = static_cast<uint32_t>(m.positions.size());
    for (int s = 0; s < segments; ++s) add_vertex(m, rim(s) * radius + z, n);
    for (int s = 0; s < segments; ++s) {
      const uint32_t a = first + uint32_t(s), b = first + uint32_t((s + 1) % segments);
      if (top)
        add_triangle(m, centre, a, b);
      else
        add_triangle(m, centre, b, a);
    }
  }
  return m;
}

scene::Mesh box(Vec3 e) {
  scene::Mesh m;
  m.name = "box";
  const Vec3 p[8] = {{0, 0, 0},   {e.x, 0, 0},   {e.x, e.y, 0},   {0, e.y, 0},
                     {0, 0, e.z}, {e.x, 0, e.z}, {e.x, e.y, e.z}, {0, e.y, e.z}};
  add_flat_quad(m, p[0], p[3], p[2], p[1]);  // -z
  add_flat_quad(m, p[4], p[5], p[6], p[7]);  // +z
  add_flat_quad(m, p[0], p[1], p[5], p[4]);  // -y
  add_flat_quad(m, p[2], p[3], p[7], p[6]);  // +y
  add_flat_quad(m, p[1], p[2], p[6], p[5]);  // +x
  add_flat_quad(m, p[3], p[0], p[4], p[7]);  // -x
  return m;
}

scene::Mesh l_wall(float len, float th, float h, int pieces) {
  scene::Mesh m;
  m.name = "l_wall";
  // Footprint (counter-clockwise from above): an L of two legs along +x and +y.
  const Vec3 f[6] = {{0, 0, 0}, {len, 0, 0}, {len, th, 0}, {th, th, 0}, {th, len, 0}, {0, len, 0}};
  const Vec3 up{0, 0, h};
  for (int i = 0; i < 6; ++i) {
    const Vec3 a = f[i], b = f[(i + 1) % 6];
    const int n = (length(b - a) > 2 * th) ? pieces : 1;
    for (int k = 0; k < n; ++k) {
      const Vec3 p = a + (b - a) * (float(k) / float(n)),
                 q = a + (b - a) * (float(k + 1) / float(n));
      add_flat_quad(m, p, q, q + up, p + up);
    }
  }
  // Top and bottom: the L as two quads each.
  add_flat_quad(m, f[0] + up, f[1] + up, f[2] + up, Vec3{0, th, h});
  add_flat_quad(m, Vec3{0, th, h}, f[3] + up, f[4] + up, f[5] + up);
  add_flat_quad(m, f[0], Vec3{0, th, 0}, f[2], f[1]);
  add_flat_quad(m, Vec3{0, th, 0}, f[5], f[4], f[3]);
  return m;
}

scene::Mesh grid(int n) {
  scene::Mesh m;
  m.name = "grid";
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) add_vertex(m, {float(i), float(j), 0}, {0, 0, 1});
  auto v = [&](int i, int j) { return uint32_t(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      add_triangle(m, v(i, j), v(i + 1, j), v(i + 1, j + 1));
      add_triangle(m, v(i, j), v(i + 1, j + 1), v(i, j + 1));
    }
  return m;
}

scene::Mesh scaled(scene::Mesh m, float s) {
  for (Vec3& p : m.positions) p = p * s;
  return m;
}

double triangle_area(const scene::Mesh& m, uint32_t t) {
  auto d = [&](int k) {
    const Vec3 p = m.positions[m.indices[3 * t + k]];
    return std::array<double, 3>{p.x, p.y, p.z};
  };
  const auto a = d(0), b = d(1), c = d(2);
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double x = u[1] * w[2] - u[2] * w[1], y = u[2] * w[0] - u[0] * w[2],
               z = u[0] * w[1] - u[1] * w[0];
  return 0.5 * std::sqrt(x * x + y * y + z * z);
}

}  // namespace luxel::uv::testing
