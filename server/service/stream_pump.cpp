#include "service/stream_pump.h"

namespace luxel::service {

StreamPump::StreamPump(std::chrono::milliseconds period)
    : period_(period), thread_([this] { loop(); }) {}

StreamPump::~StreamPump() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    stop_ = true;
  }
  stop_cv_.notify_all();
  thread_.join();
  for (PumpedStream* s : streams_) delete s;
}

void StreamPump::add(PumpedStream* stream) {
  std::lock_guard<std::mutex> lock(mu_);
  streams_.push_back(stream);
}

size_t StreamPump::size() const {
  std::lock_guard<std::mutex> lock(mu_);
  return streams_.size();
}

void StreamPump::loop() {
  std::unique_lock<std::mutex> lock(mu_);
  while (!stop_) {
    stop_cv_.wait_for(lock, period_);
    if (stop_) break;
    // Ticks run without the lock so that handlers can add streams meanwhile;
    // only this thread removes entries, so the copy stays valid.
    std::vector<PumpedStream*> now_open;
    std::vector<PumpedStream*> finished;
    for (PumpedStream* s : streams_) (s->done ? finished : now_open).push_back(s);
    streams_ = now_open;
    lock.unlock();
    for (PumpedStream* s : finished) delete s;
    const auto now = std::chrono::steady_clock::now();
    for (PumpedStream* s : now_open) s->tick(now);
    lock.lock();
  }
}

}  // namespace luxel::service
