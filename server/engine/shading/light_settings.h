// Bake settings for lighting that is not in the glTF file: the sky, a sun,
// and the angular size given to the scene's directional lights.
//
// Units are radiometric and glTF values are used 1:1 (kernels/shared/light.h
// has the full table): sky radiance = color * intensity (W/(m^2 sr)); sun
// illuminance = irradiance W/m^2 on a surface facing it. World is +Y up.
#pragma once

#include <string>

#include "common/choices.h"
#include "common/math.h"

namespace luxel::pipeline {

// Angular radii of the sun and of directional lights are in [0, this): the
// disc must be narrower than the hemisphere (L = E / (pi sin^2 a) needs
// a < 90 degrees). The settings schema and the light builder share it.
inline constexpr float kMaxAngularRadiusDegrees = 90;

struct SkySettings {
  // The settings' sky.kind choice (common/choices.h).
#define LUXEL_SKY_KIND_CHOICES(X) X(kNone, "none") X(kConstant, "constant") X(kEquirect, "equirect")
  LUXEL_MEMBER_CHOICE_ENUM(Kind, LUXEL_SKY_KIND_CHOICES)
  Kind kind = Kind::kNone;
  Vec3 color{1, 1, 1};  // multiplies the image too
  float intensity = 1;
  std::string equirect_path;   // HDR/EXR (anything OpenImageIO reads), kEquirect only
  float rotation_degrees = 0;  // about +Y, right-handed (light.h: EQUIRECT MAPPING)
};

// A sun in addition to the scene's KHR_lights_punctual directional lights.
struct SunSettings {
  bool enabled = false;
  Vec3 direction{0, -1, 0};  // direction the light travels (need not be unit)
  Vec3 color{1, 1, 1};
  float illuminance = 1;                 // W/m^2 facing the sun (color * illuminance)
  float angular_radius_degrees = 0.27f;  // 0: a delta (hard shadows); the real sun is ~0.27
};

struct LightSettings {
  SkySettings sky;
  SunSettings sun;
  // Angular radius given to the scene's directional lights (0: delta lights).
  float directional_angular_radius_degrees = 0;
};

}  // namespace luxel::pipeline
