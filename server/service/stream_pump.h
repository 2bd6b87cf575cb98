// One thread that drives every callback-API stream of the daemon: each tick
// it lets every WatchBake reactor send the bake's newest state and every
// UploadScene reactor check its idle and total deadlines. This replaces one
// blocked server thread per stream (the sync API) with one thread in all, so
// 150 watchers cost 150 small objects, not 150 threads.
//
// Ownership: grpc calls a reactor's OnDone once it is finished with it; the
// reactor then only sets `done`, and the pump deletes it on its next tick, so
// the pump never calls into a deleted reactor and OnDone never waits for the
// pump's lock.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "service/log.h"

namespace luxel::service {

class PumpedStream {
 public:
  virtual ~PumpedStream() = default;
  // Called from the pump thread only; must not block on I/O for long.
  virtual void tick(std::chrono::steady_clock::time_point now) = 0;
  // Set by the reactor's OnDone; the pump then deletes it.
  std::atomic<bool> done{false};
};

// Reactions run on threads shared by every call (gRPC's callback threads,
// the pump): each sets its call's request id for its log lines and clears it
// when it returns, so no id leaks into another call's lines.
class RequestIdScope {
 public:
  explicit RequestIdScope(const std::string& id) { set_thread_request_id(id); }
  ~RequestIdScope() { set_thread_request_id(""); }
  RequestIdScope(const RequestIdScope&) = delete;
  RequestIdScope& operator=(const RequestIdScope&) = delete;
};

class StreamPump {
 public:
  explicit StreamPump(std::chrono::milliseconds period);
  // Stops the thread and deletes every stream left (call after the gRPC
  // server has shut down, when every reactor is done).
  ~StreamPump();
  // Takes ownership.
  void add(PumpedStream* stream);
  size_t size() const;

 private:
  void loop();

  const std::chrono::milliseconds period_;
  mutable std::mutex mu_;
  std::condition_variable stop_cv_;
  bool stop_ = false;
  std::vector<PumpedStream*> streams_;
  std::thread thread_;
};

}  // namespace luxel::service
