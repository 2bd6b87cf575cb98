// `luxel bake SCENE --out DIR` on a luxeld daemon: upload the scene unless the
// daemon already stores it, submit the bake, watch it with a progress bar,
// and download every artifact into --out (each verified by sha256).
#include <unistd.h>

#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "api/settings_translate.h"
#include "bake_options.h"
#include "common/status.h"
#include "remote/fetch.h"
#include "remote/output.h"
#include "remote/upload.h"
#include "remote/watch.h"

namespace luxel::cli {
namespace {

using namespace remote;

// Settings the API cannot carry are refused, never silently dropped.
int check_remote_args(const BakeCommand& a) {
  if (!a.local_only.empty()) {
    std::fprintf(stderr,
                 "luxel bake: %s is only available with --local (the luxeld API has no such "
                 "setting)\n",
                 a.local_only.front().c_str());
    return kExitUsage;
  }
  if (auto st = pipeline::validate_settings(a.settings); !st.is_ok()) {
    std::fprintf(stderr, "luxel bake: %s\n", st.message().c_str());
    return kExitUsage;
  }
  if (auto p = service::to_proto_settings(a.settings); !p) {
    std::fprintf(stderr, "luxel bake: %s\n", p.status().message().c_str());
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
grpc::Status resolve_scene(Connection& conn, const BakeCommand& a, luxel::v1::SceneInfo& info,
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

int run_bake_remote(BakeCommand& a) {
  if (int rc = check_remote_args(a); rc != kExitOk) return rc;
  if (!read_probe_positions(a)) return kExitUsage;
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
    *req.mutable_settings() = service::to_proto_settings(a.settings).value();
    req.set_idempotency_key(a.idempotency_key);
    if (auto st = conn->stub().SubmitBake(&ctx, req, &bake); !st.ok())
      return conn->fail("bake", st);
  }
  if (json)
    print_json_line({{"type", "bake"}, {"bake", to_json(bake)}});
  else if (a.detach)
    std::printf("%s\n", bake.bake_id().c_str());
  else
    std::printf("bake       %s (%s)\n", bake.bake_id().c_str(), state_name(bake.state()).c_str());
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
                p.elapsed_s(), static_cast<unsigned long long>(p.paths()), p.mean_spp(),
                p.min_spp(), p.error(),
                done.termination().empty() ? "-" : done.termination().c_str());
    if (!done.features().empty()) std::printf("features   %s\n", done.features().c_str());
  }
  if (auto st = download_artifacts(*conn, done, {}, a.out, json); !st.ok())
    return conn->fail("bake", st);
  if (json) print_json_line({{"type", "result"}, {"bake", to_json(done)}});
  return kExitOk;
}

}  // namespace luxel::cli
