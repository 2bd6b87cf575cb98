#include "service/luxel_service.h"

#include <google/protobuf/util/message_differencer.h>
#include <openssl/crypto.h>

#include <algorithm>
#include <fstream>

#include "bake/host_memory.h"
#include "common/sha256.h"
#include "job/bake_job.h"
#include "luxel_version.h"
#include "output/exr.h"
#include "service/coordinator/shard_plan.h"
#include "service/coordinator/worker_pool.h"
#include "service/files.h"
#include "service/log.h"
#include "service/metrics.h"
#include "service/rpc_interceptor.h"
#include "service/watch_reactor.h"

namespace luxel::service {

namespace {

constexpr size_t kDownloadChunkBytes = 64 * 1024;

grpc::Status invalid(const std::string& message) {
  return {grpc::StatusCode::INVALID_ARGUMENT, message};
}

// Ids are validated before they reach a path or a log line.
grpc::Status check_id(const std::string& id, const char* field, size_t length) {
  bool ok = id.size() == length;
  for (char c : id)
    if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) ok = false;
  if (id.empty()) return invalid(strprintf("%s: required", field));
  if (!ok)
    return {grpc::StatusCode::NOT_FOUND,
            strprintf("%s: no such id '%s' (ids are %zu lowercase hex digits)", field,
                      id.substr(0, 80).c_str(), length)};
  return grpc::Status::OK;
}

}  // namespace

grpc::Status to_grpc(const Status& status) {
  switch (status.code()) {
    case StatusCode::kOk:
      return grpc::Status::OK;
    case StatusCode::kInvalidArgument:
      return {grpc::StatusCode::INVALID_ARGUMENT, status.message()};
    case StatusCode::kNotFound:
      return {grpc::StatusCode::NOT_FOUND, status.message()};
    case StatusCode::kDataLoss:
      return {grpc::StatusCode::DATA_LOSS, status.message()};
    case StatusCode::kResourceExhausted:
      return {grpc::StatusCode::RESOURCE_EXHAUSTED, status.message()};
    case StatusCode::kUnavailable:
      return {grpc::StatusCode::UNAVAILABLE, status.message()};
    case StatusCode::kDeadlineExceeded:
      return {grpc::StatusCode::DEADLINE_EXCEEDED, status.message()};
    case StatusCode::kInternal:
      return {grpc::StatusCode::INTERNAL, status.message()};
    case StatusCode::kUnauthenticated:
      return {grpc::StatusCode::UNAUTHENTICATED, status.message()};
  }
  return {grpc::StatusCode::UNKNOWN, status.message()};
}

LuxelService::LuxelService(SceneStore& scenes, BakeStore& bakes, JobQueue& queue,
                           BakeRunner& runner, ServiceOptions options)
    : scenes_(scenes),
      bakes_(bakes),
      queue_(queue),
      runner_(runner),
      options_(std::move(options)),
      started_at_(unix_now()),
      slots_(options_.streams),
      pump_(std::make_unique<StreamPump>(options_.pump_period)) {}

grpc::Status LuxelService::authenticate(grpc::ServerContextBase* ctx, const char* rpc) const {
  // Every handler starts here: its log lines carry the call's request id.
  set_thread_request_id(request_id_of(ctx));
  if (options_.token.empty()) return grpc::Status::OK;
  const std::string expected = "Bearer " + options_.token;
  const auto& md = ctx->client_metadata();
  auto it = md.find("authorization");
  if (it != md.end() && it->second.size() == expected.size() &&
      CRYPTO_memcmp(it->second.data(), expected.data(), expected.size()) == 0)
    return grpc::Status::OK;
  uint64_t suppressed = 0;
  if (unauthenticated_log_.admit(LogThrottle::Clock::now(), &suppressed)) {
    if (suppressed == 0)
      log_event("unauthenticated", {{"rpc", rpc}, {"peer", ctx->peer()}});
    else
      log_event("unauthenticated", {{"rpc", rpc},
                                    {"peer", ctx->peer()},
                                    {"suppressed_since_last", std::to_string(suppressed)}});
  }
  return {
      grpc::StatusCode::UNAUTHENTICATED,
      it == md.end() ? "missing \"authorization: Bearer <token>\" metadata" : "wrong bearer token"};
}

