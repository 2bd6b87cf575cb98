#include "post/bake_outputs.h"

#include <cctype>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <system_error>

#include "common/atomic_file.h"
#include "luxel_version.h"
#include "output/dilate.h"
#include "output/exr.h"
#include "output/preview.h"
#include "post/bake_seams.h"
#include "post/lightmapped_gltf.h"

namespace luxel::pipeline {
namespace {

// The denoiser's manifest object without its timings, for the EXR attribute:
// the same bake gives the same file bytes (the manifest keeps the seconds).
std::string denoise_attribute(const std::string& denoise_json) {
  nlohmann::json j = nlohmann::json::parse(denoise_json, nullptr, /*allow_exceptions=*/false);
  if (!j.is_object()) return denoise_json;
  for (auto it = j.begin(); it != j.end();)
    it = it.key().find("seconds") != std::string::npos ? j.erase(it) : std::next(it);
  return j.dump();
}

// The manifest's "uv_layout" object for generated UVs.
std::string uv_layout_json(const GeneratedUvLayout& g) {
  const uv::UvReport& r = g.report;
  nlohmann::json j = {{"source", "generated"},
                      {"reason", g.reason},
                      {"meshes", r.meshes},
                      {"charts", r.charts},
                      {"triangles", r.triangles},
                      {"unplaced_triangles", r.unplaced_triangles},
                      {"seam_vertices", r.seam_vertices},
                      {"stretch_l2", r.stretch_l2},
                      {"stretch_linf", r.stretch_linf},
                      {"packing_efficiency", r.efficiency},
                      {"texel_density_spread", r.density_spread},
                      {"overlapping_texels", r.overlapping_texels},
                      {"pages", r.pages},
                      {"pack_attempts", r.pack_attempts},
                      {"chart_seconds", r.chart_seconds},
                      {"pack_seconds", r.pack_seconds},
                      {"seconds", r.total_seconds}};
  return j.dump();
}

output::Image to_image(int w, int h, int channels, const std::vector<float>& px) {
  output::Image img;
  img.width = w;
  img.height = h;
  img.channels = channels;
  img.pixels = px;
  return img;
}

std::string series_csv(const BakeResult& r) {
  // rmse / rel_mse: against the reference lightmap, empty without one.
  std::string s = "elapsed_s,paths,mean_spp,min_spp,rel_error,rmse,rel_mse\n";
  for (const auto& e : r.series) {
    s += strprintf("%.6f,%llu,%.4f,%u,%.6g,", e.elapsed_s, static_cast<unsigned long long>(e.paths),
                   e.mean_spp, e.min_spp, e.error);
    s += e.rmse >= 0 ? strprintf("%.6g,%.6g\n", e.rmse, e.rel_mse) : std::string(",\n");
  }
  return s;
}

// The manifest's uv_set and uv_sets from primitives per TEXCOORD index.
void set_uv_sets(const std::map<int, size_t>& sets, output::Manifest* m) {
  m->uv_sets.clear();
  for (const auto& [set, count] : sets) m->uv_sets["TEXCOORD_" + std::to_string(set)] = count;
  if (m->uv_sets.size() == 1) m->uv_set = m->uv_sets.begin()->first;
  if (m->uv_sets.size() > 1) m->uv_set = "per primitive (extras.lightmapTexCoord)";
}

}  // namespace

output::Manifest make_manifest(const scene::Scene& scene, const BakeSettings& settings,
                               const BakeResult& result, const std::string& scene_sha256) {
  output::Manifest m;
  m.luxel_version = LUXEL_VERSION;
  m.git_revision = LUXEL_GIT_REVISION;
  m.scene_name = scene.source_name;
  m.scene_sha256 = scene_sha256;
  m.pages = result.atlas.pages;
  m.texels_per_unit = result.atlas.texels_per_unit;
  m.width = result.width;
  m.height = result.height / std::max(1, result.atlas.pages);
  m.encoding = "irradiance";
  m.units =
      "irradiance E in W/m^2 on the front side of the surface (radiometric; glTF emissive "
      "radiance and light intensities taken 1:1); outgoing diffuse radiance = albedo * E / pi";
  std::map<int, size_t> sets;
  for (const scene::Mesh& mesh : scene.meshes)
    for (const scene::Mesh::PrimitiveSpan& span : mesh.primitive_spans)
      ++sets[span.lightmap_texcoord];
  set_uv_sets(sets, &m);
  m.atlas_mode = atlas::atlas_mode_name(result.atlas.mode);
  for (const auto& stacked : result.atlas.placements) {
    const atlas::InstancePlacement p = atlas::page_relative(result.atlas, stacked);
    output::Manifest::Instance inst;
    inst.page = p.page;
    const auto& si = scene.instances[p.instance];
    inst.name = si.name;
    inst.node = si.node_index;
    inst.mesh = si.mesh;
    for (int k = 0; k < 2; ++k) {
      inst.scale[k] = p.scale[k];
      inst.offset[k] = p.offset[k];
    }
    for (int k = 0; k < 4; ++k) inst.rect[k] = p.rect[k];
    m.instances.push_back(inst);
  }
  m.settings = settings.describe();
  m.features = result.features;
  m.device = result.device;
  m.intersector = result.intersector;
  m.import_warnings = scene.import_stats.warnings;
  for (const std::string& w : result.atlas.warnings)
    m.import_warnings.push_back("lightmap layout: " + w);
  m.stats.seconds = result.seconds;
  m.stats.paths = result.paths;
  m.stats.mean_spp = result.mean_spp;
  m.stats.min_spp = result.min_spp;
  m.stats.error_estimate = result.error;
  m.stats.rmse = result.rmse;
  m.stats.rel_mse = result.rel_mse;
  m.stats.nonfinite_dropped = result.nonfinite_dropped;
  m.stats.termination = termination_name(result.termination);
  m.stats.covered_texels = result.covered_texels;
  m.stats.peak_device_bytes = result.peak_device_bytes;
  m.stats.device_memory_budget = result.device_memory_budget;
  m.stats.tiles = result.tiles;
  m.stats.batch_paths = result.batch_paths;
  m.dilation_texels = settings.dilation_texels;
  for (const auto& e : result.encodings) m.encodings_json.push_back(e.manifest_json);
  if (result.uv_layout) m.uv_layout_json = uv_layout_json(*result.uv_layout);
  m.denoise_json = result.denoise_json;  // also says why a denoise was skipped
  if (!result.encodings.empty()) {
    m.encoding = "irradiance";
    for (const auto& e : result.encodings) m.encoding += "+" + e.name;
  }
  return m;
}

std::string lightmapped_glb_name(const std::string& scene_file_name) {
  std::string stem = std::filesystem::path(scene_file_name).stem().string();
  if (stem.empty()) stem = "scene";
  for (char& c : stem)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-')) c = '_';
  return stem + "_lightmapped.glb";
}

namespace {

// `owned`: the same result as `result`, whose images may be moved out as
// they are written (null: they are copied).
Result<OutputPaths> write_outputs(const std::string& dir, const scene::Scene& scene,
                                  const BakeSettings& settings, const BakeResult& result,
                                  BakeResult* owned, const std::string& scene_sha256,
                                  const std::string& source_path, const std::string& scene_name) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec)
    return invalid_argument(
        strprintf("cannot create output folder '%s': %s", dir.c_str(), ec.message().c_str()));
  namespace fs = std::filesystem;
  OutputPaths paths;
  auto at = [&](const char* name) { return (fs::path(dir) / name).string(); };
  paths.irradiance_exr = at("irradiance.exr");
  paths.preview_png = at("preview.png");
  paths.samples_exr = at("samples.exr");
  paths.error_exr = at("rel_error.exr");
  paths.series_csv = at("error_series.csv");
  paths.manifest_json = at("manifest.json");

