// glTF mesh -> scene::Mesh: reads the triangle primitives of one glTF mesh,
// validates them, drops degenerate triangles and generates missing normals
// (and missing tangents where a material has a normal map).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/status.h"
#include "scene/gltf_import.h"
#include "scene/import_budget.h"
#include "scene/scene.h"
#include "scene/tinygltf_config.h"

namespace luxel::scene::detail {

// "mesh 'floor' (mesh[2])", or "mesh[2]" for an unnamed mesh.
std::string mesh_label(const tinygltf::Model& model, int mesh_index);

// The triangle list of a primitive of mode TRIANGLES (4), TRIANGLE_STRIP (5)
// or TRIANGLE_FAN (6) from its index list (or 0..n-1 when it has none).
// Mesh::source_triangle counts triangles of this list.
std::vector<uint32_t> to_triangle_list(int mode, const std::vector<uint32_t>& indices);

// Builds the mesh. Primitives without a material get the glTF default
// material, appended to scene->materials on first use. Each primitive's
// arrays are reserved in `budget` from the declared POSITION and index counts
// before any is read (scene/import_budget.h).
Result<Mesh> build_mesh(const tinygltf::Model& model, int mesh_index, const ImportOptions& options,
                        ImportBudget* budget, Scene* scene);

}  // namespace luxel::scene::detail