grpc::ServerReadReactor<v1::UploadSceneRequest>* LuxelService::UploadScene(
    grpc::CallbackServerContext* ctx, v1::SceneInfo* response) {
  StreamSlot slot;
  grpc::Status refused = authenticate(ctx, "UploadScene");
  if (refused.ok() && shutting_down_)
    refused = {grpc::StatusCode::UNAVAILABLE, "daemon shutting down"};
  if (refused.ok()) refused = slots_.acquire(StreamKind::kUpload, peer_host(ctx->peer()), &slot);
  auto* reactor =
      new UploadReactor(ctx, scenes_, options_.upload, options_.upload_deadlines, upload_bytes_,
                        response, std::move(slot), request_id_of(ctx), refused);
  pump_->add(reactor);
  return reactor;
}

grpc::Status LuxelService::GetScene(grpc::ServerContext* ctx, const v1::GetSceneRequest* req,
                                    v1::SceneInfo* response) {
  if (auto st = authenticate(ctx, "GetScene"); !st.ok()) return st;
  if (auto st = check_id(req->scene_id(), "scene_id", 64); !st.ok()) return st;
  auto info = scenes_.get(req->scene_id());
  if (!info) return to_grpc(info.status());
  *response = info.value();
  return grpc::Status::OK;
}

grpc::Status LuxelService::ListScenes(grpc::ServerContext* ctx, const v1::ListScenesRequest*,
                                      v1::ListScenesResponse* response) {
  if (auto st = authenticate(ctx, "ListScenes"); !st.ok()) return st;
  for (auto& s : scenes_.list()) *response->add_scenes() = std::move(s);
  return grpc::Status::OK;
}

grpc::Status LuxelService::DeleteScene(grpc::ServerContext* ctx, const v1::DeleteSceneRequest* req,
                                       v1::DeleteSceneResponse*) {
  if (auto st = authenticate(ctx, "DeleteScene"); !st.ok()) return st;
  if (auto st = check_id(req->scene_id(), "scene_id", 64); !st.ok()) return st;
  std::lock_guard<std::mutex> lock(submit_mu_);
  std::string user;
  if (bakes_.scene_in_use(req->scene_id(), &user)) {
    auto b = bakes_.get(user);
    return {grpc::StatusCode::FAILED_PRECONDITION,
            strprintf("scene_id: scene %s is used by bake %s (%s); cancel it or wait",
                      req->scene_id().c_str(), user.c_str(),
                      b ? v1::BakeState_Name(b->state()).c_str() : "?")};
  }
  if (Status st = scenes_.remove(req->scene_id()); !st.is_ok()) return to_grpc(st);
  log_event("scene_deleted", {{"scene", req->scene_id()}});
  return grpc::Status::OK;
}

grpc::Status LuxelService::estimate_at_submit(const std::string& scene_id,
                                              const pipeline::BakeSettings& settings) {
  auto info = scenes_.get(scene_id);
  if (!info)
    return {grpc::StatusCode::NOT_FOUND, strprintf("scene_id: no scene '%s'", scene_id.c_str())};
  auto scene = scenes_.load_scene(info.value());  // cached; the bake reuses it
  if (!scene) return to_grpc(scene.status());
  // What the job will need and what it will place, checked by the functions
  // the bake runs (job/bake_job.h), against the scene as the runner reads it.
  const job::JobInput input{.scene = scene.value().get(),
                            .settings = settings,
                            .scene_file = scenes_.main_file_path(info.value()),
                            .scene_name = info->name()};
  // The host side too: result images, kept state, denoiser, output
  // assembly and, on a CPU device, the device buffers (bake/host_memory.h).
  const job::HostMemoryCheck host{
      .budget = options_.host_memory_budget,
      .device_is_host = !options_.device.is_gpu && options_.device.global_mem_bytes > 0,
      .checkpoints = options_.checkpoints,
      .budget_name = "luxeld --host-memory-budget"};
  return to_grpc(job::check_bake_job(input, options_.device, host));
}

