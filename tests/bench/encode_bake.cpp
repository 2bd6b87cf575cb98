// bench_encode_bake: directional encodings in real bakes (core thesis Ch. 7-8,
// "Measurements"), one run on one device:
//   1. a high-sample irradiance-only bake per scene (the reference);
//   2. one bake with every encoding at a lower sample count: the diffuse
//      irradiance each encoding reconstructs at the texel's normal against
//      the reference (relative RMSE over fully covered texels), next to the
//      same bake's own irradiance channel (the noise floor of that sample
//      count), and each encoding's device state per texel;
//   3. bake-time overhead: irradiance only vs irradiance + one encoding, same
//      paths (each configuration baked twice, the second one measured).
//
//   bench_encode_bake [--spp N] [--reference-spp N] [--resolution N] [--quick] [SCENE...]
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "atlas/sample_info.h"
#include "bake/bake.h"
#include "device/context.h"
#include "encode/basis.h"
#include "scene/gltf_import.h"

using namespace luxel;

namespace {

pipeline::BakeResult must(Result<pipeline::BakeResult> r) {
  if (!r) {
    std::fprintf(stderr, "bench_encode_bake: %s\n", r.status().to_string().c_str());
    std::exit(1);
  }
  return std::move(r.value());
}

// World-space geometric normal of the triangle under a texel's first valid
// sample (the scenes here are flat-shaded; good enough for a diffuse
// reconstruction whose lobes are much wider than any normal difference).
std::vector<Vec3> texel_normals(const scene::Scene& s, const atlas::SampleInfo& info) {
  std::vector<Vec3> n(info.offsets.size(), Vec3{0, 0, 0});
  for (uint32_t t : info.covered_texels) {
    const atlas::SamplePoint p = atlas::sample_point(info, t, 0);
    const scene::Instance& inst = s.instances[p.instance];
    const scene::Mesh& m = s.meshes[size_t(inst.mesh)];
    Vec3 v[3];
    for (int k = 0; k < 3; ++k)
      v[k] = transform_point(inst.object_to_world,
                             m.positions[m.indices[p.triangle * 3 + uint32_t(k)]]);
    n[t] = normalize(cross(v[1] - v[0], v[2] - v[0]));
  }
  return n;
}

double luminance(const float* rgb) {
  return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2];
}

struct Error {
  double rel_rmse = 0;  // sqrt(mean (x - ref)^2) / mean ref, luminance
};

template <typename F>
Error compare(const pipeline::BakeResult& ref, const F& value) {
  double se = 0, sum_ref = 0;
  size_t n = 0;
  for (size_t t = 0; t < size_t(ref.width) * ref.height; ++t) {
    if (ref.irradiance[t * 4 + 3] < 1.0f) continue;
    const double r = luminance(&ref.irradiance[t * 4]);
    const double x = value(t);
    se += (x - r) * (x - r);
    sum_ref += r;
    ++n;
  }
  Error e;
  e.rel_rmse = n ? std::sqrt(se / n) / (sum_ref / n) : 0;
  return e;
}

}  // namespace

