// KHR_lights_punctual: a node that references a light places it in the world.
#pragma once

#include <string>

#include "common/math.h"
#include "common/status.h"
#include "scene/scene.h"
#include "scene/tinygltf_config.h"

namespace luxel::scene::detail {

// If node `node` references a KHR_lights_punctual light, appends it to
// scene->lights with its world position (the node's origin) and direction
// (the node's -Z axis). `node_label` names the node in messages.
Status convert_node_light(const tinygltf::Model& model, int node, const std::string& node_label,
                          const Mat4& world, Scene* scene);

}  // namespace luxel::scene::detail