// A reference lightmap of another size fails the bake when it starts
// (bake_buffers.cpp); with a fixed resolution the size is known now: R
// wide, and R tall per page. Its stored EXR header says the reference's.
grpc::Status LuxelService::check_reference_size(const std::string& ref,
                                                const pipeline::BakeSettings& settings) {
  const int r = settings.atlas.resolution;
  if (r <= 0 || !settings.lightmap) return grpc::Status::OK;
  auto size = output::read_exr_size(bakes_.results_dir(ref) + "/irradiance.exr");
  if (!size)
    return invalid(strprintf("settings.reference_bake_id: bake %s has no readable irradiance.exr",
                             ref.c_str()));
  const auto [w, h] = size.value();
  if (w != r || h % r != 0)
    return invalid(
        strprintf("settings.reference_bake_id: bake %s is a %dx%d lightmap; this bake's is %dx%d "
                  "(settings.resolution): a reference must have the bake's size",
                  ref.c_str(), w, h, r, r));
  return grpc::Status::OK;
}

grpc::Status LuxelService::SubmitBake(grpc::ServerContext* ctx, const v1::SubmitBakeRequest* req,
                                      v1::BakeInfo* response) {
  if (auto st = authenticate(ctx, "SubmitBake"); !st.ok()) return st;
  if (auto st = check_id(req->scene_id(), "scene_id", 64); !st.ok()) return st;
  if (req->idempotency_key().size() > 256) return invalid("idempotency_key: longer than 256 bytes");
  // The one validation of the settings (the runner only translates them).
  auto settings = to_engine_settings(req->settings(), options_.settings);
  if (!settings) return to_grpc(settings.status());
  if (Status st = coordinator::check_shard_settings(
          req->settings(), options_.workers != nullptr, options_.settings,
          options_.workers ? uint32_t(options_.workers->last_resolved().size()) : 0);
      !st.is_ok())
    return to_grpc(st);

  std::lock_guard<std::mutex> lock(submit_mu_);
  if (auto existing = bakes_.find_by_key(req->idempotency_key())) {
    // A retry is the same request; the same key with another scene or other
    // settings is a client bug, and returning the first job would hide it.
    if (existing->scene_id() != req->scene_id())
      return {grpc::StatusCode::FAILED_PRECONDITION,
              strprintf("idempotency_key '%s' was used for bake %s of another scene",
                        req->idempotency_key().c_str(), existing->bake_id().c_str())};
    if (!google::protobuf::util::MessageDifferencer::Equals(existing->settings(), req->settings()))
      return {grpc::StatusCode::FAILED_PRECONDITION,
              strprintf("idempotency_key '%s' was used for bake %s with other settings",
                        req->idempotency_key().c_str(), existing->bake_id().c_str())};
    *response = *existing;
    log_event("bake_submit_retried",
              {{"bake", existing->bake_id()}, {"key", req->idempotency_key()}});
    return grpc::Status::OK;
  }
  if (shutting_down_) return {grpc::StatusCode::UNAVAILABLE, "daemon shutting down"};
  if (!scenes_.contains(req->scene_id()))
    return {grpc::StatusCode::NOT_FOUND,
            strprintf("scene_id: no scene '%s'", req->scene_id().c_str())};
  // What the bake will need, against the daemon's device: a bake that cannot
  // fit is refused now rather than FAILED once queued (after the retry
  // check: an accepted request is never refused on a retry).
  if (auto st = estimate_at_submit(req->scene_id(), settings.value()); !st.ok()) {
    log_event("bake_refused", {{"scene", req->scene_id()}, {"error", st.error_message()}});
    return st;
  }
  if (const std::string& ref = req->settings().reference_bake_id(); !ref.empty()) {
    // One rule for ids inside the settings: malformed or unknown, the
    // settings are invalid (INVALID_ARGUMENT naming the field); NOT_FOUND is
    // for the request's own ids (scene_id, bake_id).
    if (auto st = check_id(ref, "settings.reference_bake_id", 32); !st.ok())
      return invalid(st.error_message());
    auto ref_info = bakes_.get(ref);
    if (!ref_info)
      return invalid(strprintf("settings.reference_bake_id: no bake '%s'", ref.c_str()));
    if (ref_info->state() != v1::BAKE_STATE_SUCCEEDED)
      return invalid(
          strprintf("settings.reference_bake_id: bake %s is %s; a reference must have SUCCEEDED",
                    ref.c_str(), v1::BakeState_Name(ref_info->state()).c_str()));
    if (auto st = check_reference_size(ref, settings.value()); !st.ok()) return st;
  }
  if (Status st = queue_.check_room(); !st.is_ok()) return to_grpc(st);
  auto created = bakes_.create(req->scene_id(), req->settings(), req->idempotency_key());
  if (!created) return to_grpc(created.status());
  const v1::BakeInfo& info = created->info;
  if (Status st = queue_.push(info.bake_id(), info.settings().priority(),
                              bakes_.sequence(info.bake_id()), /*force=*/true);
      !st.is_ok())
    return to_grpc(st);
  log_event("bake_submitted", {{"bake", info.bake_id()},
                               {"scene", info.scene_id()},
                               {"priority", std::to_string(info.settings().priority())}});
  *response = info;
  return grpc::Status::OK;
}