int main(int argc, char** argv) {
  uint32_t spp = 256, ref_spp = 4096;
  int resolution = 128;
  bool quick = false;
  std::vector<std::string> scenes;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--spp" && i + 1 < argc)
      spp = uint32_t(std::atoi(argv[++i]));
    else if (a == "--reference-spp" && i + 1 < argc)
      ref_spp = uint32_t(std::atoi(argv[++i]));
    else if (a == "--resolution" && i + 1 < argc)
      resolution = std::atoi(argv[++i]);
    else if (a == "--quick")
      quick = true;
    else
      scenes.push_back(a);
  }
  if (quick) {
    spp = 16;
    ref_spp = 64;
    resolution = 32;
  }
  if (scenes.empty()) {
    scenes = {std::string(LUXEL_SCENES_DIR) + "/cornell_box.gltf",
              std::string(LUXEL_SCENES_DIR) + "/foliage_instanced.glb"};
    if (quick) scenes.resize(1);
  }
  auto ctx = device::Context::create();
  if (!ctx) {
    std::fprintf(stderr, "bench_encode_bake: %s\n", ctx.status().to_string().c_str());
    return 1;
  }
  std::printf("device: %s\n", ctx.value()->info().describe().c_str());
  const std::vector<std::string> names = {"sh1",       "sh2",           "sg9",           "sg12",
                                          "sg12-hemi", "ambient-dice9", "ambient-dice12"};
  int failures = 0;

  for (const auto& path : scenes) {
    auto scene = scene::import_gltf_file(path);
    if (!scene) {
      std::fprintf(stderr, "bench_encode_bake: %s\n", scene.status().to_string().c_str());
      return 1;
    }
    const scene::Scene& s = scene.value();
    pipeline::BakeSettings base;
    base.atlas.resolution = resolution;
    base.max_bounces = 3;
    base.seed = 3;
    base.lights.sky.kind = pipeline::SkySettings::Kind::kConstant;
    base.lights.sky.color = {0.5f, 0.6f, 0.8f};
    base.lights.sun.enabled = true;
    base.lights.sun.direction = {0.3f, -1.0f, 0.2f};
    base.lights.sun.illuminance = 5.0f;
    base.progress_interval_s = 1e9;

    pipeline::BakeSettings ref_settings = base;
    ref_settings.samples_per_texel = ref_spp;
    ref_settings.seed = 99;
    const pipeline::BakeResult ref = must(pipeline::bake(s, ref_settings, *ctx.value()));

    pipeline::BakeSettings all = base;
    all.samples_per_texel = spp;
    all.encodings.names = names;
    const pipeline::BakeResult enc = must(pipeline::bake(s, all, *ctx.value()));
    auto atlas = atlas::build_atlas(s, all.atlas);
    auto info = atlas ? atlas::build_sample_info(s, atlas.value())
                      : Result<atlas::SampleInfo>(atlas.status());
    if (!info) return 1;
    const std::vector<Vec3> normals = texel_normals(s, info.value());

    std::printf(
        "\n%s, %dx%d, %zu covered texels, 3 bounces, sky + sun; reference: irradiance "
        "only, %u spp (its own error estimate %.4f)\n\n",
        path.substr(path.find_last_of('/') + 1).c_str(), enc.width, enc.height, enc.covered_texels,
        ref_spp, ref.error);
    std::printf(
        "| encoding (%u spp) | diffuse rel. RMSE vs reference | device state bytes/texel | "
        "file floats/texel | running residual |\n|---|---:|---:|---:|---:|\n",
        spp);
    const Error own = compare(ref, [&](size_t t) { return luminance(&enc.irradiance[t * 4]); });
    std::printf("| irradiance channel of the same bake | %.4f | 44 | 4 | - |\n", own.rel_rmse);
    for (const auto& e : enc.encodings) {
      auto basis = encode::SphericalBasis::from_name(e.name, all.encodings.sg_sharpness).value();
      const bool tangent = e.name == "ambient-dice9" || e.name.find("-hemi") != std::string::npos;
      const Error err = compare(ref, [&](size_t t) {
        float rgb[3];
        for (int c = 0; c < 3; ++c) {
          std::vector<float> coeffs(size_t(e.count));
          for (int i = 0; i < e.count; ++i)
            coeffs[size_t(i)] = e.coefficients[(t * size_t(e.count) + size_t(i)) * 3 + size_t(c)];
          rgb[c] = basis.diffuse_irradiance(coeffs.data(), tangent ? Vec3{0, 0, 1} : normals[t]);
        }
        return luminance(rgb);
      });
      if (!std::isfinite(err.rel_rmse)) ++failures;
      const std::string residual =
          e.name.rfind("sh", 0) == 0 ? "- (projection)" : strprintf("%.4g", e.residual_rms);
      std::printf("| %s | %.4f | %d | %d | %s |\n", e.name.c_str(), err.rel_rmse,
                  (e.count + 1) * 16, e.count * 3, residual.c_str());
    }

    // Bake-time overhead of each encoding on its own: every configuration
    // baked once to warm up (program build, PoCL JIT), then `repeats` rounds
    // over all configurations in turn, keeping each one's fastest bake, so a
    // burst of load from other processes does not land on one row only.
    std::vector<std::vector<std::string>> configs = {{}};
    for (const auto& n : names) configs.push_back({n});
    configs.push_back(names);
    auto bake_config = [&](const std::vector<std::string>& enc_names) {
      pipeline::BakeSettings st = base;
      st.samples_per_texel = spp;
      st.encodings.names = enc_names;
      return must(pipeline::bake(s, st, *ctx.value()));
    };
    auto accumulate_ms = [](const pipeline::BakeResult& r) {
      for (const auto& [k, ms] : r.kernel_ms)
        if (k == "accumulate") return ms;
      return 0.0;
    };
    std::vector<double> best(configs.size(), 1e30), best_acc(configs.size(), 1e30);
    for (const auto& c : configs) bake_config(c);
    for (int round = 0; round < (quick ? 1 : 3); ++round)
      for (size_t i = 0; i < configs.size(); ++i) {
        const pipeline::BakeResult r = bake_config(configs[i]);
        best[i] = std::min(best[i], r.seconds);
        best_acc[i] = std::min(best_acc[i], accumulate_ms(r));
      }
    std::printf(
        "\n| configuration (%u spp, fastest of %d) | seconds | ratio to irradiance only | "
        "accumulate ms |\n|---|---:|---:|---:|\n",
        spp, quick ? 1 : 3);
    for (size_t i = 0; i < configs.size(); ++i) {
      const std::string label = configs[i].empty()       ? "irradiance only"
                                : configs[i].size() == 1 ? "+ " + configs[i][0]
                                                         : "+ all seven";
      std::printf("| %s | %.2f | %.2f | %.1f |\n", label.c_str(), best[i], best[i] / best[0],
                  best_acc[i]);
    }
  }
  return failures == 0 ? 0 : 1;
}
