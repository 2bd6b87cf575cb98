// Bake records on disk and in memory, and the change feed watchers follow.
//
//   <data>/bakes/<bake_id>/record.json      the record (nlohmann JSON; the
//                                            BakeInfo in protobuf JSON form
//                                            plus the queue sequence number)
//   <data>/bakes/<bake_id>/checkpoint.bin   the latest checkpoint (shards/checkpoint.h)
//   <data>/bakes/<bake_id>/results/         write_bake_outputs() files of a finished bake
//
// The record is rewritten atomically (tmp, fsync, rename, fsync dir) on every
// state change and at checkpoints; progress in between lives in memory only.
// Every update bumps the bake's version and wakes its watchers; the newest
// snapshot is kept in one slot per bake (older ones are dropped), so a slow
// watcher reads the latest state and never holds the bake back.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "common/status.h"
#include "luxel/v1/luxel.pb.h"
#include "service/snapshot_encode.h"

namespace luxel::service {

// What a watcher sees of one bake at one moment.
struct BakeView {
  v1::BakeInfo info;
  uint64_t version = 0;
  std::shared_ptr<const SnapshotFrame> snapshot;  // newest, may be null
  uint64_t snapshot_seq = 0;                      // 0: none yet
};

bool is_terminal(v1::BakeState state);

class BakeStore {
 public:
  // Loads every record. Records whose bake was RUNNING are returned as they
  // are; BakeRunner decides what becomes of them (INTERRUPTED, re-queued).
  static Result<std::unique_ptr<BakeStore>> open(const std::string& data_dir);

  struct Created {
    v1::BakeInfo info;
    bool created = false;  // false: an earlier call with the same idempotency key
  };
  // Writes a QUEUED record durably before returning. With a key already
  // used: that bake, or INVALID_ARGUMENT when it was for another scene.
  Result<Created> create(const std::string& scene_id, const v1::BakeSettings& settings,
                         const std::string& idempotency_key);

  Result<v1::BakeInfo> get(const std::string& bake_id) const;
  // The bake created with this idempotency key, if any.
  std::optional<v1::BakeInfo> find_by_key(const std::string& idempotency_key) const;
  // Sorted by submission order; `states` empty = all.
  std::vector<v1::BakeInfo> list(const std::vector<v1::BakeState>& states) const;
  // Queue order of a bake (submission sequence number).
  uint64_t sequence(const std::string& bake_id) const;

  // Applies `change` under the store lock, wakes watchers, and (persist)
  // rewrites the record atomically. NOT_FOUND for an unknown id.
  Status update(const std::string& bake_id, const std::function<void(v1::BakeInfo&)>& change,
                bool persist);
  // Replaces the bake's snapshot slot and wakes watchers (memory only).
  void publish_snapshot(const std::string& bake_id, std::shared_ptr<const SnapshotFrame> frame);

  // The current view; NOT_FOUND for an unknown id.
  Result<BakeView> view(const std::string& bake_id) const;
  // Waits up to `timeout` for a version newer than `seen`; returns the view
  // either way (a watcher polls its client's liveness between waits).
  Result<BakeView> wait_for_change(const std::string& bake_id, uint64_t seen,
                                   std::chrono::milliseconds timeout) const;
  // Wakes every watcher (shutdown).
  void wake_all() const;

  // True while a QUEUED, RUNNING or INTERRUPTED bake uses the scene.
  bool scene_in_use(const std::string& scene_id, std::string* bake_id = nullptr) const;
  std::map<std::string, uint64_t> count_by_state() const;

  std::string bake_dir(const std::string& bake_id) const { return bakes_dir_ + "/" + bake_id; }
  std::string checkpoint_path(const std::string& bake_id) const {
    return bake_dir(bake_id) + "/checkpoint.bin";
  }
  std::string results_dir(const std::string& bake_id) const {
    return bake_dir(bake_id) + "/results";
  }

 private:
  struct Entry {
    v1::BakeInfo info;
    uint64_t seq = 0;
    uint64_t version = 1;
    std::shared_ptr<const SnapshotFrame> snapshot;
    uint64_t snapshot_seq = 0;
    std::mutex file_mu;  // orders record writes of this bake
    mutable std::condition_variable changed;
  };
  explicit BakeStore(std::string data_dir);
  Status persist(Entry& entry);
  std::shared_ptr<Entry> find(const std::string& bake_id) const;

  std::string bakes_dir_;
  mutable std::mutex mu_;
  std::map<std::string, std::shared_ptr<Entry>> bakes_;
  std::map<std::string, std::string> by_key_;  // idempotency key -> bake id
  uint64_t next_seq_ = 1;
};

}  // namespace luxel::service
