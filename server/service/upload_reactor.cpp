#include "service/upload_reactor.h"

#include <optional>

#include "service/log.h"
#include "service/luxel_service.h"

namespace luxel::service {

UploadReactor::UploadReactor(grpc::CallbackServerContext* ctx, SceneStore& scenes,
                             const UploadLimits& limits, UploadDeadlines deadlines,
                             std::atomic<uint64_t>& upload_bytes, v1::SceneInfo* response,
                             StreamSlot slot, std::string request_id, grpc::Status refused)
    : ctx_(ctx),
      scenes_(scenes),
      limits_(limits),
      deadlines_(deadlines),
      upload_bytes_(upload_bytes),
      response_(response),
      slot_(std::move(slot)),
      request_id_(std::move(request_id)),
      started_(std::chrono::steady_clock::now()),
      last_activity_(started_) {
  RequestIdScope id(request_id_);
  if (!refused.ok()) {
    finished_ = true;
    Finish(refused);
    return;
  }
  StartRead(&msg_);
}

grpc::Status UploadReactor::end_locked(const grpc::Status& status, const char* event) {
  finished_ = true;
  if (event != nullptr && upload_)
    log_event(event,
              {{"scene", scene_id_of(upload_->header())}, {"error", status.error_message()}});
  upload_.reset();  // removes the staging folder unless committed
  return status;
}

grpc::Status UploadReactor::take(const v1::UploadSceneRequest& msg) {
  if (!upload_) {
    if (!msg.has_header())
      return {grpc::StatusCode::INVALID_ARGUMENT, "upload: the first message must carry a header"};
    auto upload = SceneUpload::begin(scenes_, msg.header(), limits_);
    if (!upload) {
      log_event("upload_refused",
                {{"name", msg.header().name()}, {"error", upload.status().to_string()}});
      return to_grpc(upload.status());
    }
    upload_ = std::move(upload.value());
    log_event("upload_started",
              {{"scene", scene_id_of(msg.header())}, {"name", msg.header().name()}});
    return grpc::Status::OK;
  }
  if (msg.has_header())
    return {grpc::StatusCode::INVALID_ARGUMENT, "upload: a header may only be the first message"};
  const uint64_t before = upload_->received();
  Status st = upload_->write(msg.chunk());
  upload_bytes_ += upload_->received() - before;
  return to_grpc(st);
}

grpc::Status UploadReactor::end_of_stream() {
  if (!upload_) return {grpc::StatusCode::DATA_LOSS, "upload: stream ended before the header"};
  if (ctx_->IsCancelled()) {
    log_event("upload_cancelled", {{"scene", scene_id_of(upload_->header())}});
    return {grpc::StatusCode::CANCELLED, "upload cancelled by the client"};
  }
  auto info = upload_->finish();
  if (!info) return to_grpc(info.status());
  *response_ = info.value();
  log_event("scene_stored", {{"scene", info->scene_id()},
                             {"name", info->name()},
                             {"bytes", std::to_string(info->size())},
                             {"already_stored", info->already_stored() ? "true" : "false"}});
  return grpc::Status::OK;
}

void UploadReactor::OnReadDone(bool ok) {
  RequestIdScope id(request_id_);
  std::optional<grpc::Status> finish;
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (finished_) return;  // ended by a deadline while this read was pending
    last_activity_ = std::chrono::steady_clock::now();
    // ok == false: the client half-closed, cancelled, or sent bytes that do
    // not parse as an UploadSceneRequest (the callback API does not tell which).
    grpc::Status st = ok ? take(msg_) : end_of_stream();
    if (!st.ok())
      finish = end_locked(st, "upload_failed");
    else if (!ok)
      finish = end_locked(st, nullptr);
    else
      StartRead(&msg_);  // under the lock, so a deadline's Finish never precedes it
  }
  if (finish) Finish(*finish);
}

void UploadReactor::tick(std::chrono::steady_clock::time_point now) {
  RequestIdScope id(request_id_);
  std::optional<grpc::Status> finish;
  {
    std::unique_lock<std::mutex> lock(mu_, std::try_to_lock);
    if (!lock.owns_lock() || finished_) return;  // busy writing a chunk: not idle
    const double idle = std::chrono::duration<double>(now - last_activity_).count();
    const double total = std::chrono::duration<double>(now - started_).count();
    if (idle > deadlines_.idle_s)
      finish = end_locked({grpc::StatusCode::DEADLINE_EXCEEDED,
                           strprintf("upload: nothing received for %g s (--upload-idle-timeout); "
                                     "the partial upload was discarded",
                                     deadlines_.idle_s)},
                          "upload_timed_out");
    else if (deadlines_.total_s > 0 && total > deadlines_.total_s)
      finish = end_locked({grpc::StatusCode::DEADLINE_EXCEEDED,
                           strprintf("upload: not complete after %g s (--upload-timeout); the "
                                     "partial upload was discarded",
                                     deadlines_.total_s)},
                          "upload_timed_out");
  }
  // A read is pending: Finish ends the call and that read completes with
  // ok == false, which OnReadDone ignores (finished_).
  if (finish) Finish(*finish);
}

void UploadReactor::OnDone() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    upload_.reset();
  }
  slot_.release();
  done = true;
}

}  // namespace luxel::service
