#include "probes/probe_file.h"

#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "kernels/shared/probe.h"

namespace luxel::probes {
namespace {

template <typename T>
void put(std::string& out, T v) {
  static_assert(std::is_trivially_copyable_v<T>);
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  out.append(b, sizeof(T));
}

uint32_t mode_code(PlacementMode m) {
  switch (m) {
    case PlacementMode::kGrid:
      return 0u;
    case PlacementMode::kFile:
      return 1u;
    case PlacementMode::kAdaptive:
      return 2u;
    case PlacementMode::kNodes:
      return 3u;
  }
  return 0u;
}

const char* kConventions =
    "SH: real, orthonormal over the sphere, world frame; order l=0; l=1 (y, z, x); l=2 (xy, yz, "
    "3z^2-1, xz, x^2-y^2) (Ramamoorthi & Hanrahan 2001 constants). Coefficients c_lm = "
    "integral of incident radiance L(w) Y_lm(w) dw (radiance in W/m^2/sr). Irradiance about a "
    "unit normal n: E(n) = sum_lm sigma_l A_l c_lm Y_lm(n), A = (pi, 2 pi/3, pi/4), sigma the "
    "window (1 for none). A constant radiance L gives c_00 = L sqrt(4 pi) and E = pi L.";

}  // namespace

std::string encode_probe_bin(const ProbeBake& b) {
  const ProbeLayout& l = b.layout;
  const uint32_t n = static_cast<uint32_t>(b.count());
  const uint32_t record =
      4 * (3 + 1 + 1 + 3 + 1 + 1 + 3 * static_cast<uint32_t>(b.sh_count) + 2 * LUX_PROBE_VIS_BINS);
  std::string out;
  out.append("LUXPROBE", 8);
  put(out, kProbeFileVersion);
  put(out, kProbeHeaderBytes);
  put(out, n);
  put(out, static_cast<uint32_t>(b.sh_count));
  put(out, uint32_t{LUX_PROBE_VIS_SIDE});
  put(out, l.grid ? 1u : 0u);
  for (int a = 0; a < 3; ++a) put(out, int32_t{l.dims[a]});
  put(out, l.origin.x);
  put(out, l.origin.y);
  put(out, l.origin.z);
  put(out, l.spacing);
  put(out, static_cast<uint32_t>(b.window));
  for (float s : b.sigma) put(out, s);
  put(out, mode_code(l.mode));
  put(out, record);
  for (int k = 0; k < 3; ++k) put(out, 0u);
  if (l.grid)
    for (int32_t g : l.grid_index) put(out, g);
  const auto& r = b.bake;
  for (size_t p = 0; p < n; ++p) {
    put(out, l.positions[p].x);
    put(out, l.positions[p].y);
    put(out, l.positions[p].z);
    put(out, l.flags[p]);
    put(out, l.max_distance[p]);
    for (int c = 0; c < 3; ++c) put(out, r.irradiance[p * 4 + size_t(c)]);
    put(out, r.rel_error[p]);
    put(out, r.samples[p]);
    const float* sh = b.sh(p);
    for (int i = 0; i < b.sh_count * 3; ++i) put(out, sh[i]);
    for (size_t k = 0; k < LUX_PROBE_VIS_BINS; ++k) {
      const size_t at = (p * LUX_PROBE_VIS_BINS + k) * 4;
      put(out, r.probe_visibility.empty() ? 0.0f : r.probe_visibility[at]);
      put(out, r.probe_visibility.empty() ? 0.0f : r.probe_visibility[at + 1]);
    }
  }
  return out;
}

std::string encode_probe_json(const ProbeBake& b) {
  nlohmann::json j;
  j["format"] = "luxel-probes";
  j["version"] = kProbeFileVersion;
  j["binary"] = "probes.bin";
  j["layout"] = nlohmann::json::parse(b.layout.describe_json());
  j["basis"] = {{"name", b.sh_count == 9 ? "sh2" : "sh1"},
                {"count", b.sh_count},
                {"conventions", kConventions},
                {"units",
                 "coefficients of radiance (W/m^2/sr) over steradians; irradiance "
                 "W/m^2; positions and distances in scene units"}};
  j["window"] = {{"name", sh_window_name(b.window)},
                 {"sigma", {b.sigma[0], b.sigma[1], b.sigma[2]}},
                 {"applied", "at evaluation (the stored coefficients are the raw projection)"}};
  j["negative_irradiance"] = {
      {"normals_per_probe", 256}, {"raw", b.negative_raw}, {"windowed", b.negative_windowed}};
  j["visibility"] = {{"bins", "octahedral, z up (Cigolle et al. 2014)"},
                     {"side", LUX_PROBE_VIS_SIDE},
                     {"moments",
                      "mean and mean squared distance to the first hit, misses at "
                      "max_distance (DDGI)"}};
  j["bake"] = {{"paths", b.bake.paths},
               {"mean_samples_per_probe", b.bake.mean_spp},
               {"min_samples_per_probe", b.bake.min_spp},
               {"error", b.bake.error},
               {"seconds", b.bake.seconds},
               {"termination", pipeline::termination_name(b.bake.termination)}};
  nlohmann::json probes = nlohmann::json::array();
  for (size_t p = 0; p < b.count(); ++p) {
    const Vec3 x = b.layout.positions[p];
    const float* sh = b.sh(p);
    nlohmann::json c = nlohmann::json::array();
    for (int i = 0; i < b.sh_count; ++i) c.push_back({sh[i * 3], sh[i * 3 + 1], sh[i * 3 + 2]});
    probes.push_back(
        {{"position", {x.x, x.y, x.z}},
         {"flags", b.layout.flags[p]},
         {"irradiance",
          {b.bake.irradiance[p * 4], b.bake.irradiance[p * 4 + 1], b.bake.irradiance[p * 4 + 2]}},
         {"rel_error", b.bake.rel_error[p]},
         {"sh", c}});
  }
  j["probes"] = std::move(probes);
  return j.dump(1);
}

std::string describe_probes_json(const ProbeBake& b) {
  nlohmann::json j;
  j["files"] = {"probes.bin", "probes.json"};
  j["layout"] = nlohmann::json::parse(b.layout.describe_json());
  j["basis"] = b.sh_count == 9 ? "sh2" : "sh1";
  j["window"] = sh_window_name(b.window);
  j["negative_irradiance"] = {{"raw", b.negative_raw}, {"windowed", b.negative_windowed}};
  j["paths"] = b.bake.paths;
  j["seconds"] = b.bake.seconds;
  j["error"] = b.bake.error;
  j["termination"] = pipeline::termination_name(b.bake.termination);
  return j.dump();
}

Status write_probe_files(const ProbeBake& b, const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return internal_error("cannot create " + dir + ": " + ec.message());
  for (const auto& [name, bytes] :
       {std::pair<std::string, std::string>{"probes.bin", encode_probe_bin(b)},
        {"probes.json", encode_probe_json(b)}}) {
    const std::string path = dir + "/" + name;
    std::ofstream f(path, std::ios::binary);
    f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!f) return internal_error("cannot write " + path);
  }
  // The lightmap's manifest describes the probe layout too.
  const std::string manifest = dir + "/manifest.json";
  std::ifstream in(manifest);
  if (!in) return Status::ok();
  nlohmann::json m;
  try {
    m = nlohmann::json::parse(in);
  } catch (const std::exception& e) {
    return internal_error("cannot read " + manifest + ": " + e.what());
  }
  m["probes"] = nlohmann::json::parse(describe_probes_json(b));
  std::ofstream out(manifest, std::ios::binary | std::ios::trunc);
  out << m.dump(2);
  if (!out) return internal_error("cannot write " + manifest);
  return Status::ok();
}

}  // namespace luxel::probes
