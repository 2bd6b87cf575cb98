// WatchBake on the callback API: a ServerWriteReactor that the StreamPump
// ticks. Each tick, if no write is in flight, it reads the bake's newest view
// and, when the version changed, writes one event from it (a watcher that
// fell behind skips intermediate snapshots and progress values: coalescing).
// The bake thread never waits for a watcher; a slow watcher delays only its
// own next event. OnWriteDone(false) or OnCancel: the client went away.
#pragma once

#include <grpcpp/grpcpp.h>

#include <atomic>
#include <mutex>
#include <string>

#include "luxel/v1/luxel.grpc.pb.h"
#include "service/bake_store.h"
#include "service/stream_limits.h"
#include "service/stream_pump.h"

namespace luxel::service {

class WatchReactor final : public grpc::ServerWriteReactor<v1::BakeEvent>, public PumpedStream {
 public:
  // With `refused` not OK the call finishes at once with that status.
  WatchReactor(BakeStore& bakes, std::string bake_id, StreamSlot slot,
               const std::atomic<bool>& shutting_down, std::string request_id,
               grpc::Status refused);

  void tick(std::chrono::steady_clock::time_point now) override;
  void OnWriteDone(bool ok) override;
  void OnCancel() override;
  void OnDone() override;

 private:
  // Under mu_: marks the call finished; the caller calls Finish after unlocking.
  void end(const char* why);

  BakeStore& bakes_;
  const std::string bake_id_;
  StreamSlot slot_;
  const std::atomic<bool>& shutting_down_;
  const std::string request_id_;  // for log lines (rpc_interceptor.h)
  std::mutex mu_;
  bool writing_ = false, finished_ = false, final_sent_ = false, sent_any_ = false;
  uint64_t seen_version_ = 0, sent_snapshot_ = 0;
  v1::BakeEvent event_;  // the write in flight (one at a time)
};

}  // namespace luxel::service
