// The settings schema's table, first part: stopping rules, lightmap size,
// light transport (settings_schema.cpp has the rules that read it).
#include "settings/schema_table.h"

namespace luxel::pipeline::schema {

void add_bake_settings(std::vector<Setting>& t) {
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
  // Without either, the size follows from the default density
  // (atlas::kDefaultTexelDensity, why 40 in atlas.h) and pages of at most
  // max_resolution, as Unity's and Bakery's lightmappers size theirs.
  // texel_density comes first: when both are given, resolution (applied last) wins.
  t.push_back({.name = "texel_density",
               .type = Type::kFloat,
               .units = "texels per world unit",
               .help = "lightmap size from this density: pages of at most --max-resolution "
                       "(ignored with --resolution)",
               .flag = "--texel-density",
               .metavar = "D",
               .default_value = SettingValue::of(atlas::kDefaultTexelDensity),
               .min = 0,
               .min_open = true,
               .api_note = "0 (unset): 40 unless resolution is given",
               .get = [](const BakeSettings& s) { return SettingValue::of(s.atlas.texel_density); },
               .set =
                   [](BakeSettings& s, const SettingValue& v) {
                     s.atlas.texel_density = static_cast<float>(v.number);
                     if (v.number > 0) s.atlas.resolution = 0;
                   },
               .active = [](const BakeSettings& s) { return s.atlas.resolution == 0; }});
  t.push_back(
      {.name = "max_resolution",
       .type = Type::kInt,
       .units = "texels",
       .help = "largest lightmap page a texel density gives: past it generated UVs go "
               "on more pages and the file's UVs get a lower density (with a warning)",
       .flag = "--max-resolution",
       .metavar = "N",
       .default_value = SettingValue::of(atlas::kDefaultMaxResolution),
       .min = 1,
       .max = atlas::kResolutionLimit,
       .api_note = "0 (unset): 1024, at most the daemon's --max-resolution",
       .get = [](const BakeSettings& s) { return SettingValue::of(s.atlas.max_resolution); },
       .set = [](BakeSettings& s,
                 const SettingValue& v) { s.atlas.max_resolution = int(v.number); },
       .active = [](const BakeSettings& s) { return s.atlas.resolution == 0; }});
  t.push_back({.name = "resolution",
               .type = Type::kInt,
               .units = "texels",
               .help = "fixed lightmap side (per page); charts that do not fit get a lower "
                       "density, or several pages (with a warning)",
               .flag = "--resolution",
               .metavar = "N",
               .default_value = SettingValue::of(0),
               .min = 0,
               .max = kI32Max,
               .api_zero = ApiZero::kValue,
               .api_note = "0 (unset): from texel_density; at most the daemon's --max-resolution",
               .get = [](const BakeSettings& s) { return SettingValue::of(s.atlas.resolution); },
               .set =
                   [](BakeSettings& s, const SettingValue& v) {
                     s.atlas.resolution = static_cast<int>(v.number);
                     if (v.number > 0) s.atlas.texel_density = 0;
                   },
               .active = [](const BakeSettings& s) { return s.atlas.resolution > 0; }});
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
  t.push_back({.name = "radiance_cache",
               .type = Type::kBool,
               .units = "",
               .help = "radiance cache: first hits on lightmapped diffuse surfaces sample "
                       "their lights and take the rest of their texel's cached irradiance "
                       "instead of tracing on; its share falls with the sample count, so the "
                       "bake converges to the traced answer "
                       "(docs/accuracy.md \"Radiance cache\"; off in sharded bakes; "
                       "--no-radiance-cache: every path traced to its end)",
               .flag = "--no-radiance-cache",
               .default_value = SettingValue::of(1),
               .api_note = "unset: on (false is a value)",
               LUXEL_BOOL(radiance_cache)});
  t.push_back({.name = "guiding",
               .type = Type::kBool,
               .units = "",
               .help = "first-bounce guiding: each texel draws its first direction from a mix "
                       "of the cosine lobe and a histogram of where its earlier paths found "
                       "light (unbiased; irradiance only, not with --encodings)",
               .flag = "--guiding",
               .default_value = SettingValue::of(0),
               .api_note = "unset means off",
               LUXEL_BOOL(guiding),
               .describe_when = [](const BakeSettings& s) { return s.guiding; }});
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
             if (s.shard_count > 1) s.radiance_cache = false;
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
}

}  // namespace luxel::pipeline::schema
