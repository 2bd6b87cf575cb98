// The settings schema's table, second part: sky and sun, directional
// encodings, ablation switches, reports and outputs, light probes, the
// daemon's job.
#include "encode/basis.h"
#include "settings/schema_table.h"

namespace luxel::pipeline::schema {
namespace {

// "irradiance" (always baked) and every directional encoding.
// (kEncodingNames holds string literals: .data() is their C string.)
std::vector<const char*> encoding_choices() {
  std::vector<const char*> c = {"irradiance"};
  for (std::string_view name : encode::kEncodingNames) c.push_back(name.data());
  return c;
}

}  // namespace

void add_scene_and_output_settings(std::vector<Setting>& t) {
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
       .choices = encoding_choices(),
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
               "raw irradiance.exr (auto: oidn when its library loads, else off; atrous: "
               "edge-avoiding a-trous wavelets; oidn: Intel Open Image Denoise's RTLightmap filter "
               "per chart, a-trous when its library is missing; off: none)",
       .flag = "--denoise",
       .metavar = "D",
       .default_value = SettingValue::of_text(choice_name(Denoise::kAuto)),
       .choices = choice_list<Denoise>(),
       LUXEL_CHOICE(denoise),
       .described = Described::kUnlessDefault});
  t.push_back({.name = "seam_stitch",
               .type = Type::kBool,
               .units = "",
               .help = "least-squares stitching of lightmap UV seams so bilinear fetches on both "
                       "sides agree; baked texels move at most one standard error, seams of "
                       "charts under 3 texels wide are left alone (--no-seam-stitch: off)",
               .flag = "--no-seam-stitch",
               .default_value = SettingValue::of(1),
               .api_note = "unset means on",
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
}

}  // namespace luxel::pipeline::schema
