// See lights.h. Units are the extension's (candela for point and spot, lux for
// directional) and are not converted here.
#include "scene/lights.h"

#include <cmath>

namespace luxel::scene::detail {
namespace {

constexpr double kHalfPi = 1.57079632679489661923;

bool finite_nonneg(double v) {
  return std::isfinite(v) && v >= 0;
}

}  // namespace

Status convert_node_light(const tinygltf::Model& model, int node, const std::string& node_label,
                          const Mat4& world, Scene* scene) {
  const auto& n = model.nodes[static_cast<size_t>(node)];
  auto ext = n.extensions.find("KHR_lights_punctual");
  if (ext == n.extensions.end()) return Status::ok();
  if (!ext->second.IsObject() || !ext->second.Has("light") || !ext->second.Get("light").IsInt()) {
    return invalid_argument(node_label + ": KHR_lights_punctual has no integer 'light'");
  }
  const int index = ext->second.Get("light").GetNumberAsInt();
  if (index < 0 || static_cast<size_t>(index) >= model.lights.size()) {
    return invalid_argument(strprintf("%s: light %d does not exist (%zu lights)",
                                      node_label.c_str(), index, model.lights.size()));
  }
  const auto& gl = model.lights[static_cast<size_t>(index)];
  const std::string label = gl.name.empty() ? strprintf("light %d", index)
                                            : strprintf("light %d '%s'", index, gl.name.c_str());
  Light light;
  light.name = gl.name.empty() ? strprintf("light[%d]", index) : gl.name;
  light.node_index = node;
  if (gl.type == "point") {
    light.type = LightType::kPoint;
  } else if (gl.type == "spot") {
    light.type = LightType::kSpot;
  } else if (gl.type == "directional") {
    light.type = LightType::kDirectional;
  } else {
    return invalid_argument(strprintf("%s (on %s): type '%s' is not point, spot or directional",
                                      label.c_str(), node_label.c_str(), gl.type.c_str()));
  }
  if (!gl.color.empty()) {
    if (gl.color.size() != 3 || !finite_nonneg(gl.color[0]) || !finite_nonneg(gl.color[1]) ||
        !finite_nonneg(gl.color[2])) {
      return invalid_argument(label + ": color must be 3 finite non-negative numbers");
    }
    light.color = {static_cast<float>(gl.color[0]), static_cast<float>(gl.color[1]),
                   static_cast<float>(gl.color[2])};
  }
  if (!finite_nonneg(gl.intensity) || gl.intensity > 3.0e38) {
    return invalid_argument(
        strprintf("%s: intensity %g must be finite and non-negative", label.c_str(), gl.intensity));
  }
  light.intensity = static_cast<float>(gl.intensity);
  if (!finite_nonneg(gl.range) || gl.range > 3.0e38) {
    return invalid_argument(
        strprintf("%s: range %g must be finite and positive", label.c_str(), gl.range));
  }
  light.range = static_cast<float>(gl.range);
  if (light.type == LightType::kSpot) {
    const double inner = gl.spot.innerConeAngle, outer = gl.spot.outerConeAngle;
    if (!(inner >= 0 && inner < outer && outer <= kHalfPi)) {
      return invalid_argument(
          strprintf("%s: spot cone angles inner %g, outer %g must satisfy 0 <= inner < outer "
                    "<= pi/2",
                    label.c_str(), inner, outer));
    }
    light.inner_cone_angle = static_cast<float>(inner);
    light.outer_cone_angle = static_cast<float>(outer);
  }
  light.position = transform_point(world, Vec3{0, 0, 0});
  const Vec3 dir = transform_vector(world, Vec3{0, 0, -1});
  if (!is_finite(light.position) || !is_finite(dir) || !(length(dir) > 0)) {
    return invalid_argument(
        strprintf("%s (on %s): the node transform gives no valid position/direction", label.c_str(),
                  node_label.c_str()));
  }
  light.direction = normalize(dir);
  scene->lights.push_back(light);
  return Status::ok();
}

}  // namespace luxel::scene::detail
