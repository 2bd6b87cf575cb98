// build_light_table: gathers the lights, drops the powerless ones and builds
// the selection alias table by power (thesis §6.3.2).
#include "shading/light_table.h"

#include <cmath>

#include "shading/cdf.h"
#include "shading/light_builders.h"

namespace luxel::pipeline {
namespace {

constexpr double kPi = 3.14159265358979323846;

// pi r^2 of the scene's bounding sphere: the cross-section through which a
// directional light or the sky delivers power to the scene.
double bounding_disc_area(const Bounds3& b) {
  double r = b.empty() ? 0.0 : 0.5 * length(b.extent());
  if (!(std::isfinite(r) && r > 0)) r = 1.0;
  return kPi * r * r;
}

}  // namespace

size_t LightTable::bytes() const {
  return lights.size() * sizeof(cl::LuxLight) + select.size() * sizeof(cl::LuxAliasEntry) +
         triangle_light.size() * sizeof(int32_t) + sizeof(cl::LuxSky) +
         (sky_texels.size() + sky_block_cdfs.size() + sky_texel_cdfs.size()) * sizeof(float);
}

Result<LightTable> build_light_table(const scene::Scene& scene, const accel::TriangleSoup& soup,
                                     const LightSettings& settings, const Bounds3& scene_bounds) {
  const double disc_area = bounding_disc_area(scene_bounds);
  std::vector<detail::LightCandidate> candidates;
  LUXEL_RETURN_IF_ERROR(detail::add_punctual_lights(
      scene, settings.directional_angular_radius_degrees, disc_area, &candidates));
  LUXEL_RETURN_IF_ERROR(detail::add_sun(settings.sun, disc_area, &candidates));
  LUXEL_RETURN_IF_ERROR(detail::add_emissive_triangles(scene, soup, &candidates));
  auto sky = detail::load_sky(settings.sky);
  if (!sky) return sky.status();
  if (sky->sky.kind != LUX_SKY_KIND_NONE) {
    detail::LightCandidate c;
    detail::set_type(&c.light, LUX_LIGHT_TYPE_SKY);
    c.light.emission = {sky->mean_radiance.x, sky->mean_radiance.y, sky->mean_radiance.z, 0};
    c.power = kPi * sky->mean_luminance * disc_area;
    candidates.push_back(c);
  }

  LightTable table;
  table.triangle_light.assign(soup.size(), -1);
  std::vector<double> powers;
  for (const detail::LightCandidate& c : candidates) {
    // A light that can never be chosen is left out rather than kept with
    // probability 0: the kernels then need no code for it.
    if (!(c.power > 0 && std::isfinite(c.power))) {
      ++table.dropped_zero_power;
      continue;
    }
    const int index = static_cast<int>(table.lights.size());
    switch (detail::type_of(c.light)) {
      case LUX_LIGHT_TYPE_POINT:
        table.has_point = true;
        break;
      case LUX_LIGHT_TYPE_SPOT:
        table.has_spot = true;
        break;
      case LUX_LIGHT_TYPE_DIRECTIONAL:
        table.has_directional = true;
        break;
      case LUX_LIGHT_TYPE_TRIANGLE:
        table.has_emissive = true;
        table.triangle_light[static_cast<size_t>(LUX_LIGHT_TRIANGLE(c.light))] = index;
        break;
      case LUX_LIGHT_TYPE_SKY:
        table.has_sky = true;
        table.sky_is_image = sky->sky.kind == LUX_SKY_KIND_IMAGE;
        sky->sky.light = index;
        break;
      default:
        LUXEL_CHECK_MSG(false, "unknown light type");
    }
    table.lights.push_back(c.light);
    powers.push_back(c.power);
    table.total_power += c.power;
  }
  if (!powers.empty()) table.select = build_alias_table(powers);
  if (table.has_sky) {
    table.sky = sky->sky;
    table.sky_texels = std::move(sky->texels);
    table.sky_block_cdfs = std::move(sky->block_cdfs);
    table.sky_texel_cdfs = std::move(sky->texel_cdfs);
  } else {
    table.sky = cl::LuxSky{};
    table.sky.kind = LUX_SKY_KIND_NONE;
    table.sky.light = -1;
    table.sky.rotation = {0, 1, 0, 0};
  }
  return table;
}

void add_light_features(const LightTable& table, device::FeatureSet* features) {
  using device::Feature;
  if (table.has_point) features->set(Feature::LIGHT_POINT);
  if (table.has_spot) features->set(Feature::LIGHT_SPOT);
  if (table.has_directional) features->set(Feature::LIGHT_DIRECTIONAL);
  if (table.has_emissive) features->set(Feature::LIGHT_EMISSIVE);
  if (table.has_sky) features->set(table.sky_is_image ? Feature::SKY_IMAGE : Feature::SKY);
}

}  // namespace luxel::pipeline