  // Per page (lightmap arrays; one page: plain names): rows
  // [page * h, (page + 1) * h) of every image, dilated on its own so no
  // page bleeds into another.
  const int pages = std::max(1, result.atlas.pages);
  const int page_h = result.height / pages;
  auto rows = [&](const std::vector<float>& px, int channels, int page) {
    const size_t row = size_t(result.width) * size_t(channels);
    return std::vector<float>(px.begin() + static_cast<long>(row * size_t(page_h) * page),
                              px.begin() + static_cast<long>(row * size_t(page_h) * (page + 1)));
  };
  auto name = [&](const std::string& stem, const char* ext, int page) {
    return pages == 1 ? stem + ext : strprintf("%s_%d%s", stem.c_str(), page, ext);
  };
  std::vector<output::Manifest::File> files;
  auto add_file = [&](const std::string& role, const std::string& file, const char* format,
                      const std::string& description, int page) {
    output::Manifest::File f{role, file, format, description, pages == 1 ? -1 : page};
    files.push_back(f);
    paths.files.push_back(file);
  };
  // The name the user knows the scene by: the daemon passes the upload's
  // name, so no server path ends up in artifacts (and identical bakes of
  // one upload are identical files).
  const std::string shown_name = scene_name.empty() ? scene.source_name : scene_name;
  const std::map<std::string, std::string> meta = {
      {"luxel/encoding", "irradiance"},
      {"luxel/units", "W/m^2"},
      {"luxel/alpha", "fraction of the texel covered by geometry"},
      {"luxel/scene", shown_name}};
  BakeSeamStitch seams(result);
  // A page's pixels: a copy of its rows, or with `owned` (one page) the
  // plane itself, moved out: output assembly then holds no second
  // full-size copy of an image beside the result.
  auto take = [&](std::vector<float>* plane, const std::vector<float>& px, int channels, int page) {
    if (owned && pages == 1) return std::move(*plane);
    return rows(px, channels, page);
  };
  for (int page = 0; page < pages; ++page) {
    const std::string page_note = pages == 1 ? "" : strprintf(" (page %d)", page);
    // Directional encodings are dilated with the irradiance map's coverage
    // so every channel pads the same texels.
    output::Image coverage = to_image(result.width, page_h, 1, {});
    coverage.pixels.resize(size_t(result.width) * size_t(page_h));
    const size_t first = size_t(result.width) * size_t(page_h) * size_t(page);
    for (size_t t = 0; t < coverage.pixels.size(); ++t)
      coverage.pixels[t] = result.irradiance[(first + t) * 4 + 3];
    output::Image lightmap = to_image(result.width, page_h, 4, {});
    lightmap.pixels = take(owned ? &owned->irradiance : nullptr, result.irradiance, 4, page);
    LUXEL_RETURN_IF_ERROR(output::dilate(lightmap, settings.dilation_texels));
    // After dilation: bilinear fetches along seams read padding (bake_seams.h).
    seams.stitch_page(page, lightmap, coverage, {});

    const std::string irradiance = name("irradiance", ".exr", page);
    const std::string preview = name("preview", ".png", page);
    const std::string samples = name("samples", ".exr", page);
    const std::string error = name("rel_error", ".exr", page);
    LUXEL_RETURN_IF_ERROR(
        output::write_exr(at(irradiance.c_str()), lightmap, {"R", "G", "B", "A"}, meta));
    LUXEL_RETURN_IF_ERROR(output::write_png_preview(at(preview.c_str()), lightmap));
    lightmap = {};
    {
      output::Image spp = to_image(result.width, page_h, 1, {});
      spp.pixels = take(owned ? &owned->samples : nullptr, result.samples, 1, page);
      LUXEL_RETURN_IF_ERROR(output::write_exr(at(samples.c_str()), spp, {"Y"},
                                              {{"luxel/content", "samples per texel"}}));
    }
    // The relative errors stay: seam stitching weighs the encodings' gaps by them.
    LUXEL_RETURN_IF_ERROR(output::write_exr(
        at(error.c_str()), to_image(result.width, page_h, 1, rows(result.rel_error, 1, page)),
        {"Y"}, {{"luxel/content", "relative standard error of the texel mean"}}));
    add_file("irradiance", irradiance, "exr",
             "RGBA float32, linear irradiance; A = coverage" + page_note, page);
    add_file("preview", preview, "png",
             "tone-mapped sRGB preview of the dilated lightmap" + page_note, page);
    add_file("samples", samples, "exr", "float32 Y: samples per texel" + page_note, page);
    add_file("rel_error", error, "exr", "float32 Y: relative standard error per texel" + page_note,
             page);
    if (!result.irradiance_denoised.empty()) {
      // The denoised map, dilated the same way; the raw one above stays the bake.
      output::Image denoised = to_image(result.width, page_h, 4, {});
      denoised.pixels =
          take(owned ? &owned->irradiance_denoised : nullptr, result.irradiance_denoised, 4, page);
      LUXEL_RETURN_IF_ERROR(output::dilate(denoised, settings.dilation_texels));
      seams.stitch_denoised_page(page, denoised, coverage);
      std::map<std::string, std::string> denoised_meta = meta;
      denoised_meta["luxel/denoise"] = denoise_attribute(result.denoise_json);
      const std::string file = name("irradiance_denoised", ".exr", page);
      LUXEL_RETURN_IF_ERROR(
          output::write_exr(at(file.c_str()), denoised, {"R", "G", "B", "A"}, denoised_meta));
      add_file("irradiance_denoised", file, "exr",
               "RGBA float32, irradiance.exr filtered by the denoiser (see denoise in this "
               "manifest); A = coverage" +
                   page_note,
               page);
      if (page == 0) paths.irradiance_denoised_exr = at(file.c_str());
    }
    if (page == 0) {
      paths.irradiance_exr = at(irradiance.c_str());
      paths.preview_png = at(preview.c_str());
      paths.samples_exr = at(samples.c_str());
      paths.error_exr = at(error.c_str());
    }
    // Directional encodings: one EXR each, channels c00.R .. cNN.B, one at
    // a time (dilated, stitched, written, released).
    for (size_t k = 0; k < result.encodings.size(); ++k) {
      const auto& e = result.encodings[k];
      std::vector<std::string> names;
      for (int i = 0; i < e.count; ++i)
        for (const char* c : {"R", "G", "B"}) names.push_back(strprintf("c%02d.%s", i, c));
      output::Image coefficients = to_image(result.width, page_h, e.count * 3, {});
      coefficients.pixels = take(owned ? &owned->encodings[k].coefficients : nullptr,
                                 e.coefficients, e.count * 3, page);
      LUXEL_RETURN_IF_ERROR(output::dilate(coefficients, coverage, settings.dilation_texels));
      seams.stitch_encoding(page, k, coefficients, coverage);
      const std::string file = name(e.name, ".exr", page);
      LUXEL_RETURN_IF_ERROR(output::write_exr(at(file.c_str()), coefficients, names,
                                              {{"luxel/encoding", e.name},
                                               {"luxel/units", "radiance coefficients, W/(m^2 sr)"},
                                               {"luxel/scene", shown_name}}));
      coefficients = {};
      paths.encodings.push_back(at(file.c_str()));
      add_file(e.name, file, "exr",
               strprintf("float32, %d coefficients x RGB of the %s basis (see encodings in this "
                         "manifest)",
                         e.count, e.name.c_str()) +
                   page_note,
               page);
      if (e.coefficients_denoised.empty()) continue;
      // The denoised coefficients (SH through OIDN's directional mode),
      // dilated like the raw ones; the raw file above stays the bake.
      output::Image denoised = to_image(result.width, page_h, e.count * 3, {});
      denoised.pixels = take(owned ? &owned->encodings[k].coefficients_denoised : nullptr,
                             e.coefficients_denoised, e.count * 3, page);
      LUXEL_RETURN_IF_ERROR(output::dilate(denoised, coverage, settings.dilation_texels));
      const std::string dfile = name(e.name + "_denoised", ".exr", page);
      LUXEL_RETURN_IF_ERROR(
          output::write_exr(at(dfile.c_str()), denoised, names,
                            {{"luxel/encoding", e.name},
                             {"luxel/units", "radiance coefficients, W/(m^2 sr)"},
                             {"luxel/scene", shown_name},
                             {"luxel/denoise", denoise_attribute(result.denoise_json)}}));
      add_file(e.name + "_denoised", dfile, "exr",
               strprintf("float32, %s.exr's coefficients filtered by the denoiser (see denoise in "
                         "this manifest)",
                         e.name.c_str()) +
                   page_note,
               page);
    }
  }

