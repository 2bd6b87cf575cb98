#include "settings/settings_schema.h"

#include <cmath>
#include <nlohmann/json.hpp>
#include <set>
#include <type_traits>

#include "settings/bake_settings.h"

namespace luxel::pipeline {
namespace {

using Type = SettingType;
using Scope = SettingScope;

// Accessors binding a setting to a BakeSettings member. Values reach a
// setter only after check_setting, so the casts stay in range.
#define LUXEL_NUMBER(member)                                                       \
  .get = [](const BakeSettings& s) { return SettingValue::of(double(s.member)); }, \
  .set = [](BakeSettings& s, const SettingValue& v) {                              \
    s.member = static_cast<std::remove_cvref_t<decltype(s.member)>>(v.number);     \
  }
#define LUXEL_BOOL(member)                                                             \
  .get = [](const BakeSettings& s) { return SettingValue::of(s.member ? 1.0 : 0.0); }, \
  .set = [](BakeSettings& s, const SettingValue& v) { s.member = v.number != 0; }
#define LUXEL_VEC3(member)                                                     \
  .get = [](const BakeSettings& s) { return SettingValue::of_vec(s.member); }, \
  .set = [](BakeSettings& s, const SettingValue& v) { s.member = v.vec; }
#define LUXEL_TEXT(member)                                                      \
  .get = [](const BakeSettings& s) { return SettingValue::of_text(s.member); }, \
  .set = [](BakeSettings& s, const SettingValue& v) { s.member = v.text; }
// A member of a choice enum (common/choices.h); .choices = choice_list<E>()
// gives its names. check_setting admits only those, hence the CHECK.
#define LUXEL_CHOICE(member)                                                                 \
  .get = [](const BakeSettings& s) { return SettingValue::of_text(choice_name(s.member)); }, \
  .set = [](BakeSettings& s, const SettingValue& v) {                                        \
    const auto c = parse_choice<std::remove_cvref_t<decltype(s.member)>>(v.text);            \
    LUXEL_CHECK_MSG(c.has_value(), "a choice reaches its setter checked");                   \
    s.member = *c;                                                                           \
  }

constexpr double kU32Max = 4294967295.0;
constexpr double kI32Max = 2147483647.0;

using SkyKind = SkySettings::Kind;

bool has_sky(const BakeSettings& s) {
  return s.lights.sky.kind != SkyKind::kNone;
}
bool has_equirect_sky(const BakeSettings& s) {
  return s.lights.sky.kind == SkyKind::kEquirect;
}
bool has_sun(const BakeSettings& s) {
  return s.lights.sun.enabled;
}
bool has_encodings(const BakeSettings& s) {
  return !s.encodings.names.empty();
}
bool has_probes(const BakeSettings& s) {
  return !s.probes.empty();
}

std::string describe_sky(const BakeSettings& s) {
  const SkySettings& sky = s.lights.sky;
  switch (sky.kind) {
    case SkyKind::kConstant:
      return strprintf("constant %g,%g,%g x %g", sky.color.x, sky.color.y, sky.color.z,
                       sky.intensity);
    case SkyKind::kEquirect:
      return strprintf("equirect %s x %g rot %g", sky.equirect_path.c_str(), sky.intensity,
                       sky.rotation_degrees);
    case SkyKind::kNone:
      break;
  }
  return choice_name(sky.kind);
}

std::string describe_sun(const BakeSettings& s) {
  const SunSettings& sun = s.lights.sun;
  return strprintf("dir %g,%g,%g E %g radius %g deg", sun.direction.x, sun.direction.y,
                   sun.direction.z, sun.illuminance, sun.angular_radius_degrees);
}

std::vector<Setting> make_schema() {
  std::vector<Setting> t;
  // ------------------------------------------------------------ stopping rules
  t.push_back({.name = "samples_per_texel",
               .type = Type::kInt,
               .units = "samples",
               .help = "stop at this many paths per covered texel on average (adaptive "
                       "sampling gives noisy texels more; 0: no sample rule)",
               .flag = "--samples",
               .metavar = "N",
               .default_value = SettingValue::of(256),
               .min = 0,
               .max = kU32Max,
               .api_zero = ApiZero::kValue,
               .api_note = "0 (unset): no sample rule",
               LUXEL_NUMBER(samples_per_texel)});
  t.push_back({.name = "time_budget_s",
               .type = Type::kFloat,
               .units = "s",
               .help = "stop after this much path tracing, wall clock, checked per iteration "
                       "(0: none)",
               .flag = "--time",
               .metavar = "SECONDS",
               .default_value = SettingValue::of(0),
               .min = 0,
               .api_zero = ApiZero::kValue,
               LUXEL_NUMBER(time_budget_s)});
  t.push_back({.name = "target_error",
               .type = Type::kFloat,
               .units = "",
               .help = "stop when target_metric over covered texels falls to this (0: none)",
               .flag = "--target-error",
               .metavar = "E",
               .default_value = SettingValue::of(0),
               .min = 0,
               .api_zero = ApiZero::kValue,
               LUXEL_NUMBER(target_error)});
  t.push_back({.name = "target_metric",
               .type = Type::kChoice,
               .units = "",
               .help = "what target_error bounds: the mean relative standard error estimate, "
                       "or rmse / relmse against the reference",
               .flag = "--target-metric",
               .metavar = "M",
               .default_value = SettingValue::of_text(choice_name(ErrorMetric::kEstimate)),
               .choices = choice_list<ErrorMetric>(),
               LUXEL_CHOICE(target_metric),
               .described = Described::kUnlessDefault});
  t.push_back({.name = "reference",
               .type = Type::kText,
               .units = "",
               .help = "benchmark mode: a reference lightmap EXR of the bake's size (RGB or "
                       "RGBA float); reports carry RMSE and relMSE against it",
               .flag = "--reference",
               .metavar = "FILE.exr",
               .default_value = SettingValue::of_text(""),
               .scope = Scope::kLocalOnly,
               LUXEL_TEXT(reference_name),
               // A reference given in-process has no name.
               .describe_when = [](const BakeSettings& s) { return s.reference != nullptr; },
               .describe_text =
                   [](const BakeSettings& s) {
                     return s.reference_name.empty() ? std::string("given") : s.reference_name;
                   }});
  t.push_back({.name = "reference_bake_id",
               .type = Type::kText,
               .units = "",
               .help = "benchmark mode: the irradiance of this SUCCEEDED bake (same lightmap "
                       "size) is the reference",
               .flag = "--reference-bake",
               .metavar = "ID",
               .default_value = SettingValue::of_text(""),
               .scope = Scope::kApiOnly,
               LUXEL_TEXT(job.reference_bake_id),
               // the daemon resolves it into `reference`
               .described = Described::kNever});
  // ------------------------------------------------------------ lightmap size
  // texel_density comes first: when both are given, resolution (applied last) wins.
  t.push_back({.name = "texel_density",
               .type = Type::kFloat,
               .units = "texels per world unit",
               .help = "derive the lightmap size from this density instead of a resolution",
               .flag = "--texel-density",
               .metavar = "D",
               .default_value = SettingValue::of(0),
               .min = 0,
               .api_zero = ApiZero::kValue,
               .api_note = "0 (unset): use resolution",
               .get = [](const BakeSettings& s) { return SettingValue::of(s.atlas.texel_density); },
               .set =
                   [](BakeSettings& s, const SettingValue& v) {
                     s.atlas.texel_density = static_cast<float>(v.number);
                     if (v.number > 0) s.atlas.resolution = 0;
                   }});
  t.push_back({.name = "resolution",
               .type = Type::kInt,
               .units = "texels",
               .help = "lightmap side (0 with a texel density)",
               .flag = "--resolution",
               .metavar = "N",
               .default_value = SettingValue::of(512),
               .min = 0,
               .max = kI32Max,
               .api_note = "0 (unset) with texel_density 0: 512, at most --max-resolution",
               .get = [](const BakeSettings& s) { return SettingValue::of(s.atlas.resolution); },
               .set =
                   [](BakeSettings& s, const SettingValue& v) {
                     s.atlas.resolution = static_cast<int>(v.number);
                     if (v.number > 0) s.atlas.texel_density = 0;
                   }});
  // ------------------------------------------------------------ light transport
  t.push_back({.name = "max_bounces",
               .type = Type::kInt,
               .units = "bounces",
               .help = "indirect bounces after the texel point (0: direct light only)",
               .flag = "--bounces",
               .metavar = "B",
               .default_value = SettingValue::of(4),
               .min = 0,
               .max = 64,
               LUXEL_NUMBER(max_bounces)});
  t.push_back({.name = "rr_depth",
               .type = Type::kInt,
               .units = "vertices",
               .help = "Russian roulette from this path vertex depth on",
               .flag = "--rr-depth",
               .metavar = "D",
               .default_value = SettingValue::of(3),
               .min = 1,
               .max = 64,
               .scope = Scope::kLocalOnly,
               LUXEL_NUMBER(rr_depth)});
  t.push_back({.name = "paths_per_iteration",
               .type = Type::kInt,
               .units = "paths",
               .help = "batch size, at most the device's iteration cap (2^17 paths per compute "
                       "unit, at least 2^18): device memory scales with it; 0: auto (2^18 on "
                       "CPUs, 2^22 on GPUs, halved to fit the memory budget)",
               .flag = "--paths-per-iteration",
               .metavar = "N",
               .default_value = SettingValue::of(0),
               .min = 1024,
               .max = 1u << 26,
               .zero_is_auto = true,
               LUXEL_NUMBER(paths_per_iteration)});
  t.push_back({.name = "adaptive",
               .type = Type::kBool,
               .units = "",
               .help = "adaptive sampling: after a uniform warm-up, paths go where the relative "
                       "error is highest (--no-adaptive: every texel alike)",
               .flag = "--no-adaptive",
               .default_value = SettingValue::of(1),
               LUXEL_BOOL(adaptive),
               .describe_text = [](const BakeSettings& s) {
                 return s.adaptive ? strprintf("on,min=%u", s.adaptive_min_samples)
                                   : std::string("off");
               }});
  t.push_back({.name = "adaptive_min_samples",
               .type = Type::kInt,
               .units = "samples",
               .help = "adaptive sampling's uniform warm-up: samples every texel has before "
                       "paths follow the error",
               .flag = "--adaptive-min-samples",
               .metavar = "N",
               .default_value = SettingValue::of(8),
               .min = 2,
               .max = 65536,
               .api_note = "0 (unset) means 8",
               LUXEL_NUMBER(adaptive_min_samples),
               .active = [](const BakeSettings& s) { return s.adaptive; },
               // in adaptive's entry
               .described = Described::kNever});
  t.push_back(
      {.name = "shard_count",
       .type = Type::kInt,
       .units = "shards",
       .help = "distributed bake: the bake is split into this many shards by sample "
               "index, merged exactly afterwards (0 or 1: the whole bake; implies "
               "--no-adaptive)",
       .flag = "--shard-count",
       .metavar = "N",
       .default_value = SettingValue::of(1),
       .min = 0,
       .max = 4096,
       .api_note = "0 (unset) means 1",
       .implies =
           [](BakeSettings& s) {
             if (s.shard_count > 1) s.adaptive = false;
           },
       LUXEL_NUMBER(shard_count),
       // One entry for both shard settings, which bake_fingerprint leaves out:
       // the shards of one bake share its fingerprint.
       .describe_key = "shard",
       .describe_when = [](const BakeSettings& s) { return s.sharded(); },
       .describe_text =
           [](const BakeSettings& s) { return strprintf("%u/%u", s.shard_index, s.shard_count); }});
  t.push_back({.name = "shard_index",
               .type = Type::kInt,
               .units = "",
               .help = "distributed bake: which shard this bake traces, < shard_count "
                       "(samples_per_texel stays the whole bake's)",
               .flag = "--shard-index",
               .metavar = "K",
               .default_value = SettingValue::of(0),
               .min = 0,
               .max = 4095,
               .api_zero = ApiZero::kValue,
               LUXEL_NUMBER(shard_index),
               // in shard_count's entry
               .described = Described::kNever});
  t.push_back({.name = "device_memory_budget_mib",
               .type = Type::kFloat,
               .units = "MiB",
               .help = "device memory the bake may hold; past it the atlas is baked in tiles "
                       "(0: min(80 % of the device's memory, 4 GiB))",
               .flag = "--device-memory-budget",
               .metavar = "MIB",
               .default_value = SettingValue::of(0),
               .min = 0,
               .max = 1u << 24,
               LUXEL_NUMBER(device_memory_budget_mib),
               .described = Described::kUnlessDefault});
  t.push_back({.name = "seed",
               .type = Type::kInt,
               .units = "",
               .help = "seed of the per-texel sequences (same seed, same bits)",
               .flag = "--seed",
               .metavar = "S",
               .default_value = SettingValue::of(1),
               .min = 0,
               .max = kU32Max,
               .api_note = "0 (unset) means 1",
               LUXEL_NUMBER(seed)});
  t.push_back({.name = "filter",
               .type = Type::kChoice,
               .units = "",
               .help = "accumulation filter (gaussian: 1.5-texel truncated Gaussian)",
               .flag = "--filter",
               .metavar = "F",
               .default_value = SettingValue::of_text(choice_name(Filter::kBox)),
               .choices = choice_list<Filter>(),
               LUXEL_CHOICE(filter)});
  t.push_back({.name = "direct",
               .type = Type::kChoice,
               .units = "",
               .help =
                   "direct light at the texel point: analytic (exact unshadowed irradiance of "
                   "untextured emissive triangles and punctual lights, sampled shadows; irradiance "
                   "only), sampled (plain next-event estimation), or auto (analytic when every "
                   "analytic light of the scene is punctual, else sampled)",
               .flag = "--direct",
               .metavar = "D",
               .default_value = SettingValue::of_text(choice_name(DirectLight::kAuto)),
               .choices = choice_list<DirectLight>(),
               LUXEL_CHOICE(direct),
               .described = Described::kUnlessDefault});
  t.push_back({.name = "intersector",
               .type = Type::kChoice,
               .units = "",
               .help = "ray queries: auto (Embree on CPU devices, OpenCL on GPUs), embree, opencl",
               .flag = "--intersector",
               .metavar = "I",
               .default_value = SettingValue::of_text(choice_name(accel::IntersectorKind::kAuto)),
               .choices = choice_list<accel::IntersectorKind>(),
               LUXEL_CHOICE(intersector)});
  t.push_back({.name = "uv",
               .type = Type::kChoice,
               .units = "",
               .help = "lightmap UVs: auto (TEXCOORD_1 when valid, else generated), generate, "
                       "existing",
               .flag = "--uv",
               .metavar = "M",
               .default_value = SettingValue::of_text(choice_name(UvMode::kAuto)),
               .choices = choice_list<UvMode>(),
               LUXEL_CHOICE(uv)});
  t.push_back({.name = "clamp_luminance",
               .type = Type::kFloat,
               .units = "W/m^2/sr",
               .help = "clamp a path's luminance against fireflies (biased; 0: off)",
               .flag = "--clamp",
               .metavar = "L",
               .default_value = SettingValue::of(0),
               .min = 0,
               .scope = Scope::kLocalOnly,
               LUXEL_NUMBER(clamp_luminance)});
  // ------------------------------------------------------------ sky and sun
  t.push_back({.name = "sky.kind",
               .type = Type::kChoice,
               .units = "",
               .help = "sky: none, a constant radiance, or an equirectangular image (set by "
                       "--sky / --sky-image)",
               .default_value = SettingValue::of_text(choice_name(SkyKind::kNone)),
               .choices = choice_list<SkyKind>(),
               .local_choices = {choice_name(SkyKind::kEquirect)},
               LUXEL_CHOICE(lights.sky.kind),
               // One entry for the sky: "none", "constant R,G,B x I", "equirect FILE x I rot DEG".
               .describe_key = "sky",
               .describe_text = describe_sky});
  t.push_back({.name = "sky.color",
               .type = Type::kVec3,
               .units = "W/m^2/sr",
               .help = "constant sky radiance, linear RGB (multiplies a sky image)",
               .flag = "--sky",
               .metavar = "R,G,B",
               .default_value = SettingValue::of_vec({1, 1, 1}),
               .min = 0,
               .api_note = "empty: 1,1,1",
               .implies = [](BakeSettings& s) { s.lights.sky.kind = SkyKind::kConstant; },
               LUXEL_VEC3(lights.sky.color),
               .active = has_sky,
               // in sky.kind's entry
               .described = Described::kNever});
  t.push_back({.name = "sky.intensity",
               .type = Type::kFloat,
               .units = "",
               .help = "multiplies the sky colour",
               .flag = "--sky-intensity",
               .metavar = "X",
               .default_value = SettingValue::of(1),
               .min = 0,
               .api_note = "0 (unset) means 1",
               LUXEL_NUMBER(lights.sky.intensity),
               .active = has_sky,
               // in sky.kind's entry
               .described = Described::kNever});
  t.push_back({.name = "sky.image",
               .type = Type::kText,
               .units = "",
               .help = "equirectangular HDR/EXR sky, importance-sampled",
               .flag = "--sky-image",
               .metavar = "FILE",
               .default_value = SettingValue::of_text(""),
               .scope = Scope::kLocalOnly,
               .implies = [](BakeSettings& s) { s.lights.sky.kind = SkyKind::kEquirect; },
               LUXEL_TEXT(lights.sky.equirect_path),
               .active = has_equirect_sky,
               // in sky.kind's entry
               .described = Described::kNever});
  t.push_back({.name = "sky.rotation_degrees",
               .type = Type::kFloat,
               .units = "degrees",
               .help = "rotation of the sky image about +Y",
               .flag = "--sky-rotation",
               .metavar = "DEG",
               .default_value = SettingValue::of(0),
               .scope = Scope::kLocalOnly,
               LUXEL_NUMBER(lights.sky.rotation_degrees),
               .active = has_equirect_sky,
               // in sky.kind's entry
               .described = Described::kNever});
  t.push_back({.name = "sun.direction",
               .type = Type::kVec3,
               .units = "",
               .help = "adds a sun; the direction its light travels (need not be unit)",
               .flag = "--sun",
               .metavar = "X,Y,Z",
               .default_value = SettingValue::of_vec({0, -1, 0}),
               .nonzero = true,
               .api_note = "empty: 0,-1,0",
               .implies = [](BakeSettings& s) { s.lights.sun.enabled = true; },
               LUXEL_VEC3(lights.sun.direction),
               .active = has_sun,
               // One entry for the sun: "dir X,Y,Z E ILLUMINANCE radius DEG deg".
               .describe_key = "sun",
               .describe_text = describe_sun});
  t.push_back({.name = "sun.color",
               .type = Type::kVec3,
               .units = "",
               .help = "sun colour, linear RGB (multiplies the illuminance)",
               .flag = "--sun-color",
               .metavar = "R,G,B",
               .default_value = SettingValue::of_vec({1, 1, 1}),
               .min = 0,
               .api_note = "empty: 1,1,1",
               LUXEL_VEC3(lights.sun.color),
               .active = has_sun,
               // Never in describe() (kept so): bakes differing only in the sun's colour
               // share a fingerprint.
               .described = Described::kNever});
  t.push_back({.name = "sun.illuminance",
               .type = Type::kFloat,
               .units = "W/m^2",
               .help = "sun irradiance on a surface facing it",
               .flag = "--sun-illuminance",
               .metavar = "E",
               .default_value = SettingValue::of(1),
               .min = 0,
               .api_zero = ApiZero::kValue,
               .api_note = "0 (unset): no sun",
               LUXEL_NUMBER(lights.sun.illuminance),
               .active = has_sun,
               // in sun.direction's entry
               .described = Described::kNever});
  t.push_back({.name = "sun.angular_radius_degrees",
               .type = Type::kFloat,
               .units = "degrees",
               .help = "angular radius of the sun's disc (0: a delta light, hard shadows)",
               .flag = "--sun-radius",
               .metavar = "DEG",
               .default_value = SettingValue::of(0.27),
               .min = 0,
               .max = kMaxAngularRadiusDegrees,
               .max_open = true,
               .api_zero = ApiZero::kValue,
               .api_note = "0 (unset): hard shadows",
               LUXEL_NUMBER(lights.sun.angular_radius_degrees),
               .active = has_sun,
               // in sun.direction's entry
               .described = Described::kNever});
  t.push_back({.name = "directional_angular_radius_degrees",
               .type = Type::kFloat,
               .units = "degrees",
               .help = "angular radius given to the scene's directional lights",
               .flag = "--directional-radius",
               .metavar = "DEG",
               .default_value = SettingValue::of(0),
               .min = 0,
               .max = kMaxAngularRadiusDegrees,
               .max_open = true,
               .scope = Scope::kLocalOnly,
               LUXEL_NUMBER(lights.directional_angular_radius_degrees),
               // Never in describe() (kept so): bakes differing only here share a
               // fingerprint.
               .described = Described::kNever});
  // ------------------------------------------------------------ directional encodings
  t.push_back(
      {.name = "encodings",
       .type = Type::kChoiceList,
       .units = "",
       .help = "irradiance (always baked) plus directional encodings; each adds "
               "<name>.exr",
       .flag = "--encoding",
       .metavar = "LIST",
       .default_value = SettingValue::of_list({}),
       .max = 8,
       .choices = {"irradiance", "sh1", "sh2", "sg6", "sg9", "sg12", "sg6-hemi", "sg9-hemi",
                   "sg12-hemi", "ambient-dice9", "ambient-dice12"},
       .get = [](const BakeSettings& s) { return SettingValue::of_list(s.encodings.names); },
       .set =
           [](BakeSettings& s, const SettingValue& v) {
             s.encodings.names.clear();
             for (const auto& n : v.list)
               if (n != "irradiance") s.encodings.names.push_back(n);
           },
       .described = Described::kUnlessDefault,
       .describe_text =
           [](const BakeSettings& s) {
             std::string list = "irradiance";  // always baked, implicit in the value
             for (const auto& n : s.encodings.names) list += "," + n;
             return list;
           }});
  t.push_back({.name = "sg_sharpness",
               .type = Type::kFloat,
               .units = "",
               .help = "spherical Gaussian lambda of Eq. 8.2",
               .flag = "--sg-sharpness",
               .metavar = "L",
               .default_value = SettingValue::of(3.4),
               .min = 0.25,
               .max = 256,
               .api_note = "0 (unset) means 3.4",
               LUXEL_NUMBER(encodings.sg_sharpness),
               .describe_when = has_encodings});
  t.push_back({.name = "solver",
               .type = Type::kChoice,
               .units = "",
               .help = "auto (SH: projection; SG, Ambient Dice: progressive-nn), projection, "
                       "progressive (Listing 7.1), progressive-nn (amplitudes >= 0)",
               .flag = "--solver",
               .metavar = "S",
               .default_value = SettingValue::of_text(choice_name(EncodingSolver::kAuto)),
               .choices = choice_list<EncodingSolver>(),
               LUXEL_CHOICE(encodings.solver),
               .describe_when = has_encodings});
  t.push_back({.name = "acceleration",
               .type = Type::kFloat,
               .units = "",
               .help = "alpha of Eq. 7.14 for the progressive solvers",
               .flag = "--acceleration",
               .metavar = "A",
               .default_value = SettingValue::of(3),
               .min = 0.5,
               .max = 8,
               .api_note = "0 (unset) means 3",
               LUXEL_NUMBER(encodings.acceleration),
               .describe_when = has_encodings});
  // ------------------------------------------------------------ ablation switches (§5.1, §5.4,
  // §6.2)
  t.push_back({.name = "compaction",
               .type = Type::kBool,
               .units = "",
               .help = "stream compaction of live paths (--no-compaction: off)",
               .flag = "--no-compaction",
               .default_value = SettingValue::of(1),
               .scope = Scope::kLocalOnly,
               LUXEL_BOOL(compaction)});
  t.push_back({.name = "sort_directions",
               .type = Type::kBool,
               .units = "",
               .help = "sort rays by direction octant before traversal",
               .flag = "--sort-directions",
               .default_value = SettingValue::of(0),
               .scope = Scope::kLocalOnly,
               LUXEL_BOOL(sort_directions)});
  t.push_back({.name = "random_sequence",
               .type = Type::kBool,
               .units = "",
               .help = "independent random numbers instead of Owen-scrambled Sobol",
               .flag = "--random-sequence",
               .default_value = SettingValue::of(0),
               .scope = Scope::kLocalOnly,
               LUXEL_BOOL(random_sequence),
               .describe_key = "sequence",
               .describe_text = [](const BakeSettings& s) {
                 return std::string(s.random_sequence ? "random" : "sobol");
               }});
  // ------------------------------------------------------------ reports and output
  t.push_back({.name = "progress_interval_s",
               .type = Type::kFloat,
               .units = "s",
               .help = "seconds between progress reports and error-series points (at least 0.05)",
               .flag = "--progress-interval",
               .metavar = "S",
               .default_value = SettingValue::of(1),
               .min = 0,
               .min_open = true,
               .raise_to = 0.05,
               .api_note = "0 (unset) means 1",
               LUXEL_NUMBER(progress_interval_s),
               // shapes the reports, not the lightmap
               .described = Described::kNever});
  t.push_back({.name = "dilation_texels",
               .type = Type::kInt,
               .units = "texels",
               .help = "fill uncovered texels up to this far from a chart",
               .flag = "--dilate",
               .metavar = "N",
               .default_value = SettingValue::of(2),
               .min = 0,
               .max = 64,
               .api_note = "0 (unset) means 2",
               LUXEL_NUMBER(dilation_texels)});
  t.push_back(
      {.name = "denoise",
       .type = Type::kChoice,
       .units = "",
       .help = "denoiser of the finished lightmap, written as irradiance_denoised.exr besides the "
               "raw irradiance.exr (atrous: edge-avoiding a-trous wavelets; off: none)",
       .flag = "--denoise",
       .metavar = "D",
       .default_value = SettingValue::of_text(choice_name(Denoise::kOff)),
       .choices = choice_list<Denoise>(),
       LUXEL_CHOICE(denoise),
       .described = Described::kUnlessDefault});
  t.push_back({.name = "seam_stitch",
               .type = Type::kBool,
               .units = "",
               .help = "least-squares stitching of lightmap UV seams so bilinear fetches on both "
                       "sides agree (opt-in: on the gas station at 128^2 it still moves the "
                       "converged map; seams of charts under 3 texels wide are left alone)",
               .flag = "--seam-stitch",
               .default_value = SettingValue::of(0),
               .api_note = "unset means off",
               LUXEL_BOOL(seam_stitch)});
  // ------------------------------------------------------------ light probes
  t.push_back({.name = "probes",
               .type = Type::kText,
               .units = "",
               .help = "light probes baked with (or instead of) the lightmap: grid:S (spacing S "
                       "over the scene bounds), grid:S:box=x0,y0,z0,x1,y1,z1, file:P.json (a "
                       "list of [x,y,z]), adaptive:S (grid kept near geometry, probes moved out "
                       "of closed geometry), nodes (glTF nodes with extras.luxelProbe); empty: "
                       "none",
               .flag = "--probes",
               .metavar = "SPEC",
               .default_value = SettingValue::of_text(""),
               LUXEL_TEXT(probes),
               .described = Described::kUnlessDefault});
  t.push_back({.name = "probe_sh_order",
               .type = Type::kInt,
               .units = "",
               .help = "SH order of the probes' radiance: 1 (L1, 4 coefficients) or 2 (L2, 9)",
               .flag = "--probe-sh-order",
               .metavar = "L",
               .default_value = SettingValue::of(2),
               .min = 1,
               .max = 2,
               .api_note = "0 (unset) means 2",
               LUXEL_NUMBER(probe_sh_order),
               .describe_when = has_probes});
  t.push_back({.name = "probe_window",
               .type = Type::kText,
               .units = "",
               .help = "SH ringing control applied when probes are evaluated (recorded in "
                       "probes.bin/json): none, hanning, lanczos",
               .flag = "--probe-window",
               .metavar = "W",
               .default_value = SettingValue::of_text("hanning"),
               .api_note = "empty (unset) means hanning",
               LUXEL_TEXT(probe_window),
               .describe_when = has_probes});
  t.push_back({.name = "lightmap",
               .type = Type::kBool,
               .units = "",
               .help = "bake the lightmap (off: probes only, needs --probes)",
               .flag = "--no-lightmap",
               .default_value = SettingValue::of(1),
               .api_note = "unset means on",
               LUXEL_BOOL(lightmap),
               .described = Described::kUnlessDefault});
  t.push_back({.name = "probe_positions",
               .type = Type::kText,
               .units = "",
               .help = "probes file:... mode: the JSON list of positions (luxel bake reads the "
                       "file named in --probes)",
               .flag = "--probe-positions",
               .metavar = "JSON",
               .default_value = SettingValue::of_text(""),
               .scope = Scope::kApiOnly,
               LUXEL_TEXT(probe_positions),
               .described = Described::kUnlessDefault,
               .describe_key = "probe_positions_fnv1a",
               .describe_when = has_probes,
               .describe_fnv1a = true});
  // ------------------------------------------------------------ the daemon's job
  t.push_back({.name = "priority",
               .type = Type::kInt,
               .units = "",
               .help = "higher runs first; FIFO among equals",
               .flag = "--priority",
               .metavar = "P",
               .default_value = SettingValue::of(0),
               .min = -kI32Max - 1,
               .max = kI32Max,
               .scope = Scope::kApiOnly,
               LUXEL_NUMBER(job.priority),
               .described = Described::kNever});
  t.push_back({.name = "snapshot_interval_s",
               .type = Type::kFloat,
               .units = "s",
               .help = "seconds between progressive snapshots (a minimum; at least 0.05)",
               .flag = "--snapshot-interval",
               .metavar = "S",
               .default_value = SettingValue::of(5),
               .min = 0,
               .min_open = true,
               .raise_to = 0.05,
               .scope = Scope::kApiOnly,
               .api_note = "0 (unset) means 5",
               LUXEL_NUMBER(job.snapshot_interval_s),
               .described = Described::kNever});
  t.push_back({.name = "snapshot_format",
               .type = Type::kChoice,
               .units = "",
               .help = "png: tone-mapped 8-bit preview; exr: the float lightmap; none: progress "
                       "events only",
               .flag = "--snapshot-format",
               .metavar = "F",
               .default_value = SettingValue::of_text(choice_name(SnapshotFormat::kPng)),
               .choices = choice_list<SnapshotFormat>(),
               .scope = Scope::kApiOnly,
               LUXEL_CHOICE(job.snapshot_format),
               .described = Described::kNever});
  t.push_back({.name = "denoise_snapshots",
               .type = Type::kBool,
               .units = "",
               .help = "denoise progressive snapshots too (previews; needs denoise != off)",
               .flag = "--denoise-snapshots",
               .default_value = SettingValue::of(0),
               .scope = Scope::kApiOnly,
               LUXEL_BOOL(job.denoise_snapshots),
               .described = Described::kNever});
  t.push_back({.name = "snapshot_max_side",
               .type = Type::kInt,
               .units = "pixels",
               .help = "longest side of PNG snapshots",
               .flag = "--snapshot-size",
               .metavar = "N",
               .default_value = SettingValue::of(512),
               .min = 1,
               .max = 8192,
               .scope = Scope::kApiOnly,
               .api_note = "0 (unset) means 512",
               LUXEL_NUMBER(job.snapshot_max_side),
               .described = Described::kNever});
  // Coordinator mode (server/service/coordinator/): the daemon splits the bake
  // by sample index across worker daemons; the merged result is the one-machine
  // result, so neither setting shapes the result (nor the fingerprint).
  t.push_back({.name = "shards",
               .type = Type::kInt,
               .units = "",
               .help = "split the bake across this many worker daemons of a coordinator luxeld "
                       "(--workers); 0 or 1: one machine. `--shards auto`: one per worker "
                       "(implies --no-adaptive)",
               .flag = "--shards",
               .metavar = "N|auto",
               .default_value = SettingValue::of(0),
               .min = 0,
               .max = 1024,
               .scope = Scope::kApiOnly,
               // Shards sample uniformly (their accumulators merge exactly).
               .implies =
                   [](BakeSettings& s) {
                     if (s.job.shards > 1) s.adaptive = false;
                   },
               LUXEL_NUMBER(job.shards),
               .described = Described::kNever});
  t.push_back({.name = "shards_auto",
               .type = Type::kBool,
               .units = "",
               .help = "one shard per worker the coordinator resolves when the bake starts",
               .default_value = SettingValue::of(0),
               .scope = Scope::kApiOnly,
               LUXEL_BOOL(job.shards_auto),
               .described = Described::kNever});
  return t;
}

#undef LUXEL_NUMBER
#undef LUXEL_BOOL
#undef LUXEL_VEC3
#undef LUXEL_TEXT
#undef LUXEL_CHOICE

std::string fmt_number(double x) {
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  if (std::isfinite(x) && x == std::floor(x) && std::fabs(x) < 1e15) return strprintf("%.0f", x);
  return strprintf("%g", x);
}

bool in_range(const Setting& st, double x) {
  if (st.zero_is_auto && x == 0) return true;
  if (st.min_open ? !(x > st.min) : !(x >= st.min)) return false;
  if (st.max_open ? !(x < st.max) : !(x <= st.max)) return false;
  return true;
}

// "in [0, 64]", ">= 0", "in [0, 90)", "> 0".
std::string range_phrase(const Setting& st) {
  const bool lo = std::isfinite(st.min), hi = std::isfinite(st.max);
  if (lo && hi)
    return strprintf("%sin %c%s, %s%c", st.zero_is_auto ? "0 (auto) or " : "",
                     st.min_open ? '(' : '[', fmt_number(st.min).c_str(),
                     fmt_number(st.max).c_str(), st.max_open ? ')' : ']');
  if (lo) return strprintf("%s %s", st.min_open ? ">" : ">=", fmt_number(st.min).c_str());
  if (hi) return strprintf("%s %s", st.max_open ? "<" : "<=", fmt_number(st.max).c_str());
  return "";
}

bool is_choice(const Setting& st, const std::string& name) {
  for (const char* c : st.choices)
    if (name == c) return true;
  return false;
}

std::string choice_list(const Setting& st) {
  std::string out;
  for (const char* c : st.choices) out += (out.empty() ? "" : ", ") + std::string(c);
  return out;
}

std::vector<std::string> split(const std::string& text, char sep) {
  std::vector<std::string> parts;
  size_t start = 0;
  while (start <= text.size()) {
    size_t end = text.find(sep, start);
    if (end == std::string::npos) end = text.size();
    parts.push_back(text.substr(start, end - start));
    start = end + 1;
  }
  return parts;
}

}  // namespace

const std::vector<Setting>& settings_schema() {
  static const std::vector<Setting> schema = make_schema();
  return schema;
}

const Setting* find_setting(const std::string& name) {
  for (const Setting& st : settings_schema())
    if (name == st.name) return &st;
  return nullptr;
}

BakeSettings default_settings() {
  BakeSettings s;
  for (const Setting& st : settings_schema()) st.set(s, st.default_value);
  return s;
}

Status check_setting(const Setting& st, const SettingValue& v) {
  auto bad = [&](const std::string& why) {
    return invalid_argument(strprintf("settings.%s: %s", st.name, why.c_str()));
  };
  switch (st.type) {
    case Type::kInt:
    case Type::kFloat: {
      const double x = v.number;
      if (!std::isfinite(x)) return bad("must be a finite number, got " + fmt_number(x));
      if (st.type == Type::kInt && x != std::floor(x))
        return bad("must be a whole number, got " + fmt_number(x));
      if (!in_range(st, x))
        return bad(
            strprintf("must be %s, got %s", range_phrase(st).c_str(), fmt_number(x).c_str()));
      return Status::ok();
    }
    case Type::kBool:
    case Type::kText:
      return Status::ok();
    case Type::kChoice:
      if (!is_choice(st, v.text))
        return bad(strprintf("'%s' is not one of %s", v.text.c_str(), choice_list(st).c_str()));
      return Status::ok();
    case Type::kChoiceList: {
      std::set<std::string> seen;
      for (const auto& n : v.list) {
        if (!is_choice(st, n))
          return bad(strprintf("'%s' is not one of %s", n.c_str(), choice_list(st).c_str()));
        if (!seen.insert(n).second) return bad(strprintf("'%s' is listed twice", n.c_str()));
      }
      if (double(v.list.size()) > st.max)
        return bad(
            strprintf("at most %s at once, got %zu", fmt_number(st.max).c_str(), v.list.size()));
      return Status::ok();
    }
    case Type::kVec3: {
      const Vec3 c = v.vec;
      const std::string got = strprintf("(%g, %g, %g)", c.x, c.y, c.z);
      if (!is_finite(c)) return bad("values must be finite, got " + got);
      for (int i = 0; i < 3; ++i)
        if (!in_range(st, c[i]))
          return bad(
              strprintf("each value must be %s, got %s", range_phrase(st).c_str(), got.c_str()));
      if (st.nonzero && c.x == 0 && c.y == 0 && c.z == 0) return bad("must not be zero");
      return Status::ok();
    }
  }
  return Status::ok();
}

Status apply_setting(BakeSettings& s, const Setting& st, SettingValue v) {
  LUXEL_RETURN_IF_ERROR(check_setting(st, v));
  if (st.raise_to > 0 && v.number > 0 && v.number < st.raise_to) v.number = st.raise_to;
  st.set(s, v);
  return Status::ok();
}

std::string format_setting_value(const Setting& st, const SettingValue& v) {
  switch (st.type) {
    case Type::kInt:
    case Type::kFloat:
      return fmt_number(v.number);
    case Type::kBool:
      return v.number != 0 ? "on" : "off";
    case Type::kChoice:
    case Type::kText:
      return v.text;
    case Type::kChoiceList: {
      std::string out;
      for (const auto& n : v.list) out += (out.empty() ? "" : ",") + n;
      return out;
    }
    case Type::kVec3:
      return strprintf("%g,%g,%g", v.vec.x, v.vec.y, v.vec.z);
  }
  return "";
}

Result<SettingValue> parse_setting_value(const Setting& st, const std::string& text) {
  auto number = [&](const std::string& t, double* out) {
    char* end = nullptr;
    *out = std::strtod(t.c_str(), &end);
    return !t.empty() && *end == '\0';
  };
  auto bad = [&](const char* expected) -> Status {
    return invalid_argument(
        strprintf("settings.%s: expected %s, got '%s'", st.name, expected, text.c_str()));
  };
  SettingValue v;
  switch (st.type) {
    case Type::kInt:
    case Type::kFloat:
      if (!number(text, &v.number)) return bad("a number");
      return v;
    case Type::kBool:
      if (text == "on" || text == "1" || text == "true") return SettingValue::of(1);
      if (text == "off" || text == "0" || text == "false") return SettingValue::of(0);
      return bad("on or off");
    case Type::kChoice:
    case Type::kText:
      return SettingValue::of_text(text);
    case Type::kChoiceList:
      for (auto& item : split(text, ','))
        if (!item.empty()) v.list.push_back(item);
      return v;
    case Type::kVec3: {
      auto parts = split(text, ',');
      double c[3];
      if (parts.size() != 3) return bad("three comma-separated numbers");
      for (int i = 0; i < 3; ++i)
        if (!number(parts[size_t(i)], &c[i])) return bad("three comma-separated numbers");
      return SettingValue::of_vec({float(c[0]), float(c[1]), float(c[2])});
    }
  }
  return bad("a value");
}

std::string describe_setting_value(const Setting& st, const SettingValue& v) {
  switch (st.type) {
    case Type::kInt:
      if (st.zero_is_auto && v.number == 0) return "auto";
      return strprintf("%lld", static_cast<long long>(v.number));
    case Type::kFloat:
      return strprintf("%g", v.number);
    case Type::kBool:
    case Type::kChoice:
    case Type::kText:
    case Type::kChoiceList:
    case Type::kVec3:
      break;
  }
  return format_setting_value(st, v);  // on/off, names, "a,b", "x,y,z" (%g)
}

bool same_setting_value(const Setting& st, const SettingValue& a, const SettingValue& b) {
  switch (st.type) {
    case Type::kInt:
    case Type::kFloat:
    case Type::kBool:
      return a.number == b.number;
    case Type::kChoice:
    case Type::kText:
      return a.text == b.text;
    case Type::kChoiceList:
      return a.list == b.list;
    case Type::kVec3:
      return a.vec.x == b.vec.x && a.vec.y == b.vec.y && a.vec.z == b.vec.z;
  }
  return false;
}

std::string describe_range(const Setting& st) {
  switch (st.type) {
    case Type::kChoice: {
      std::string out;
      for (const char* c : st.choices) out += (out.empty() ? "" : " | ") + std::string(c);
      return out;
    }
    case Type::kChoiceList:
      return strprintf("each of %s at most once, at most %s", choice_list(st).c_str(),
                       fmt_number(st.max).c_str());
    case Type::kVec3: {
      std::string r = range_phrase(st);
      std::string out = r.empty() ? "3 finite values" : "3 values, each " + r;
      return st.nonzero ? out + ", not all 0" : out;
    }
    case Type::kBool:
      return "on | off";
    case Type::kText:
      return "text";
    default: {
      std::string r = range_phrase(st);
      if (r.empty()) r = "finite";
      if (st.raise_to > 0)
        r += strprintf(", below %s raised to it", fmt_number(st.raise_to).c_str());
      return r;
    }
  }
}

std::string settings_schema_json() {
  using nlohmann::json;
  json all = json::array();
  for (const Setting& st : settings_schema()) {
    static const char* kTypes[] = {"int", "float", "bool", "choice", "choice_list", "vec3", "text"};
    static const char* kScopes[] = {"everywhere", "local_only", "api_only"};
    json e = {{"name", st.name},
              {"type", kTypes[int(st.type)]},
              {"units", st.units},
              {"help", st.help},
              {"flag", st.flag ? st.flag : ""},
              {"range", describe_range(st)},
              {"scope", kScopes[int(st.scope)]},
              {"api_zero", st.api_zero == ApiZero::kValue ? "value" : "default"},
              {"api_note", st.api_note ? st.api_note : ""}};
    const SettingValue& d = st.default_value;
    switch (st.type) {
      case Type::kInt:
        e["default"] = static_cast<long long>(d.number);
        break;
      case Type::kFloat:
        e["default"] = d.number;
        break;
      case Type::kBool:
        e["default"] = d.number != 0;
        break;
      case Type::kChoice:
      case Type::kText:
        e["default"] = d.text;
        break;
      case Type::kChoiceList:
        e["default"] = d.list;
        break;
      case Type::kVec3:
        e["default"] = {d.vec.x, d.vec.y, d.vec.z};
        break;
    }
    if (std::isfinite(st.min)) e["min"] = st.min;
    if (std::isfinite(st.max)) e["max"] = st.max;
    if (!st.choices.empty()) {
      std::vector<std::string> choices(st.choices.begin(), st.choices.end());
      e["choices"] = choices;
    }
    all.push_back(e);
  }
  return json({{"format", "luxel-settings-schema"}, {"version", 1}, {"settings", all}}).dump(1) +
         "\n";
}

}  // namespace luxel::pipeline
