// Deterministic ray sets for conformance tests and benchmarks.
//
//   coherent    primary-like rays: a cube map of pinhole cameras at the
//               scene's centre, rays in scanline order within 8x8 tiles
//   incoherent  diffuse-bounce-like rays: origins on surfaces (area-weighted
//               random triangles, robustly offset), cosine-distributed
//               directions about a random side of the geometric normal
//   random      origins uniform in the scene bounds, directions uniform on
//               the sphere (hits from inside and outside, grazing angles)
//   shadow      finite segments between two random surface points (any-hit)
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "accel/triangle_soup.h"
#include "kernels/shared/geometry.h"

namespace luxel::accel {

enum class RayKind { kCoherent, kIncoherent, kRandom, kShadow };

const char* ray_kind_name(RayKind kind);

std::vector<cl::LuxRay> make_rays(const TriangleSoup& soup, RayKind kind, size_t count,
                                  uint64_t seed);

}  // namespace luxel::accel
