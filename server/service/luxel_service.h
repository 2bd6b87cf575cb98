// The luxel.v1.Luxel gRPC service: translates requests to the stores, the
// queue and the runner, and engine statuses to gRPC status codes. Every
// handler returns a status (a bad request never ends the daemon); with a
// token configured every call must carry "authorization: Bearer <token>".
// Unary calls and DownloadResult use the synchronous API; UploadScene and
// WatchBake are callback reactors driven by one StreamPump thread (idle
// deadlines for uploads, no thread per watcher). Uploads, watchers and
// downloads are capped in total and per client (stream_limits.h).
#pragma once

#include <atomic>
#include <memory>
#include <mutex>
#include <string>

#include "api/settings_translate.h"
#include "bake/resource_estimate.h"
#include "luxel/v1/luxel.grpc.pb.h"
#include "service/bake_runner.h"
#include "service/bake_store.h"
#include "service/job_queue.h"
#include "service/log.h"
#include "service/scene_store.h"
#include "service/scene_upload.h"
#include "service/stream_limits.h"
#include "service/stream_pump.h"
#include "service/upload_reactor.h"

namespace luxel::service {

namespace coordinator {
class WorkerPool;
}

class Metrics;

struct ServiceOptions {
  UploadLimits upload;
  SettingsLimits settings;
  std::string token;               // empty: no authentication
  std::string device_description;  // reported by GetServerStatus
  // The bake device's memory limits, for the estimate at SubmitBake
  // (bake/resource_estimate.h); zeros when there is no device.
  pipeline::DeviceLimits device;
  uint32_t max_concurrent_bakes = 1;
  // Host bytes one bake may be estimated to need (bake/host_memory.h); 0:
  // not checked. On a CPU device its device memory counts here too.
  size_t host_memory_budget = 0;
  bool checkpoints = true;  // bakes write checkpoints (--checkpoint-interval > 0)
  StreamCaps streams;
  UploadDeadlines upload_deadlines;
  // How often watchers look for a new bake state and uploads for deadlines.
  std::chrono::milliseconds pump_period{50};
  Metrics* metrics = nullptr;  // download bytes (metrics.h); may be null
  // Coordinator mode (--workers / --workers-dns): the workers sharded bakes
  // go to; null on a plain daemon, which refuses sharded bakes.
  coordinator::WorkerPool* workers = nullptr;
};

grpc::Status to_grpc(const Status& status);

using LuxelServiceBase = v1::Luxel::WithCallbackMethod_UploadScene<
    v1::Luxel::WithCallbackMethod_WatchBake<v1::Luxel::Service>>;

class LuxelService final : public LuxelServiceBase {
 public:
  LuxelService(SceneStore& scenes, BakeStore& bakes, JobQueue& queue, BakeRunner& runner,
               ServiceOptions options);

  // Refuse new uploads and bakes; end open WatchBake streams.
  void begin_shutdown() { shutting_down_ = true; }
  // Scene bytes received by UploadScene since the start (metrics).
  uint64_t upload_bytes() const { return upload_bytes_.load(); }

  grpc::ServerReadReactor<v1::UploadSceneRequest>* UploadScene(grpc::CallbackServerContext* ctx,
                                                               v1::SceneInfo* response) override;
  grpc::Status GetScene(grpc::ServerContext* ctx, const v1::GetSceneRequest* req,
                        v1::SceneInfo* response) override;
  grpc::Status ListScenes(grpc::ServerContext* ctx, const v1::ListScenesRequest* req,
                          v1::ListScenesResponse* response) override;
  grpc::Status DeleteScene(grpc::ServerContext* ctx, const v1::DeleteSceneRequest* req,
                           v1::DeleteSceneResponse* response) override;
  grpc::Status SubmitBake(grpc::ServerContext* ctx, const v1::SubmitBakeRequest* req,
                          v1::BakeInfo* response) override;
  grpc::Status GetBake(grpc::ServerContext* ctx, const v1::GetBakeRequest* req,
                       v1::BakeInfo* response) override;
  grpc::Status ListBakes(grpc::ServerContext* ctx, const v1::ListBakesRequest* req,
                         v1::ListBakesResponse* response) override;
  grpc::Status CancelBake(grpc::ServerContext* ctx, const v1::CancelBakeRequest* req,
                          v1::BakeInfo* response) override;
  grpc::ServerWriteReactor<v1::BakeEvent>* WatchBake(grpc::CallbackServerContext* ctx,
                                                     const v1::WatchBakeRequest* req) override;
  grpc::Status DownloadResult(grpc::ServerContext* ctx, const v1::DownloadResultRequest* req,
                              grpc::ServerWriter<v1::DownloadResultResponse>* writer) override;
  grpc::Status GetServerStatus(grpc::ServerContext* ctx, const v1::GetServerStatusRequest* req,
                               v1::ServerStatus* response) override;

 private:
  // The job's check before queueing (job::check_bake_job: the resource
  // estimate, a small layout, the probe placement) as a gRPC status:
  // RESOURCE_EXHAUSTED or INVALID_ARGUMENT naming the setting.
  grpc::Status estimate_at_submit(const std::string& scene_id,
                                  const pipeline::BakeSettings& settings);
  // INVALID_ARGUMENT when the reference bake's lightmap has another size
  // than the one a fixed resolution gives this bake.
  grpc::Status check_reference_size(const std::string& ref, const pipeline::BakeSettings& settings);
  // UNAUTHENTICATED unless the call carries the configured bearer token.
  grpc::Status authenticate(grpc::ServerContextBase* ctx, const char* rpc) const;

  SceneStore& scenes_;
  BakeStore& bakes_;
  JobQueue& queue_;
  BakeRunner& runner_;
  const ServiceOptions options_;
  const double started_at_;
  std::atomic<bool> shutting_down_{false};
  std::atomic<uint64_t> upload_bytes_{0};
  StreamSlots slots_;
  // Declared after everything its reactors use: destroyed first.
  std::unique_ptr<StreamPump> pump_;
  // Serialises SubmitBake against DeleteScene (a bake never lands on a
  // scene being deleted) and the queue-limit check against the push.
  std::mutex submit_mu_;
  // One "unauthenticated" line per second, with the count held back.
  mutable LogThrottle unauthenticated_log_{std::chrono::seconds(1)};
};

}  // namespace luxel::service
