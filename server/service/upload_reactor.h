// UploadScene on the callback API: a ServerReadReactor that writes each chunk
// through SceneUpload as it arrives. The StreamPump ticks it to enforce two
// deadlines that the sync API could not (a thread blocked in Read() wakes only
// through TryCancel, which the client sees as a bare CANCELLED):
//   --upload-idle-timeout  nothing received for that long, and
//   --upload-timeout       the whole upload took longer than that.
// Past either, the call ends with DEADLINE_EXCEEDED naming the flag, and the
// staging folder is removed at once (SceneUpload's destructor).
#pragma once

#include <grpcpp/grpcpp.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <mutex>
#include <string>

#include "luxel/v1/luxel.grpc.pb.h"
#include "service/scene_store.h"
#include "service/scene_upload.h"
#include "service/stream_limits.h"
#include "service/stream_pump.h"

namespace luxel::service {

struct UploadDeadlines {
  double idle_s = 60;     // --upload-idle-timeout
  double total_s = 3600;  // --upload-timeout; 0: none
};

class UploadReactor final : public grpc::ServerReadReactor<v1::UploadSceneRequest>,
                            public PumpedStream {
 public:
  // With `refused` not OK the call finishes at once with that status.
  UploadReactor(grpc::CallbackServerContext* ctx, SceneStore& scenes, const UploadLimits& limits,
                UploadDeadlines deadlines, std::atomic<uint64_t>& upload_bytes,
                v1::SceneInfo* response, StreamSlot slot, std::string request_id,
                grpc::Status refused);

  void tick(std::chrono::steady_clock::time_point now) override;
  void OnReadDone(bool ok) override;
  void OnDone() override;

 private:
  // Under mu_: what to do with one message / with the end of the stream.
  grpc::Status take(const v1::UploadSceneRequest& msg);
  grpc::Status end_of_stream();
  // Under mu_: marks the call finished, removes the staging folder, returns
  // `status` for the caller to Finish with once it has unlocked.
  grpc::Status end_locked(const grpc::Status& status, const char* event);

  grpc::CallbackServerContext* const ctx_;
  SceneStore& scenes_;
  const UploadLimits limits_;
  const UploadDeadlines deadlines_;
  std::atomic<uint64_t>& upload_bytes_;
  v1::SceneInfo* const response_;
  StreamSlot slot_;
  const std::string request_id_;  // for log lines (rpc_interceptor.h)
  const std::chrono::steady_clock::time_point started_;

  std::mutex mu_;  // held while a chunk is written; tick only try_locks it
  bool finished_ = false;
  std::chrono::steady_clock::time_point last_activity_;
  std::unique_ptr<SceneUpload> upload_;
  v1::UploadSceneRequest msg_;  // the read in flight (one at a time)
};

}  // namespace luxel::service
