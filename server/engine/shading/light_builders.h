// Internal to build_light_table: one builder per kind of light. Each appends
// candidates (a LuxLight and its selection power); light_table.cpp drops the
// powerless ones and builds the selection CDF.
#pragma once

#include <string>
#include <vector>

#include "accel/triangle_soup.h"
#include "common/status.h"
#include "kernels/shared/light.h"
#include "scene/scene.h"
#include "shading/light_settings.h"

namespace luxel::pipeline::detail {

struct LightCandidate {
  cl::LuxLight light{};
  double power = 0;
};

inline void set_type(cl::LuxLight* l, int type) {
  l->origin.w = lux_as_float(static_cast<int32_t>(type));
}
inline int type_of(const cl::LuxLight& l) {
  return LUX_LIGHT_TYPE(l);
}

// Scene KHR_lights_punctual lights. disc_area: pi r^2 of the scene's bounding
// sphere (directional power).
Status add_punctual_lights(const scene::Scene& scene, float directional_angular_radius_degrees,
                           double disc_area, std::vector<LightCandidate>* out);

// The settings sun (nothing when disabled).
Status add_sun(const SunSettings& sun, double disc_area, std::vector<LightCandidate>* out);

// Every world triangle with an emissive material.
Status add_emissive_triangles(const scene::Scene& scene, const accel::TriangleSoup& soup,
                              std::vector<LightCandidate>* out);

// The sky and its importance-sampling distribution.
struct SkyData {
  cl::LuxSky sky{};
  std::vector<float> texels, block_cdfs, texel_cdfs;  // shading/sky_distribution.h
  double mean_luminance = 0;                          // over the sphere (solid-angle weighted)
  Vec3 mean_radiance;
};
Result<SkyData> load_sky(const SkySettings& settings);

// Shared validation: "<what>: <field> ..." errors.
Status check_color(const std::string& what, const char* field, Vec3 c);
Status check_nonnegative(const std::string& what, const char* field, double v);

}  // namespace luxel::pipeline::detail