grpc::Status LuxelService::GetBake(grpc::ServerContext* ctx, const v1::GetBakeRequest* req,
                                   v1::BakeInfo* response) {
  if (auto st = authenticate(ctx, "GetBake"); !st.ok()) return st;
  if (auto st = check_id(req->bake_id(), "bake_id", 32); !st.ok()) return st;
  auto info = bakes_.get(req->bake_id());
  if (!info) return to_grpc(info.status());
  *response = info.value();
  return grpc::Status::OK;
}

grpc::Status LuxelService::ListBakes(grpc::ServerContext* ctx, const v1::ListBakesRequest* req,
                                     v1::ListBakesResponse* response) {
  if (auto st = authenticate(ctx, "ListBakes"); !st.ok()) return st;
  std::vector<v1::BakeState> states;
  for (int s : req->states()) {
    if (!v1::BakeState_IsValid(s) || s == v1::BAKE_STATE_UNSPECIFIED)
      return invalid(strprintf("states: unknown bake state %d", s));
    states.push_back(static_cast<v1::BakeState>(s));
  }
  for (auto& b : bakes_.list(states)) *response->add_bakes() = std::move(b);
  return grpc::Status::OK;
}

grpc::Status LuxelService::CancelBake(grpc::ServerContext* ctx, const v1::CancelBakeRequest* req,
                                      v1::BakeInfo* response) {
  if (auto st = authenticate(ctx, "CancelBake"); !st.ok()) return st;
  if (auto st = check_id(req->bake_id(), "bake_id", 32); !st.ok()) return st;
  auto info = runner_.cancel(req->bake_id(), req->finish());
  if (!info) return to_grpc(info.status());
  *response = info.value();
  return grpc::Status::OK;
}

grpc::ServerWriteReactor<v1::BakeEvent>* LuxelService::WatchBake(grpc::CallbackServerContext* ctx,
                                                                 const v1::WatchBakeRequest* req) {
  StreamSlot slot;
  grpc::Status refused = authenticate(ctx, "WatchBake");
  if (refused.ok()) refused = check_id(req->bake_id(), "bake_id", 32);
  if (refused.ok()) {
    // NOT_FOUND before a slot is taken.
    if (auto first = bakes_.view(req->bake_id()); !first) refused = to_grpc(first.status());
  }
  if (refused.ok()) refused = slots_.acquire(StreamKind::kWatch, peer_host(ctx->peer()), &slot);
  auto* reactor = new WatchReactor(bakes_, req->bake_id(), std::move(slot), shutting_down_,
                                   request_id_of(ctx), refused);
  pump_->add(reactor);
  return reactor;
}

