// The queue of bakes waiting for a worker: higher priority first, FIFO among
// equal priorities (by submission sequence number). Bounded by --max-queued.
// Thread-safe; workers block in pop().
#pragma once

#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <optional>
#include <set>
#include <string>

#include "common/status.h"

namespace luxel::service {

class JobQueue {
 public:
  explicit JobQueue(size_t max_queued) : max_queued_(max_queued) {}

  // RESOURCE_EXHAUSTED naming --max-queued when full. `force` skips the limit
  // (bakes re-queued at startup were accepted before).
  Status push(const std::string& bake_id, int priority, uint64_t seq, bool force = false);
  // OK when one more job fits.
  Status check_room() const;
  // Blocks until a job is available or the queue is closed (nullopt).
  std::optional<std::string> pop();
  // Takes a queued bake out (cancel); false when it is not queued.
  bool remove(const std::string& bake_id);
  // Wakes every pop() with nullopt; later pushes still store jobs (they are
  // persisted as QUEUED and picked up after a restart).
  void close();
  size_t size() const;

 private:
  struct Job {
    int priority;
    uint64_t seq;
    std::string bake_id;
    bool operator<(const Job& o) const {
      if (priority != o.priority) return priority > o.priority;  // higher first
      return seq < o.seq;                                        // then FIFO
    }
  };
  Status room_locked() const;  // mu_ held

  const size_t max_queued_;
  mutable std::mutex mu_;
  std::condition_variable cv_;
  std::set<Job> jobs_;
  bool closed_ = false;
};

}  // namespace luxel::service
