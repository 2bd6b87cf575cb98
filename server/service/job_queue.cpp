#include "service/job_queue.h"

namespace luxel::service {

Status JobQueue::room_locked() const {
  if (jobs_.size() >= max_queued_)
    return resource_exhausted(
        strprintf("queue full: %zu bakes queued, the daemon's limit is --max-queued=%zu",
                  jobs_.size(), max_queued_));
  return Status::ok();
}

Status JobQueue::check_room() const {
  std::lock_guard<std::mutex> lock(mu_);
  return room_locked();
}

Status JobQueue::push(const std::string& bake_id, int priority, uint64_t seq, bool force) {
  {
    // Checked under the lock of the insert: with the check in a separate
    // critical section, racing submits could each see one free place.
    std::lock_guard<std::mutex> lock(mu_);
    if (!force) LUXEL_RETURN_IF_ERROR(room_locked());
    jobs_.insert(Job{priority, seq, bake_id});
  }
  cv_.notify_one();
  return Status::ok();
}

std::optional<std::string> JobQueue::pop() {
  std::unique_lock<std::mutex> lock(mu_);
  cv_.wait(lock, [&] { return closed_ || !jobs_.empty(); });
  if (closed_) return std::nullopt;
  std::string id = jobs_.begin()->bake_id;
  jobs_.erase(jobs_.begin());
  return id;
}

bool JobQueue::remove(const std::string& bake_id) {
  std::lock_guard<std::mutex> lock(mu_);
  for (auto it = jobs_.begin(); it != jobs_.end(); ++it) {
    if (it->bake_id == bake_id) {
      jobs_.erase(it);
      return true;
    }
  }
  return false;
}

void JobQueue::close() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    closed_ = true;
  }
  cv_.notify_all();
}

size_t JobQueue::size() const {
  std::lock_guard<std::mutex> lock(mu_);
  return jobs_.size();
}

}  // namespace luxel::service