  const std::string csv = series_csv(result);
  LUXEL_RETURN_IF_ERROR(write_file_atomic(paths.series_csv, csv.data(), csv.size()));

  output::Manifest m = make_manifest(scene, settings, result, scene_sha256);
  m.scene_name = shown_name;
  m.seam_stitch_json = seams.manifest_json();
  add_file("error_series", "error_series.csv", "csv", "error estimate against time", -1);
  if (result.final_state) {
    // A shard of a distributed bake: its accumulators, for the merge
    // (shards/shard_merge.h).
    paths.accumulators_bin = at("accumulators.bin");
    LUXEL_RETURN_IF_ERROR(write_checkpoint(paths.accumulators_bin, *result.final_state));
    add_file("accumulators", "accumulators.bin", "luxel-checkpoint",
             strprintf("shard %u of %u: per-texel accumulators (checkpoint format) for the exact "
                       "merge of the shards",
                       result.final_state->shard_index, result.final_state->shard_count),
             -1);
  }
  m.files = std::move(files);
  if (result.uv_layout && !source_path.empty()) {
    const std::string glb = lightmapped_glb_name(shown_name);
    auto written = write_lightmapped_glb(source_path, scene, result, at(glb.c_str()));
    if (!written) return written.status();
    for (const std::string& w : written.value().warnings) m.import_warnings.push_back(w);
    set_uv_sets(written.value().texcoord_primitives, &m);
    paths.lightmapped_glb = at(glb.c_str());
    m.files.push_back({"lightmapped_gltf", glb, "glb",
                       "the scene with the generated lightmap UVs in " + m.uv_set +
                           " (each primitive's extras.lightmapTexCoord names the set) and each "
                           "node's extras.lightmapScaleOffset (and lightmapIndex: its page)",
                       -1});
    paths.files.push_back(glb);
  }
  LUXEL_RETURN_IF_ERROR(output::write_manifest(paths.manifest_json, m));
  paths.files.push_back("manifest.json");
  return paths;
}

}  // namespace

Result<OutputPaths> write_bake_outputs(const std::string& dir, const scene::Scene& scene,
                                       const BakeSettings& settings, const BakeResult& result,
                                       const std::string& scene_sha256,
                                       const std::string& source_path,
                                       const std::string& scene_name) {
  return write_outputs(dir, scene, settings, result, nullptr, scene_sha256, source_path,
                       scene_name);
}

Result<OutputPaths> write_bake_outputs_releasing(const std::string& dir, const scene::Scene& scene,
                                                 const BakeSettings& settings, BakeResult& result,
                                                 const std::string& scene_sha256,
                                                 const std::string& source_path,
                                                 const std::string& scene_name) {
  return write_outputs(dir, scene, settings, result, &result, scene_sha256, source_path,
                       scene_name);
}

}  // namespace luxel::pipeline
