#include "service/watch_reactor.h"

#include <optional>

#include "service/log.h"
#include "service/luxel_service.h"

namespace luxel::service {

WatchReactor::WatchReactor(BakeStore& bakes, std::string bake_id, StreamSlot slot,
                           const std::atomic<bool>& shutting_down, std::string request_id,
                           grpc::Status refused)
    : bakes_(bakes),
      bake_id_(std::move(bake_id)),
      slot_(std::move(slot)),
      shutting_down_(shutting_down),
      request_id_(std::move(request_id)) {
  RequestIdScope id(request_id_);
  if (!refused.ok()) {
    finished_ = true;
    Finish(refused);
    return;
  }
  log_event("watch_started", {{"bake", bake_id_}});
  tick(std::chrono::steady_clock::now());  // the first event goes out at once
}

void WatchReactor::end(const char* why) {
  finished_ = true;
  log_event("watch_ended", {{"bake", bake_id_}, {"why", why}});
}

void WatchReactor::tick(std::chrono::steady_clock::time_point) {
  RequestIdScope id(request_id_);
  std::optional<grpc::Status> finish;
  bool start_write = false;
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (finished_ || writing_) return;  // a write in flight: OnWriteDone continues
    if (shutting_down_) {
      end("daemon shutting down");
      finish = grpc::Status(grpc::StatusCode::UNAVAILABLE,
                            "daemon shutting down; the bake resumes after restart, watch again "
                            "then");
    } else {
      auto v = bakes_.view(bake_id_);
      if (!v) {
        end("bake gone");
        finish = to_grpc(v.status());
      } else if (!sent_any_ || v->version != seen_version_) {
        sent_any_ = true;
        seen_version_ = v->version;
        event_.Clear();
        *event_.mutable_info() = v->info;
        if (v->snapshot && v->snapshot_seq != sent_snapshot_) {
          auto encoded = v->snapshot->encoded();
          if (encoded)
            *event_.mutable_snapshot() = std::move(encoded.value());
          else
            log_event("snapshot_encode_failed",
                      {{"bake", bake_id_}, {"error", encoded.status().to_string()}});
          sent_snapshot_ = v->snapshot_seq;
        }
        final_sent_ = is_terminal(v->info.state());
        event_.set_final(final_sent_);
        writing_ = start_write = true;
      }
    }
  }
  // Outside the lock: grpc may run OnWriteDone on another thread at once.
  if (finish)
    Finish(*finish);
  else if (start_write)
    StartWrite(&event_);
}

void WatchReactor::OnWriteDone(bool ok) {
  RequestIdScope id(request_id_);
  std::optional<grpc::Status> finish;
  {
    std::lock_guard<std::mutex> lock(mu_);
    writing_ = false;
    if (finished_) {
      // OnCancel came during the write and left the Finish to us.
      finish = grpc::Status(grpc::StatusCode::CANCELLED, "watcher went away");
    } else if (!ok) {
      end("client went away");
      finish = grpc::Status(grpc::StatusCode::CANCELLED, "watcher went away");
    } else if (final_sent_) {
      end("final");
      finish = grpc::Status::OK;
    }
  }
  if (finish) Finish(*finish);
}

void WatchReactor::OnCancel() {
  RequestIdScope id(request_id_);
  bool finish_now = false;
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (finished_) return;
    end("client went away");
    finish_now = !writing_;  // otherwise OnWriteDone finishes
  }
  if (finish_now) Finish(grpc::Status(grpc::StatusCode::CANCELLED, "watcher went away"));
}

void WatchReactor::OnDone() {
  slot_.release();
  done = true;
}

}  // namespace luxel::service
