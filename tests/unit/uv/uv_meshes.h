// Meshes built in code for the uv/ tests: closed surfaces, hard edges,
// material boundaries, thin walls and broken input.
#pragma once

#include <cstdint>
#include <functional>

#include "common/math.h"
#include "scene/scene.h"

namespace luxel::uv::testing {

uint32_t add_vertex(scene::Mesh& m, Vec3 p, Vec3 n);
void add_triangle(scene::Mesh& m, uint32_t a, uint32_t b, uint32_t c, int32_t material = 0);
// A flat-shaded quad with its own four vertices (a, b, c, d counter-clockwise
// seen from the side its normal points to).
void add_flat_quad(scene::Mesh& m, Vec3 a, Vec3 b, Vec3 c, Vec3 d, int32_t material = 0);

// Smooth UV sphere: one vertex per pole, `rings` x `segments`.
scene::Mesh sphere(float radius, int rings, int segments);
// Smooth torus, shared vertices (closed in both directions).
scene::Mesh torus(float major, float minor, int rings, int segments);
// Smooth cylinder side (shared vertices, outward normals) and flat caps with
// their own vertices: the rims are hard edges in the file.
scene::Mesh capped_cylinder(float radius, float height, int segments, int stacks);
// Box of flat quads (per-face vertices: every edge a hard edge).
scene::Mesh box(Vec3 size);
// L-shaped wall: two legs `length` long, `thickness` thick, `height` tall,
// built from flat quads with each leg's long faces cut into `pieces` quads.
scene::Mesh l_wall(float length, float thickness, float height, int pieces);
// n x n grid of unit quads in the z = 0 plane, shared vertices.
scene::Mesh grid(int n);
// Every position multiplied by s.
scene::Mesh scaled(scene::Mesh m, float s);
// Sum of the 3D areas of the given triangles (double).
double triangle_area(const scene::Mesh& m, uint32_t t);

}  // namespace luxel::uv::testing
