// KHR_lights_punctual lights and the settings sun as LuxLight records.
// glTF intensities are used 1:1 as radiometric quantities (light.h: UNITS).
#include <cmath>

#include "common/direction.h"
#include "shading/color.h"
#include "shading/light_builders.h"

namespace luxel::pipeline::detail {
namespace {

constexpr double kPi = 3.14159265358979323846;

cl::float4 f4(Vec3 v, float w = 0) {
  return {v.x, v.y, v.z, w};
}

// A directional light of irradiance E (rgb, facing the light). With an
// angular radius a > 0 it becomes a disc of uniform radiance
// L = E / (pi sin^2 a), so that the irradiance it gives a surface facing it,
// pi L sin^2 a, is still E. 1 - cos a is computed in double: for the sun
// (a ~ 0.27 deg) the float cos would lose most of its digits.
Status directional_candidate(const std::string& what, Vec3 direction, Vec3 irradiance,
                             float angular_radius_degrees, double disc_area, LightCandidate* c) {
  // The sun is a setting (settings.sun.*, checked by the same rule at
  // submit); other directional lights come from the scene file.
  const bool setting = what.rfind("settings.", 0) == 0;
  const std::string direction_field = setting ? what + ".direction: " : what + ": direction ";
  if (!normalizable(direction))
    return invalid_argument(
        strprintf("%s(%g, %g, %g) does not survive normalisation in single precision (finite, "
                  "squared length a normal float)",
                  direction_field.c_str(), static_cast<double>(direction.x),
                  static_cast<double>(direction.y), static_cast<double>(direction.z)));
  if (!(angular_radius_degrees >= 0 && angular_radius_degrees < kMaxAngularRadiusDegrees))
    return invalid_argument(strprintf("%s: angular radius %g degrees must be in [0, %g)",
                                      what.c_str(), static_cast<double>(angular_radius_degrees),
                                      static_cast<double>(kMaxAngularRadiusDegrees)));
  set_type(&c->light, LUX_LIGHT_TYPE_DIRECTIONAL);
  c->light.axis = f4(normalize(direction), c->light.axis.w);
  Vec3 radiance = irradiance;
  if (angular_radius_degrees > 0) {
    const double a = angular_radius_degrees * kPi / 180.0;
    const double one_minus_cos = 2.0 * std::sin(a / 2) * std::sin(a / 2);
    const double sin2 = std::sin(a) * std::sin(a);
    radiance = irradiance * static_cast<float>(1.0 / (kPi * sin2));
    LUX_LIGHT_ONE_MINUS_COS(c->light) = static_cast<float>(one_minus_cos);
  }
  if (!is_finite(radiance)) return invalid_argument(what + ": radiance overflows a float");
  c->light.emission = f4(radiance);
  c->power = luminance(irradiance) * disc_area;
  return Status::ok();
}

std::string light_label(const scene::Light& l, size_t index) {
  return strprintf("light %zu '%s'", index, l.name.c_str());
}

}  // namespace

Status check_color(const std::string& what, const char* field, Vec3 c) {
  if (!is_finite(c) || c.x < 0 || c.y < 0 || c.z < 0)
    return invalid_argument(strprintf("%s: %s (%g, %g, %g) must be finite and non-negative",
                                      what.c_str(), field, static_cast<double>(c.x),
                                      static_cast<double>(c.y), static_cast<double>(c.z)));
  return Status::ok();
}

Status check_nonnegative(const std::string& what, const char* field, double v) {
  if (!std::isfinite(v) || v < 0)
    return invalid_argument(
        strprintf("%s: %s %g must be finite and non-negative", what.c_str(), field, v));
  return Status::ok();
}

Status add_punctual_lights(const scene::Scene& scene, float directional_angular_radius_degrees,
                           double disc_area, std::vector<LightCandidate>* out) {
  for (size_t i = 0; i < scene.lights.size(); ++i) {
    const scene::Light& l = scene.lights[i];
    const std::string what = light_label(l, i);
    LUXEL_RETURN_IF_ERROR(check_color(what, "color", l.color));
    LUXEL_RETURN_IF_ERROR(check_nonnegative(what, "intensity", l.intensity));
    const Vec3 value = l.color * l.intensity;  // W/sr (point, spot) or W/m^2 (directional)
    if (!is_finite(value)) return invalid_argument(what + ": color * intensity overflows a float");
    LightCandidate c;
    if (l.type == scene::LightType::kDirectional) {
      LUXEL_RETURN_IF_ERROR(directional_candidate(
          what, l.direction, value, directional_angular_radius_degrees, disc_area, &c));
      out->push_back(c);
      continue;
    }
    if (!is_finite(l.position)) return invalid_argument(what + ": position is not finite");
    c.light.origin = f4(l.position);
    c.light.emission = f4(value);
    if (l.type == scene::LightType::kPoint) {
      set_type(&c.light, LUX_LIGHT_TYPE_POINT);
      c.power = 4 * kPi * luminance(value);
    } else {
      if (!is_finite(l.direction) || !(length(l.direction) > 0))
        return invalid_argument(what + ": direction must be finite and non-zero");
      const double inner = l.inner_cone_angle, outer = l.outer_cone_angle;
      if (!(inner >= 0 && inner <= outer && outer <= kPi / 2))
        return invalid_argument(
            strprintf("%s: spot cone angles inner %g, outer %g must satisfy "
                      "0 <= inner <= outer <= pi/2",
                      what.c_str(), inner, outer));
      set_type(&c.light, LUX_LIGHT_TYPE_SPOT);
      c.light.axis = f4(normalize(l.direction), c.light.axis.w);
      LUX_LIGHT_COS_INNER(c.light) = static_cast<float>(std::cos(inner));
      LUX_LIGHT_COS_OUTER(c.light) = static_cast<float>(std::cos(outer));
      c.power = 2 * kPi * (1 - std::cos((inner + outer) / 2)) * luminance(value);
    }
    out->push_back(c);
  }
  return Status::ok();
}

Status add_sun(const SunSettings& sun, double disc_area, std::vector<LightCandidate>* out) {
  if (!sun.enabled) return Status::ok();
  LUXEL_RETURN_IF_ERROR(check_color("settings.sun", "color", sun.color));
  LUXEL_RETURN_IF_ERROR(check_nonnegative("settings.sun", "illuminance", sun.illuminance));
  LightCandidate c;
  LUXEL_RETURN_IF_ERROR(directional_candidate("settings.sun", sun.direction,
                                              sun.color * sun.illuminance,
                                              sun.angular_radius_degrees, disc_area, &c));
  out->push_back(c);
  return Status::ok();
}

}  // namespace luxel::pipeline::detail