grpc::Status LuxelService::DownloadResult(grpc::ServerContext* ctx,
                                          const v1::DownloadResultRequest* req,
                                          grpc::ServerWriter<v1::DownloadResultResponse>* writer) {
  if (auto st = authenticate(ctx, "DownloadResult"); !st.ok()) return st;
  if (auto st = check_id(req->bake_id(), "bake_id", 32); !st.ok()) return st;
  StreamSlot slot;
  if (auto st = slots_.acquire(StreamKind::kDownload, peer_host(ctx->peer()), &slot); !st.ok())
    return st;
  auto info = bakes_.get(req->bake_id());
  if (!info) return to_grpc(info.status());
  if (info->state() != v1::BAKE_STATE_SUCCEEDED)
    return {grpc::StatusCode::FAILED_PRECONDITION,
            strprintf("bake_id: bake %s is %s; artifacts exist once it has SUCCEEDED",
                      req->bake_id().c_str(), v1::BakeState_Name(info->state()).c_str())};
  const auto& names = info->artifacts();
  if (std::find(names.begin(), names.end(), req->artifact()) == names.end()) {
    std::string list;
    for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
    return {grpc::StatusCode::NOT_FOUND,
            strprintf("artifact: no artifact '%s' (have: %s)",
                      req->artifact().substr(0, 80).c_str(), list.c_str())};
  }
  const std::string path = bakes_.results_dir(req->bake_id()) + "/" + req->artifact();
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in)
    return {grpc::StatusCode::DATA_LOSS,
            strprintf("artifact %s is missing on disk", req->artifact().c_str())};
  const uint64_t total = static_cast<uint64_t>(in.tellg());
  in.seekg(0);
  Sha256 hash;
  auto read_chunk = [&] {
    std::string chunk(kDownloadChunkBytes, '\0');
    in.read(chunk.data(), static_cast<std::streamsize>(chunk.size()));
    chunk.resize(static_cast<size_t>(in.gcount()));
    hash.update(chunk);
    return chunk;
  };
  // One chunk of look-ahead, so the checksum rides on the last data message.
  std::string current = read_chunk();
  bool first = true;
  for (;;) {
    std::string next = in ? read_chunk() : std::string();
    v1::DownloadResultResponse msg;
    if (first) msg.set_total_size(total);
    first = false;
    msg.set_chunk(std::move(current));
    const bool last = next.empty();
    if (last) msg.set_sha256(hash.hex_digest());
    const uint64_t chunk_bytes = msg.chunk().size();
    if (!writer->Write(msg)) return {grpc::StatusCode::CANCELLED, "client went away"};
    if (options_.metrics) options_.metrics->download_bytes(chunk_bytes);
    if (last) break;
    current = std::move(next);
  }
  log_event(
      "artifact_downloaded",
      {{"bake", req->bake_id()}, {"artifact", req->artifact()}, {"bytes", std::to_string(total)}});
  return grpc::Status::OK;
}

grpc::Status LuxelService::GetServerStatus(grpc::ServerContext* ctx,
                                           const v1::GetServerStatusRequest*,
                                           v1::ServerStatus* response) {
  if (auto st = authenticate(ctx, "GetServerStatus"); !st.ok()) return st;
  response->set_version(std::string(LUXEL_VERSION) + " (" + LUXEL_GIT_REVISION + ")");
  response->set_device(options_.device_description);
  response->set_started_at(started_at_);
  for (const auto& [state, n] : bakes_.count_by_state())
    (*response->mutable_bakes_by_state())[state] = n;
  response->set_paths_traced(runner_.paths_traced());
  response->set_upload_bytes(upload_bytes_.load());
  response->set_scenes(static_cast<uint32_t>(scenes_.size()));
  response->set_max_concurrent_bakes(options_.max_concurrent_bakes);
  response->set_watchers(slots_.open(StreamKind::kWatch));
  response->set_uploads(slots_.open(StreamKind::kUpload));
  response->set_downloads(slots_.open(StreamKind::kDownload));
  if (options_.workers)
    for (const std::string& w : options_.workers->last_resolved()) response->add_workers(w);
  return grpc::Status::OK;
}

}  // namespace luxel::service
