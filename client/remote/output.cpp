#include "remote/output.h"

#include <google/protobuf/util/json_util.h>

#include <algorithm>
#include <cstdio>
#include <ctime>

#include "common/status.h"

namespace luxel::cli::remote {
namespace {

std::string format_time(double unix_s) {
  if (unix_s <= 0) return "-";
  const std::time_t t = static_cast<std::time_t>(unix_s);
  std::tm tm{};
  localtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%d %H:%M:%S", &tm);
  return buf;
}

std::string format_bytes(uint64_t bytes) {
  if (bytes < 1024) return std::to_string(bytes) + " B";
  if (bytes < (1u << 20)) return strprintf("%.1f KiB", bytes / 1024.0);
  if (bytes < (1u << 30)) return strprintf("%.1f MiB", bytes / 1048576.0);
  return strprintf("%.2f GiB", bytes / 1073741824.0);
}

std::string join(const google::protobuf::RepeatedPtrField<std::string>& items) {
  std::string out;
  for (const auto& s : items) out += (out.empty() ? "" : ", ") + s;
  return out.empty() ? "-" : out;
}

}  // namespace

nlohmann::json to_json(const google::protobuf::Message& message) {
  google::protobuf::util::JsonPrintOptions options;
  options.preserve_proto_field_names = true;
  options.always_print_primitive_fields = true;
  std::string text;
  if (!google::protobuf::util::MessageToJsonString(message, &text, options).ok()) return {};
  return nlohmann::json::parse(text, nullptr, false);
}

void print_json_line(const nlohmann::json& object) {
  std::fputs(object.dump().c_str(), stdout);
  std::fputc('\n', stdout);
  std::fflush(stdout);
}

std::string state_name(luxel::v1::BakeState state) {
  std::string name = luxel::v1::BakeState_Name(state);
  const std::string prefix = "BAKE_STATE_";
  return name.rfind(prefix, 0) == 0 ? name.substr(prefix.size()) : name;
}

bool parse_state(const std::string& text, luxel::v1::BakeState& state) {
  std::string upper = text;
  std::transform(upper.begin(), upper.end(), upper.begin(),
                 [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  if (upper.rfind("BAKE_STATE_", 0) != 0) upper = "BAKE_STATE_" + upper;
  return luxel::v1::BakeState_Parse(upper, &state) && state != luxel::v1::BAKE_STATE_UNSPECIFIED;
}

bool is_terminal(luxel::v1::BakeState state) {
  return state == luxel::v1::BAKE_STATE_SUCCEEDED || state == luxel::v1::BAKE_STATE_FAILED ||
         state == luxel::v1::BAKE_STATE_CANCELLED;
}

ProgressView progress_view(const luxel::v1::BakeProgress& p) {
  ProgressView v;
  v.fraction = p.fraction();
  v.mean_spp = p.mean_spp();
  v.min_spp = p.min_spp();
  v.error = p.error();
  v.elapsed_s = p.elapsed_s();
  v.eta_s = p.eta_s();
  v.rmse = p.rmse();
  v.rel_mse = p.rel_mse();
  return v;
}

void print_scene_info(const luxel::v1::SceneInfo& s) {
  const auto& st = s.statistics();
  std::printf("scene      %s\n", s.scene_id().c_str());
  std::printf("name       %s (%s, %s)%s\n", s.name().c_str(),
              s.format() == luxel::v1::SCENE_FORMAT_GLB ? "glb" : "gltf",
              format_bytes(s.size()).c_str(), s.already_stored() ? ", already stored" : "");
  std::printf("uploaded   %s\n", format_time(s.uploaded_at()).c_str());
  std::printf("contents   %u meshes, %u instances, %llu triangles, %u materials, %u textures\n",
              st.meshes(), st.instances(), static_cast<unsigned long long>(st.triangles()),
              st.materials(), st.textures());
  std::printf("lights     %u point, %u spot, %u directional, %llu emissive triangles\n",
              st.point_lights(), st.spot_lights(), st.directional_lights(),
              static_cast<unsigned long long>(st.emissive_triangles()));
  if (st.bounds_min_size() == 3 && st.bounds_max_size() == 3)
    std::printf("bounds     (%g, %g, %g) .. (%g, %g, %g)\n", st.bounds_min(0), st.bounds_min(1),
                st.bounds_min(2), st.bounds_max(0), st.bounds_max(1), st.bounds_max(2));
  for (const auto& w : s.warnings()) std::printf("warning    %s\n", w.c_str());
}

void print_bake_info(const luxel::v1::BakeInfo& b) {
  const auto& p = b.progress();
  std::printf("bake       %s\n", b.bake_id().c_str());
  std::printf("scene      %s\n", b.scene_id().c_str());
  std::printf("state      %s%s\n", state_name(b.state()).c_str(),
              b.resumed() > 0 ? strprintf(" (resumed %u times)", b.resumed()).c_str() : "");
  std::printf("progress   %.1f%%  spp %.1f (min %u)  error %.4f  %s elapsed  ETA %s  %llu paths\n",
              100.0 * p.fraction(), p.mean_spp(), p.min_spp(), p.error(),
              format_duration(p.elapsed_s()).c_str(), format_duration(p.eta_s()).c_str(),
              static_cast<unsigned long long>(p.paths()));
  std::printf("submitted  %s\nstarted    %s\nfinished   %s\n",
              format_time(b.submitted_at()).c_str(), format_time(b.started_at()).c_str(),
              format_time(b.finished_at()).c_str());
  if (!b.features().empty()) std::printf("features   %s\n", b.features().c_str());
  if (b.termination() == "stopped")
    std::printf("stopped by a finish request (luxel cancel --finish)\n");
  else if (!b.termination().empty())
    std::printf("stopped by %s\n", b.termination().c_str());
  else if (b.finish_requested())
    std::printf("finish     requested: ends with the samples it has\n");
  if (!b.error_message().empty()) std::printf("error      %s\n", b.error_message().c_str());
  if (b.nonfinite_dropped() > 0)
    std::printf("warning    %llu non-finite samples dropped\n",
                static_cast<unsigned long long>(b.nonfinite_dropped()));
  std::printf("artifacts  %s\n", join(b.artifacts()).c_str());
}

void print_scene_table(const luxel::v1::ListScenesResponse& r) {
  std::printf("%-64s  %-10s  %10s  %19s  %s\n", "SCENE", "TRIANGLES", "SIZE", "UPLOADED", "NAME");
  for (const auto& s : r.scenes())
    std::printf("%-64s  %-10llu  %10s  %19s  %s\n", s.scene_id().c_str(),
                static_cast<unsigned long long>(s.statistics().triangles()),
                format_bytes(s.size()).c_str(), format_time(s.uploaded_at()).c_str(),
                s.name().c_str());
}

void print_bake_table(const luxel::v1::ListBakesResponse& r) {
  std::printf("%-32s  %-11s  %6s  %8s  %19s  %s\n", "BAKE", "STATE", "DONE", "SPP", "SUBMITTED",
              "SCENE");
  for (const auto& b : r.bakes())
    std::printf("%-32s  %-11s  %5.1f%%  %8.1f  %19s  %.12s\n", b.bake_id().c_str(),
                state_name(b.state()).c_str(), 100.0 * b.progress().fraction(),
                b.progress().mean_spp(), format_time(b.submitted_at()).c_str(),
                b.scene_id().c_str());
}

}  // namespace luxel::cli::remote
