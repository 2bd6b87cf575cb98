// Per-vertex tangent frames for normal maps when a primitive has no TANGENT
// attribute (glTF 2.0 §3.7.2.1: "When tangents are not specified, client
// implementations SHOULD calculate tangents using default MikkTSpace
// algorithms with the specified vertex positions, normals, and texture
// coordinates associated with the normal texture").
//
// Debian packages no MikkTSpace library, so this is the per-triangle UV
// gradient method (Lengyel, "Computing Tangent Space Basis Vectors for an
// Arbitrary Mesh", 2001) that MikkTSpace refines: per triangle, dP/du and
// dP/dv from the edge and UV differences; summed per vertex; the tangent is
// the dP/du sum Gram-Schmidt orthogonalised against the vertex normal.
// Deviations from MikkTSpace (docs/accuracy.md "Normal maps"): triangles are
// weighted by their UV-space determinant (area) rather than by corner angle,
// and vertices are not split where the UV orientation flips (a vertex shared
// by a mirrored and an unmirrored triangle gets the average, like any
// per-vertex accumulation). On flat, consistently mapped surfaces (the
// common case and every test scene) both give the same frame.
#pragma once

#include <cstdint>
#include <vector>

#include "common/math.h"

namespace luxel::scene {

// Tangents for every vertex of `positions` (parallel `normals`, `uvs`) from
// the triangles of `indices` (3 per triangle): xyz = unit tangent along +u
// orthogonal to the normal, w = +1 or -1 so that cross(normal, tangent) * w
// points along -v. glTF UVs have v pointing down the image while a normal
// map's +Y is up (glTF 2.0 §3.9.3: "+Y is up"), so an unmirrored mapping gets
// w = +1, as MikkTSpace gives on the V-flipped UVs of DCC tools. A vertex
// without a usable triangle (degenerate UVs) gets an arbitrary tangent
// orthogonal to its normal and w = +1.
std::vector<Vec4> generate_tangents(const std::vector<Vec3>& positions,
                                    const std::vector<Vec3>& normals, const std::vector<Vec2>& uvs,
                                    const std::vector<uint32_t>& indices);

}  // namespace luxel::scene
