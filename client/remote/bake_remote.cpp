// `luxel bake SCENE --out DIR` on a luxeld daemon: upload the scene unless the
// daemon already stores it, submit the bake, watch it with a progress bar,
// and download every artifact into --out (each verified by sha256).
#include <unistd.h>

#include <cctype>
#include <cstdio>
#include <filesystem>

#include "bake_options.h"
#include "common/status.h"
#include "remote/fetch.h"
#include "remote/output.h"
#include "remote/upload.h"
#include "remote/watch.h"

namespace luxel::cli {
namespace {

using namespace remote;

luxel::v1::BakeSettings to_proto(const BakeArgs& a) {
  const pipeline::BakeSettings& s = a.settings;
  luxel::v1::BakeSettings p;
  p.set_resolution(static_cast<uint32_t>(std::max(s.atlas.resolution, 0)));
  p.set_texel_density(s.atlas.texel_density);
  p.set_samples_per_texel(s.samples_per_texel);
  p.set_time_budget_s(s.time_budget_s);
  p.set_target_error(s.target_error);
  p.set_max_bounces(static_cast<uint32_t>(s.max_bounces));
  p.set_filter(s.filter == pipeline::Filter::kGaussian ? luxel::v1::FILTER_GAUSSIAN
                                                       : luxel::v1::FILTER_BOX);
  if (s.lights.sky.kind == pipeline::SkySettings::Kind::kConstant) {
    auto* sky = p.mutable_sky();
    sky->set_kind(luxel::v1::Sky::KIND_CONSTANT);
    for (float c : {s.lights.sky.color.x, s.lights.sky.color.y, s.lights.sky.color.z}) sky->add_color(c);
    sky->set_intensity(s.lights.sky.intensity);
  }
  if (s.lights.sun.enabled) {
    // Sent in full (the engine's defaults included) so that a remote bake
    // lights the scene exactly as `--local` would.
    auto* sun = p.mutable_sun();
    const auto& in = s.lights.sun;
    for (float d : {in.direction.x, in.direction.y, in.direction.z}) sun->add_direction(d);
    for (float c : {in.color.x, in.color.y, in.color.z}) sun->add_color(c);
    sun->set_illuminance(in.illuminance);
    sun->set_angular_radius_degrees(in.angular_radius_degrees);
  }
  p.set_seed(s.seed);
  if (!s.encodings.names.empty()) {
    std::string list = "irradiance";
    for (const auto& n : s.encodings.names) list += "," + n;
    p.set_encoding(list);
    p.set_sg_sharpness(s.encodings.sg_sharpness);
    p.set_solver(pipeline::solver_name(s.encodings.solver));
    p.set_acceleration(s.encodings.acceleration);
  }
  if (!a.reference_bake.empty()) p.set_reference_bake_id(a.reference_bake);
  if (s.target_metric != pipeline::ErrorMetric::kEstimate)
    p.set_target_metric(pipeline::error_metric_name(s.target_metric));
  p.set_paths_per_iteration(s.paths_per_iteration);
  p.set_dilation_texels(static_cast<uint32_t>(std::max(s.dilation_texels, 0)));
  p.set_priority(a.priority);
  p.set_snapshot_interval_s(a.snapshot_interval_s);
  p.set_snapshot_max_side(a.snapshot_max_side);
  if (a.snapshot_format == "png") p.set_snapshot_format(luxel::v1::SNAPSHOT_FORMAT_PNG);
  if (a.snapshot_format == "exr") p.set_snapshot_format(luxel::v1::SNAPSHOT_FORMAT_EXR);
  if (a.snapshot_format == "none") p.set_snapshot_format(luxel::v1::SNAPSHOT_FORMAT_NONE);
  return p;
}

// Settings the API cannot carry are refused, never silently dropped.
int check_remote_args(const BakeArgs& a) {
  if (!a.local_only.empty()) {
    std::fprintf(stderr,
                 "luxel bake: %s is only available with --local (the luxeld API has no such "
                 "setting)\n", a.local_only.front().c_str());
    return kExitUsage;
  }
  if (a.settings.dilation_texels == 0) {
    std::fprintf(stderr, "luxel bake: --dilate 0 needs --local (0 means the default 2 in the API)\n");
    return kExitUsage;
  }
  if (auto st = pipeline::validate_settings(a.settings); !st.is_ok()) {
    std::fprintf(stderr, "luxel bake: %s\n", st.message().c_str());
    return kExitUsage;
  }
  return kExitOk;
}

bool looks_like_scene_id(const std::string& s) {
  if (s.size() != 64) return false;
  for (char c : s)
    if (!std::isxdigit(static_cast<unsigned char>(c))) return false;
  return true;
}

// The scene the bake uses: a local file (uploaded when the daemon lacks it)
// or the id of a scene the daemon stores.
grpc::Status resolve_scene(Connection& conn, const BakeArgs& a, luxel::v1::SceneInfo& info,
                           bool& uploaded) {
  uploaded = false;
  if (!std::filesystem::exists(a.scene) && looks_like_scene_id(a.scene)) {
    grpc::ClientContext ctx;
    conn.prepare_unary(ctx);
    luxel::v1::GetSceneRequest req;
    req.set_scene_id(a.scene);
    return conn.stub().GetScene(&ctx, req, &info);
  }
  SceneFiles files;
  if (auto st = collect_scene_files(a.scene, files); !st.ok()) return st;
  return ensure_scene(conn, files, a.name, info, uploaded);
}

}  // namespace

int run_bake_remote(BakeArgs& a) {
  if (int rc = check_remote_args(a); rc != kExitOk) return rc;
  const bool json = a.connection.json;
  auto conn = Connection::open("bake", a.connection);
  if (!conn) return kExitUsage;

  luxel::v1::SceneInfo scene;
  bool uploaded = false;
  if (auto st = resolve_scene(*conn, a, scene, uploaded); !st.ok()) return conn->fail("bake", st);
  if (json) {
    print_json_line({{"type", "scene"}, {"uploaded", uploaded}, {"scene", to_json(scene)}});
  } else {
    // With --detach stdout carries only the bake id (for `id=$(luxel bake ...)`).
    std::fprintf(a.detach ? stderr : stdout, "scene      %s (%s, %s)\n", scene.scene_id().c_str(),
                 scene.name().c_str(), uploaded ? "uploaded" : "already on the daemon");
    for (const auto& w : scene.warnings())
      std::fprintf(a.detach ? stderr : stdout, "warning    %s\n", w.c_str());
  }

  luxel::v1::BakeInfo bake;
  {
    grpc::ClientContext ctx;
    conn->prepare_unary(ctx);
    luxel::v1::SubmitBakeRequest req;
    req.set_scene_id(scene.scene_id());
    *req.mutable_settings() = to_proto(a);
    req.set_idempotency_key(a.idempotency_key);
    if (auto st = conn->stub().SubmitBake(&ctx, req, &bake); !st.ok()) return conn->fail("bake", st);
  }
  if (json) print_json_line({{"type", "bake"}, {"bake", to_json(bake)}});
  else if (a.detach) std::printf("%s\n", bake.bake_id().c_str());
  else std::printf("bake       %s (%s)\n", bake.bake_id().c_str(), state_name(bake.state()).c_str());
  if (a.detach) return kExitOk;

  WatchOptions wopt;
  wopt.snapshots_dir = a.snapshots_dir;
  wopt.json = json;
  wopt.quiet = a.quiet;
  luxel::v1::BakeInfo done;
  if (auto st = watch_bake(*conn, bake.bake_id(), wopt, done); !st.ok()) {
    std::fprintf(stderr, "luxel bake: bake %s continues on the daemon (luxel watch %s)\n",
                 bake.bake_id().c_str(), bake.bake_id().c_str());
    return conn->fail("bake", st);
  }
  if (int rc = bake_outcome("bake", done); rc != kExitOk) {
    if (json) print_json_line({{"type", "result"}, {"bake", to_json(done)}});
    return rc;
  }
  if (!json) {
    const auto& p = done.progress();
    std::printf("baked      %.2f s, %llu paths, spp mean %.1f min %u, error %.4f, stopped by %s\n",
                p.elapsed_s(), static_cast<unsigned long long>(p.paths()), p.mean_spp(), p.min_spp(),
                p.error(), done.termination().empty() ? "-" : done.termination().c_str());
    if (!done.features().empty()) std::printf("features   %s\n", done.features().c_str());
  }
  if (auto st = download_artifacts(*conn, done, {}, a.out, json); !st.ok())
    return conn->fail("bake", st);
  if (json) print_json_line({{"type", "result"}, {"bake", to_json(done)}});
  return kExitOk;
}

}  // namespace luxel::cli
