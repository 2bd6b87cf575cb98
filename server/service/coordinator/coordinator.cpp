#include "service/coordinator/coordinator.h"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <set>
#include <thread>
#include <vector>

#include "api/scene_files.h"
#include "common/sha256.h"
#include "output/reference_exr.h"
#include "service/coordinator/shard_plan.h"
#include "service/files.h"
#include "service/log.h"
#include "service/metrics.h"
#include "settings/fingerprint.h"
#include "shards/checkpoint.h"
#include "shards/shard_merge.h"

namespace luxel::service::coordinator {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

constexpr const char* kAccumulators = "accumulators.bin";
constexpr size_t kUploadChunkBytes = 64 * 1024;

double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

std::string grpc_text(const grpc::Status& s) {
  return strprintf("%d: %s", int(s.error_code()), s.error_message().c_str());
}

// One sharded bake in flight: the shard threads and the loop that combines them.
class Run {
 public:
  Run(BakeStore& bakes, WorkerPool& pool, const CoordinatorOptions& options, const ShardedJob& job)
      : bakes_(bakes), pool_(pool), options_(options), job_(job) {}

  Result<pipeline::BakeResult> execute();

 private:
  enum class WatchEnd { kTerminal, kRewatch, kLost, kStall, kGone, kStopped };

  // ---- state shared by the threads (mu_)
  void note(const std::string& line);
  void count(const char* event) {
    if (options_.metrics) options_.metrics->shard_event(event);
  }
  Status persist_locked();
  void fail(const Status& why);
  bool stopped() const { return stop_.load(); }
  void sleep_for(double s);

  // ---- one shard's thread
  void drive(uint32_t k);
  bool assign(uint32_t k);
  bool ensure_scene(const std::string& worker);
  WatchEnd watch(uint32_t k, const std::string& worker, const std::string& worker_bake,
                 v1::BakeInfo* terminal, grpc::Status* why);
  void lost(uint32_t k, const std::string& worker, const std::string& worker_bake,
            const std::string& why);
  void reassign(uint32_t k, const std::string& worker, const std::string& why);
  void finished(uint32_t k, const std::string& worker, const v1::BakeInfo& terminal);
  Status download(uint32_t k, const std::string& worker, const std::string& worker_bake,
                  std::string* sha256);

  // ---- stop rules across shards
  void decide_stop(const v1::BakeProgress& combined);
  void ask_to_finish(uint32_t k, const std::string& worker, const std::string& worker_bake);

  // ---- the combining loop
  v1::BakeProgress publish_progress();
  void publish_snapshot();
  // CancelBake (finish: keep what it traced) of a worker's bake, within deadline_s.
  grpc::Status cancel_on(const std::string& worker, const std::string& worker_bake, bool finish,
                         double deadline_s);
  void cancel_workers();
  void cancel_abandoned();
  Status fold_downloaded();
  Result<pipeline::BakeResult> merge();

  std::string shard_path(uint32_t k) const { return dir_ + strprintf("/%u.bin", k); }

  BakeStore& bakes_;
  WorkerPool& pool_;
  const CoordinatorOptions& options_;
  const ShardedJob& job_;
  std::string dir_;          // <bake dir>/shards
  std::string fingerprint_;  // every shard's accumulators carry it
  cli::remote::SceneFiles scene_files_;

  std::mutex mu_;
  ShardPlan plan_;
  std::vector<v1::ShardStatus> status_;
  std::vector<v1::Snapshot> snapshots_;  // newest EXR snapshot per shard
  uint64_t snapshot_changes_ = 0;
  uint32_t previews_ = 0;                            // merged snapshots published
  double preview_s_ = 0;                             // seconds spent decoding and averaging them
  std::map<uint32_t, grpc::ClientContext*> active_;  // open WatchBake calls (TryCancel on stop)
  std::optional<Status> failure_;
  std::set<std::string> finish_sent_;  // worker bakes asked to finish (this process)
  bool stop_rules_ = false;            // the bake has a time budget or target error
  // The merge as a fold (pipeline::ShardMerger), in shard order, as shards
  // arrive: shard k is folded once shards 0..k are downloaded. Only the
  // combining loop's thread touches it.
  pipeline::ShardMerger merger_;
  double fold_read_s_ = 0, fold_merge_s_ = 0;
  std::atomic<bool> stop_{false};
  std::condition_variable wake_;
};

void Run::note(const std::string& line) {
  log_event("coordinator_note", {{"bake", job_.bake_id}, {"note", line}});
  (void)bakes_.update(
      job_.bake_id, [&](v1::BakeInfo& b) { b.add_notes(line); }, true);
}

Status Run::persist_locked() {
  return write_file_atomic(bakes_.bake_dir(job_.bake_id) + "/shards.json", plan_to_json(plan_));
}

void Run::fail(const Status& why) {
  std::lock_guard<std::mutex> lock(mu_);
  if (!failure_) failure_ = why;
  stop_ = true;
  for (auto& [k, ctx] : active_) ctx->TryCancel();
  wake_.notify_all();
}

void Run::sleep_for(double s) {
  std::unique_lock<std::mutex> lock(mu_);
  wake_.wait_for(lock, std::chrono::milliseconds(static_cast<int64_t>(s * 1000)),
                 [&] { return stop_.load(); });
}

bool Run::ensure_scene(const std::string& worker) {
  auto stub = pool_.stub(worker);
  const std::string scene_id = job_.info.scene_id();
  {
    grpc::ClientContext ctx;
    pool_.prepare(ctx, 10);
    v1::GetSceneRequest req;
    req.set_scene_id(scene_id);
    v1::SceneInfo info;
    grpc::Status st = stub->GetScene(&ctx, req, &info);
    if (st.ok()) return true;
    if (st.error_code() != grpc::StatusCode::NOT_FOUND) {
      log_event("worker_unreachable",
                {{"bake", job_.bake_id}, {"worker", worker}, {"error", grpc_text(st)}});
      return false;
    }
  }
  // Same files, same bytes: the worker's scene id is the coordinator's.
  grpc::ClientContext ctx;
  pool_.prepare(ctx, 600);
  v1::SceneInfo info;
  auto writer = stub->UploadScene(&ctx, &info);
  v1::UploadSceneRequest first;
  *first.mutable_header() = cli::remote::upload_header(scene_files_, job_.scene_name);
  bool ok = writer->Write(first);
  uint64_t bytes = 0;
  std::vector<const cli::remote::SceneFile*> files = {&scene_files_.main};
  for (const auto& r : scene_files_.resources) files.push_back(&r);
  std::string chunk(kUploadChunkBytes, '\0');
  for (const auto* f : files) {
    std::ifstream in(f->path, std::ios::binary);
    while (ok && in) {
      in.read(chunk.data(), static_cast<std::streamsize>(chunk.size()));
      const auto n = static_cast<size_t>(in.gcount());
      if (n == 0) break;
      v1::UploadSceneRequest m;
      m.set_chunk(chunk.data(), n);
      bytes += n;
      ok = writer->Write(m);
    }
  }
  writer->WritesDone();
  grpc::Status st = writer->Finish();
  if (!st.ok() || info.scene_id() != scene_id) {
    log_event("worker_upload_failed", {{"bake", job_.bake_id},
                                       {"worker", worker},
                                       {"error", st.ok() ? "scene id differs" : grpc_text(st)}});
    return false;
  }
  log_event("worker_scene_uploaded",
            {{"bake", job_.bake_id}, {"worker", worker}, {"bytes", std::to_string(bytes)}});
  return true;
}

bool Run::assign(uint32_t k) {
  const std::vector<std::string> workers = pool_.resolve();
  std::string worker;
  uint32_t attempt = 0, give_up = 0;
  {
    std::lock_guard<std::mutex> lock(mu_);
    ShardRecord& rec = plan_.shards[k];
    if (rec.worker.empty() && !workers.empty() && rec.attempts >= options_.max_attempts)
      give_up = rec.attempts;
    if (rec.worker.empty() && !give_up) {
      if (workers.empty()) return false;
      // Workers that have not failed this shard first, then the least
      // loaded, then rotation by shard index so shards spread on equal load.
      std::map<std::string, int> load;
      for (const ShardRecord& r : plan_.shards)
        if (!r.worker.empty() && !r.downloaded) ++load[r.worker];
      auto bad = [&](const std::string& w) {
        return std::find(rec.bad_workers.begin(), rec.bad_workers.end(), w) !=
               rec.bad_workers.end();
      };
      size_t best = 0;
      for (size_t i = 1; i <= workers.size(); ++i) {
        const std::string& w = workers[(k + i) % workers.size()];
        const std::string& b = workers[(k + best) % workers.size()];
        auto key = [&](const std::string& x) { return std::make_pair(bad(x), load[x]); };
        if (i == 1 || key(w) < key(b)) best = i;
      }
      rec.worker = workers[(k + best) % workers.size()];
      rec.worker_bake_id.clear();
      ++rec.attempts;
      // On disk before the submission: a restart re-submits to this worker
      // with this key and gets the same worker bake back.
      if (Status st = persist_locked(); !st.is_ok())
        log_event("coordinator_persist_failed", {{"error", st.to_string()}});
    }
    worker = rec.worker;
    attempt = rec.attempts;
  }
  if (give_up) {
    fail(Status(
        StatusCode::kUnavailable,
        strprintf("shard %u: given up after %u attempts on workers (see notes)", k, give_up)));
    return false;
  }
  if (!ensure_scene(worker)) return false;
  grpc::ClientContext ctx;
  pool_.prepare(ctx, 30);
  v1::SubmitBakeRequest req;
  req.set_scene_id(job_.info.scene_id());
  *req.mutable_settings() = shard_settings(job_.info.settings(), k, plan_.count);
  req.set_idempotency_key(shard_idempotency_key(job_.bake_id, k, attempt));
  v1::BakeInfo info;
  grpc::Status st = pool_.stub(worker)->SubmitBake(&ctx, req, &info);
  if (!st.ok()) {
    if (st.error_code() == grpc::StatusCode::INVALID_ARGUMENT ||
        st.error_code() == grpc::StatusCode::FAILED_PRECONDITION) {
      // The worker refuses these settings (another Luxel version, a smaller
      // --max-resolution): another worker may take them.
      reassign(k, worker, "refused the shard: " + grpc_text(st));
      return true;
    }
    return false;  // unreachable: retried (and past the grace, reassigned) by drive()
  }
  {
    std::lock_guard<std::mutex> lock(mu_);
    ShardRecord& rec = plan_.shards[k];
    rec.worker_bake_id = info.bake_id();
    status_[k].set_worker(worker);
    status_[k].set_worker_bake_id(info.bake_id());
    status_[k].set_attempts(rec.attempts);
    status_[k].set_state(v1::SHARD_STATE_RUNNING);
    if (Status p = persist_locked(); !p.is_ok())
      log_event("coordinator_persist_failed", {{"error", p.to_string()}});
  }
  count("submitted");
  note(strprintf("shard %u/%u: submitted to worker %s as bake %s (attempt %u)", k, plan_.count,
                 worker.c_str(), info.bake_id().c_str(), attempt));
  return true;
}

Run::WatchEnd Run::watch(uint32_t k, const std::string& worker, const std::string& worker_bake,
                         v1::BakeInfo* terminal, grpc::Status* why) {
  grpc::ClientContext ctx;
  pool_.prepare(ctx, options_.stall_s);
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (stop_) return WatchEnd::kStopped;
    active_[k] = &ctx;
  }
  v1::WatchBakeRequest req;
  req.set_bake_id(worker_bake);
  auto reader = pool_.stub(worker)->WatchBake(&ctx, req);
  uint64_t first_paths = UINT64_MAX, last_paths = 0;
  bool queued = false, got_terminal = false;
  v1::BakeEvent ev;
  while (reader->Read(&ev)) {
    const v1::BakeInfo& info = ev.info();
    if (first_paths == UINT64_MAX) first_paths = info.progress().paths();
    last_paths = info.progress().paths();
    queued = info.state() == v1::BAKE_STATE_QUEUED || info.state() == v1::BAKE_STATE_INTERRUPTED;
    {
      std::lock_guard<std::mutex> lock(mu_);
      *status_[k].mutable_progress() = info.progress();
      // The combining loop judges the time and error rules on every report.
      if (stop_rules_) wake_.notify_all();
      if (ev.has_snapshot() && ev.snapshot().format() == v1::SNAPSHOT_FORMAT_EXR) {
        snapshots_[k] = ev.snapshot();
        ++snapshot_changes_;
      }
    }
    if (ev.final() || is_terminal(info.state())) {
      *terminal = info;
      got_terminal = is_terminal(info.state());
      ctx.TryCancel();
      break;
    }
  }
  *why = reader->Finish();
  {
    std::lock_guard<std::mutex> lock(mu_);
    active_.erase(k);
  }
  if (got_terminal) return WatchEnd::kTerminal;
  if (stopped()) return WatchEnd::kStopped;
  if (why->error_code() == grpc::StatusCode::NOT_FOUND) return WatchEnd::kGone;
  if (why->error_code() == grpc::StatusCode::DEADLINE_EXCEEDED && first_paths != UINT64_MAX)
    return last_paths > first_paths || queued ? WatchEnd::kRewatch : WatchEnd::kStall;
  return WatchEnd::kLost;
}

void Run::reassign(uint32_t k, const std::string& worker, const std::string& why) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    ShardRecord& rec = plan_.shards[k];
    if (std::find(rec.bad_workers.begin(), rec.bad_workers.end(), worker) == rec.bad_workers.end())
      rec.bad_workers.push_back(worker);
    if (!rec.worker_bake_id.empty()) plan_.abandoned.emplace_back(worker, rec.worker_bake_id);
    rec.worker.clear();
    rec.worker_bake_id.clear();
    snapshots_[k].Clear();
    status_[k].clear_progress();
    status_[k].set_state(v1::SHARD_STATE_PENDING);
    if (Status st = persist_locked(); !st.is_ok())
      log_event("coordinator_persist_failed", {{"error", st.to_string()}});
  }
  count("reassigned");
  note(strprintf("shard %u/%u: worker %s %s; reassigned (restarts from zero, same result)", k,
                 plan_.count, worker.c_str(), why.c_str()));
}

void Run::lost(uint32_t k, const std::string& worker, const std::string& worker_bake,
               const std::string& why) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    status_[k].set_state(v1::SHARD_STATE_RETRYING);
  }
  count("lost");
  note(strprintf("shard %u/%u: worker %s lost (%s); retrying for %.0f s", k, plan_.count,
                 worker.c_str(), why.c_str(), options_.grace_s));
  const auto since = Clock::now();
  while (!stopped() && seconds_since(since) < options_.grace_s) {
    sleep_for(std::min(1.0, std::max(0.1, options_.grace_s / 10)));
    grpc::ClientContext ctx;
    pool_.prepare(ctx, 2);
    v1::GetBakeRequest req;
    req.set_bake_id(worker_bake);
    v1::BakeInfo info;
    grpc::Status st = pool_.stub(worker)->GetBake(&ctx, req, &info);
    if (st.ok()) {
      {
        std::lock_guard<std::mutex> lock(mu_);
        status_[k].set_state(v1::SHARD_STATE_RUNNING);
      }
      count("reattached");
      note(strprintf("shard %u/%u: re-attached to bake %s on worker %s (%s, %llu paths)", k,
                     plan_.count, worker_bake.c_str(), worker.c_str(),
                     v1::BakeState_Name(info.state()).c_str(),
                     static_cast<unsigned long long>(info.progress().paths())));
      return;
    }
    if (st.error_code() == grpc::StatusCode::NOT_FOUND) break;
  }
  if (stopped()) return;
  reassign(k, worker, strprintf("unreachable for %.0f s", options_.grace_s));
}

Status Run::download(uint32_t k, const std::string& worker, const std::string& worker_bake,
                     std::string* sha256) {
  const std::string part = shard_path(k) + ".part";
  grpc::ClientContext ctx;
  pool_.prepare(ctx, 0);
  v1::DownloadResultRequest req;
  req.set_bake_id(worker_bake);
  req.set_artifact(kAccumulators);
  auto reader = pool_.stub(worker)->DownloadResult(&ctx, req);
  std::ofstream out(part, std::ios::binary | std::ios::trunc);
  Sha256 hash;
  uint64_t bytes = 0, total = 0;
  std::string sent_sha;
  const auto t0 = Clock::now();
  v1::DownloadResultResponse msg;
  while (reader->Read(&msg)) {
    if (msg.total_size()) total = msg.total_size();
    hash.update(msg.chunk());
    out.write(msg.chunk().data(), static_cast<std::streamsize>(msg.chunk().size()));
    bytes += msg.chunk().size();
    if (!msg.sha256().empty()) sent_sha = msg.sha256();
  }
  out.close();
  grpc::Status st = reader->Finish();
  if (!st.ok()) {
    std::remove(part.c_str());
    return Status(st.error_code() == grpc::StatusCode::NOT_FOUND ? StatusCode::kDataLoss
                                                                 : StatusCode::kUnavailable,
                  "download of " + std::string(kAccumulators) + ": " + grpc_text(st));
  }
  *sha256 = hash.hex_digest();
  if (!out || bytes != total || sent_sha != *sha256) {
    std::remove(part.c_str());
    return data_loss(strprintf("%s: %llu of %llu bytes, sha256 %s, stream said %s", kAccumulators,
                               static_cast<unsigned long long>(bytes),
                               static_cast<unsigned long long>(total), sha256->c_str(),
                               sent_sha.c_str()));
  }
  auto ckpt = pipeline::read_checkpoint(part);
  Status verdict = Status::ok();
  if (!ckpt)
    verdict = data_loss(std::string(kAccumulators) + " unreadable: " + ckpt.status().to_string());
  else if (ckpt->fingerprint != fingerprint_)
    verdict =
        data_loss(strprintf("%s belongs to another scene or other settings (fingerprint "
                            "%.16s, expected %.16s)",
                            kAccumulators, ckpt->fingerprint.c_str(), fingerprint_.c_str()));
  else if (ckpt->shard_index != k || ckpt->shard_count != plan_.count)
    verdict = data_loss(strprintf("%s is shard %u/%u, expected %u/%u", kAccumulators,
                                  ckpt->shard_index, ckpt->shard_count, k, plan_.count));
  if (!verdict.is_ok()) {
    std::remove(part.c_str());
    return verdict;
  }
  LUXEL_RETURN_IF_ERROR(rename_durable(part, shard_path(k)));
  count("downloaded");
  if (options_.metrics) options_.metrics->shard_downloaded(bytes, seconds_since(t0));
  log_event("shard_downloaded", {{"bake", job_.bake_id},
                                 {"shard", std::to_string(k)},
                                 {"worker", worker},
                                 {"bytes", std::to_string(bytes)},
                                 {"seconds", strprintf("%.3f", seconds_since(t0))}});
  return Status::ok();
}

void Run::finished(uint32_t k, const std::string& worker, const v1::BakeInfo& terminal) {
  if (terminal.state() != v1::BAKE_STATE_SUCCEEDED) {
    reassign(
        k, worker,
        strprintf("ended its shard bake %s %s%s%s", terminal.bake_id().c_str(),
                  v1::BakeState_Name(terminal.state()).c_str(),
                  terminal.error_message().empty() ? "" : ": ", terminal.error_message().c_str()));
    return;
  }
  std::string sha;
  Status st = download(k, worker, terminal.bake_id(), &sha);
  if (st.code() == StatusCode::kUnavailable) {
    lost(k, worker, terminal.bake_id(), st.message());
    return;
  }
  if (!st.is_ok()) {
    reassign(k, worker, "returned unusable accumulators (" + st.to_string() + "): rejected");
    return;
  }
  std::lock_guard<std::mutex> lock(mu_);
  ShardRecord& rec = plan_.shards[k];
  rec.downloaded = true;
  rec.sha256 = sha;
  rec.termination = terminal.termination();
  *status_[k].mutable_progress() = terminal.progress();
  status_[k].set_state(v1::SHARD_STATE_DOWNLOADED);
  if (Status p = persist_locked(); !p.is_ok())
    log_event("coordinator_persist_failed", {{"error", p.to_string()}});
  wake_.notify_all();
}

void Run::drive(uint32_t k) {
  std::optional<Clock::time_point> no_worker_since;
  while (!stopped()) {
    std::string worker, worker_bake;
    {
      std::lock_guard<std::mutex> lock(mu_);
      const ShardRecord& rec = plan_.shards[k];
      if (rec.downloaded) return;
      worker = rec.worker;
      worker_bake = rec.worker_bake_id;
    }
    if (worker_bake.empty()) {
      if (assign(k)) {
        no_worker_since.reset();
        continue;
      }
      if (!no_worker_since) no_worker_since = Clock::now();
      // No worker takes it (none resolved, or the chosen one unreachable):
      // past the grace, the chosen one counts as lost for this shard.
      if (seconds_since(*no_worker_since) > options_.grace_s) {
        no_worker_since.reset();
        if (!worker.empty()) reassign(k, worker, "did not take the shard within the grace period");
      }
      sleep_for(0.5);
      continue;
    }
    ask_to_finish(k, worker, worker_bake);
    v1::BakeInfo terminal;
    grpc::Status why;
    switch (watch(k, worker, worker_bake, &terminal, &why)) {
      case WatchEnd::kTerminal:
        finished(k, worker, terminal);
        break;
      case WatchEnd::kRewatch:
      case WatchEnd::kStopped:
        break;
      case WatchEnd::kGone:
        reassign(k, worker, "no longer knows bake " + worker_bake);
        break;
      case WatchEnd::kStall:
        reassign(k, worker, strprintf("made no progress for %.0f s", options_.stall_s));
        break;
      case WatchEnd::kLost:
        lost(k, worker, worker_bake, grpc_text(why));
        break;
    }
  }
}

v1::BakeProgress Run::publish_progress() {
  std::vector<v1::BakeProgress> parts;
  std::vector<v1::ShardStatus> shards;
  {
    std::lock_guard<std::mutex> lock(mu_);
    shards = status_;
  }
  for (const auto& s : shards) parts.push_back(s.progress());
  const v1::BakeProgress combined = combine_progress(parts);
  (void)bakes_.update(
      job_.bake_id,
      [&](v1::BakeInfo& b) {
        *b.mutable_progress() = combined;
        b.clear_shards();
        for (const auto& s : shards) *b.add_shards() = s;
      },
      false);
  return combined;
}

// Called by the combining loop with the shards' summed progress. Once a rule
// is reached it is recorded (a restarted coordinator keeps it) and every
// shard bake is asked to finish; shards assigned later are asked as soon as
// they are submitted (drive()).
void Run::decide_stop(const v1::BakeProgress& combined) {
  const v1::BakeSettings& s = job_.info.settings();
  std::string rule, why;
  if (job_.finish && job_.finish->load()) {
    rule = "stopped";
    why = "CancelBake asked to finish";
  } else if (s.target_error() > 0 && combined.error() <= s.target_error()) {
    rule = "error";
    why = strprintf("the shards' combined error estimate %.4g reached the target %.4g",
                    combined.error(), s.target_error());
  } else if (s.time_budget_s() > 0 && combined.elapsed_s() >= s.time_budget_s()) {
    rule = "time";
    why = strprintf("the shards traced for %.2f s of the %.2f s budget", combined.elapsed_s(),
                    s.time_budget_s());
  }
  if (rule.empty()) return;
  std::vector<ShardRecord> recs;
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (!plan_.stop.empty()) return;
    plan_.stop = rule;
    if (Status st = persist_locked(); !st.is_ok())
      log_event("coordinator_persist_failed", {{"error", st.to_string()}});
    recs = plan_.shards;
  }
  note(strprintf("stop rule \"%s\": %s; every shard asked to finish with what it traced",
                 rule.c_str(), why.c_str()));
  for (const ShardRecord& r : recs)
    if (!r.downloaded && !r.worker_bake_id.empty())
      ask_to_finish(r.index, r.worker, r.worker_bake_id);
}

// CancelBake with finish on a shard bake, once per bake and process, when a
// stop rule is decided. A failed call is not retried here: the shard's
// watcher calls again after its next re-attach.
void Run::ask_to_finish(uint32_t k, const std::string& worker, const std::string& worker_bake) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (plan_.stop.empty() || finish_sent_.count(worker_bake)) return;
  }
  grpc::Status st = cancel_on(worker, worker_bake, true, 5);
  if (!st.ok()) {
    log_event("shard_finish_failed", {{"bake", job_.bake_id},
                                      {"shard", std::to_string(k)},
                                      {"worker", worker},
                                      {"error", grpc_text(st)}});
    return;
  }
  count("finish_asked");
  std::lock_guard<std::mutex> lock(mu_);
  finish_sent_.insert(worker_bake);
}

// The shards' newest EXR snapshots, averaged per texel weighted by each
// shard's paths: a preview of the merged state, not the merged state (a
// shard's snapshot is its resolved mean; merging means by path counts is
// exact only where every texel got the same share, which uniform sampling
// gives up to one sample). The final result comes from the exact merge.
void Run::publish_snapshot() {
  const auto t0 = Clock::now();
  std::vector<v1::Snapshot> snaps;
  {
    std::lock_guard<std::mutex> lock(mu_);
    snaps = snapshots_;
  }
  output::Image sum;
  double total = 0;
  uint32_t pages = 1;
  std::vector<v1::BakeProgress> parts;
  for (size_t k = 0; k < snaps.size(); ++k) {
    const v1::Snapshot& s = snaps[k];
    parts.push_back(s.progress());
    if (s.data().empty()) continue;
    const std::string scratch = dir_ + strprintf("/snapshot-%zu.exr", k);
    if (!write_file_atomic(scratch, s.data()).is_ok()) continue;
    auto img = output::read_reference_exr(scratch);
    std::remove(scratch.c_str());
    if (!img) continue;
    const double w = double(std::max<uint64_t>(s.progress().paths(), 1));
    if (sum.pixels.empty()) {
      sum = output::Image{img->width, img->height, 4, std::vector<float>(img->pixels.size(), 0.0f)};
      pages = std::max<uint32_t>(1, s.pages());
    }
    if (img->width != sum.width || img->height != sum.height) continue;
    for (size_t i = 0; i < sum.pixels.size(); ++i)
      sum.pixels[i] += static_cast<float>(w * img->pixels[i]);
    total += w;
  }
  if (total <= 0) return;
  for (float& x : sum.pixels) x = static_cast<float>(x / total);
  const v1::BakeSettings& s = job_.info.settings();
  const int max_side = s.snapshot_max_side() ? int(s.snapshot_max_side()) : 512;
  bakes_.publish_snapshot(
      job_.bake_id,
      std::make_shared<SnapshotFrame>(std::move(sum), combine_progress(parts), s.snapshot_format(),
                                      max_side, bakes_.bake_dir(job_.bake_id), int(pages), false));
  ++previews_;
  preview_s_ += seconds_since(t0);
}

grpc::Status Run::cancel_on(const std::string& worker, const std::string& worker_bake, bool finish,
                            double deadline_s) {
  grpc::ClientContext ctx;
  pool_.prepare(ctx, deadline_s);
  v1::CancelBakeRequest req;
  req.set_bake_id(worker_bake);
  req.set_finish(finish);
  v1::BakeInfo info;
  return pool_.stub(worker)->CancelBake(&ctx, req, &info);
}

void Run::cancel_workers() {
  std::vector<ShardRecord> recs;
  {
    std::lock_guard<std::mutex> lock(mu_);
    recs = plan_.shards;
  }
  for (const ShardRecord& r : recs) {
    if (r.downloaded || r.worker_bake_id.empty()) continue;
    (void)cancel_on(r.worker, r.worker_bake_id, false, 2);
  }
}

// Best effort, from the combining loop and at the end: a reassigned shard's
// old bake would otherwise run to its end on a worker that comes back (a
// restarted luxeld resumes its bakes), taking the worker from other shards.
void Run::cancel_abandoned() {
  std::vector<std::pair<std::string, std::string>> todo;
  {
    std::lock_guard<std::mutex> lock(mu_);
    todo = plan_.abandoned;
  }
  if (todo.empty()) return;
  std::vector<std::pair<std::string, std::string>> done;
  for (const auto& [worker, bake] : todo) {
    grpc::Status st = cancel_on(worker, bake, false, 1);
    if (st.ok() || st.error_code() == grpc::StatusCode::NOT_FOUND) {
      done.emplace_back(worker, bake);
      log_event("abandoned_shard_cancelled",
                {{"bake", job_.bake_id}, {"worker", worker}, {"worker_bake", bake}});
    }
  }
  std::lock_guard<std::mutex> lock(mu_);
  for (const auto& d : done)
    plan_.abandoned.erase(std::remove(plan_.abandoned.begin(), plan_.abandoned.end(), d),
                          plan_.abandoned.end());
  if (!done.empty()) (void)persist_locked();
}

// Folds every downloaded shard whose predecessors are folded: the merge
// overlaps the downloads of later shards and holds one shard's state at a
// time (not all of them).
Status Run::fold_downloaded() {
  for (;;) {
    const uint32_t k = merger_.added();
    {
      std::lock_guard<std::mutex> lock(mu_);
      if (k >= plan_.count || !plan_.shards[k].downloaded) return Status::ok();
    }
    const auto t0 = Clock::now();
    auto c = pipeline::read_checkpoint(shard_path(k));
    if (!c)
      return Status(c.status().code(), strprintf("shard %u: %s", k, c.status().message().c_str()));
    fold_read_s_ += seconds_since(t0);
    const auto t1 = Clock::now();
    LUXEL_RETURN_IF_ERROR(merger_.add(c.value()));
    fold_merge_s_ += seconds_since(t1);
  }
}

Result<pipeline::BakeResult> Run::merge() {
  LUXEL_RETURN_IF_ERROR(fold_downloaded());
  auto merged = merger_.finish();
  if (!merged) return merged.status();
  const auto t2 = Clock::now();
  pipeline::BakeHooks hooks;
  hooks.on_layout = [&](const std::string& line) {
    (void)bakes_.update(
        job_.bake_id, [&](v1::BakeInfo& b) { b.set_lightmap_layout(line); }, false);
  };
  const pipeline::Termination why = merged_termination(plan_);
  auto result = pipeline::finish_merged_bake(*job_.scene, *job_.settings, *job_.ctx, merged.value(),
                                             why, hooks);
  if (result && why != pipeline::Termination::kSamples)
    note(strprintf(
        "merged %llu paths of the shards (ended on %s): mean %.1f samples per texel, "
        "minimum %u, error estimate %.4g",
        static_cast<unsigned long long>(result.value().paths), pipeline::termination_name(why),
        result.value().mean_spp, result.value().min_spp, result.value().error));
  log_event("shards_merged", {{"bake", job_.bake_id},
                              {"shards", std::to_string(plan_.count)},
                              {"read_s", strprintf("%.4f", fold_read_s_)},
                              {"merge_s", strprintf("%.4f", fold_merge_s_)},
                              {"finish_s", strprintf("%.4f", seconds_since(t2))}});
  if (options_.metrics)
    options_.metrics->shards_merged(fold_read_s_, fold_merge_s_, seconds_since(t2));
  return result;
}

Result<pipeline::BakeResult> Run::execute() {
  dir_ = bakes_.bake_dir(job_.bake_id) + "/shards";
  LUXEL_RETURN_IF_ERROR(make_directories(dir_));
  if (auto st = cli::remote::collect_scene_files(job_.scene_main_file, scene_files_); !st.ok())
    return Status(StatusCode::kInternal, "scene files for the workers: " + st.error_message());
  const v1::BakeSettings& s = job_.info.settings();

  // The plan: the one on disk (a restarted coordinator), else a new one.
  const std::string plan_file = bakes_.bake_dir(job_.bake_id) + "/shards.json";
  bool resumed = false;
  if (fs::exists(plan_file)) {
    auto text = read_whole_file(plan_file);
    auto plan = text ? plan_from_json(text.value()) : Result<ShardPlan>(text.status());
    if (plan) {
      plan_ = std::move(plan.value());
      resumed = true;
    } else {
      note("coordinator state unreadable (" + plan.status().to_string() + "): sharded anew");
    }
  }
  if (!resumed) {
    uint32_t count = s.shards();
    if (s.shards_auto()) {
      const auto t0 = Clock::now();
      std::vector<std::string> workers;
      while ((workers = pool_.resolve()).empty() && seconds_since(t0) < options_.grace_s &&
             !job_.cancel->load())
        std::this_thread::sleep_for(std::chrono::milliseconds(500));
      if (workers.empty())
        return Status(
            StatusCode::kUnavailable,
            strprintf("settings.shards_auto: no worker resolved within %.0f s", options_.grace_s));
      // At least two: one worker then runs both in turn (a shard bake of
      // shard_count 1 would be a whole bake, without accumulators.bin).
      count =
          usable_shard_count(s, std::max<uint32_t>(2, uint32_t(workers.size())), options_.limits);
      if (count < 2)
        return invalid_argument(
            "settings.samples_per_texel: too few samples to split into 2 shards");
    }
    count = std::max<uint32_t>(count, 1);
    remove_tree(dir_);
    LUXEL_RETURN_IF_ERROR(make_directories(dir_));
    plan_.count = count;
    plan_.shards.resize(count);
    for (uint32_t k = 0; k < count; ++k) plan_.shards[k].index = k;
    LUXEL_RETURN_IF_ERROR(persist_locked());
    note(strprintf("sharded into %u shards across the workers", count));
  } else {
    uint32_t attached = 0, done = 0;
    for (const ShardRecord& r : plan_.shards) {
      if (r.downloaded && !fs::exists(shard_path(r.index))) {
        // Lost from disk (a wiped folder): the shard runs again.
        plan_.shards[r.index] = ShardRecord{.index = r.index, .attempts = r.attempts};
        continue;
      }
      done += r.downloaded;
      attached += !r.downloaded && !r.worker_bake_id.empty();
    }
    LUXEL_RETURN_IF_ERROR(persist_locked());
    note(strprintf("coordinator restarted: %u of %u shards downloaded, re-attaching to %u", done,
                   plan_.count, attached));
  }
  // Every shard's accumulators carry this; shard_index/shard_count are left
  // out of it by the engine, so shard 0's settings stand for all.
  fingerprint_ = pipeline::bake_fingerprint(
      job_.info.scene_id(),
      stored_engine_settings(shard_settings(s, 0, plan_.count), options_.limits));
  status_.resize(plan_.count);
  snapshots_.resize(plan_.count);
  for (uint32_t k = 0; k < plan_.count; ++k) {
    const ShardRecord& r = plan_.shards[k];
    status_[k].set_index(k);
    status_[k].set_worker(r.worker);
    status_[k].set_worker_bake_id(r.worker_bake_id);
    status_[k].set_attempts(r.attempts);
    status_[k].set_state(r.downloaded               ? v1::SHARD_STATE_DOWNLOADED
                         : r.worker_bake_id.empty() ? v1::SHARD_STATE_PENDING
                                                    : v1::SHARD_STATE_RUNNING);
  }

  stop_rules_ = s.time_budget_s() > 0 || s.target_error() > 0;
  std::vector<std::thread> threads;
  for (uint32_t k = 0; k < plan_.count; ++k) threads.emplace_back([this, k] { drive(k); });

  const double progress_every =
      s.progress_interval_s() > 0 ? std::max(0.05, s.progress_interval_s()) : 1.0;
  const double snapshot_every =
      s.snapshot_interval_s() > 0 ? std::max(0.05, s.snapshot_interval_s()) : 5.0;
  auto last_progress = Clock::now(), last_snapshot = Clock::now(), last_cleanup = Clock::now();
  uint64_t snapshots_seen = 0;
  bool all_done = false;
  while (!all_done) {
    {
      std::unique_lock<std::mutex> lock(mu_);
      wake_.wait_for(lock, std::chrono::milliseconds(100));
      all_done = std::all_of(plan_.shards.begin(), plan_.shards.end(),
                             [](const ShardRecord& r) { return r.downloaded; });
      if (failure_) break;
    }
    if (job_.cancel->load() || (job_.stopping && job_.stopping->load())) {
      std::lock_guard<std::mutex> lock(mu_);
      stop_ = true;
      for (auto& [k, ctx] : active_) ctx->TryCancel();
      wake_.notify_all();
      break;
    }
    if (Status st = fold_downloaded(); !st.is_ok()) {
      // A checked download that does not read back: the disk under the
      // data dir failed. The bake fails rather than merge less.
      fail(st);
      break;
    }
    if (seconds_since(last_cleanup) >= 1) {
      cancel_abandoned();
      last_cleanup = Clock::now();
    }
    if (seconds_since(last_progress) >= progress_every || all_done) {
      const v1::BakeProgress combined = publish_progress();
      if (!all_done) decide_stop(combined);
      last_progress = Clock::now();
    } else if (stop_rules_ || (job_.finish && job_.finish->load())) {
      // Between published reports too: the shards trace on while the rule waits.
      std::vector<v1::BakeProgress> parts;
      {
        std::lock_guard<std::mutex> lock(mu_);
        for (const auto& st : status_) parts.push_back(st.progress());
      }
      decide_stop(combine_progress(parts));
    }
    if (s.snapshot_format() != v1::SNAPSHOT_FORMAT_NONE &&
        seconds_since(last_snapshot) >= snapshot_every) {
      uint64_t changes;
      {
        std::lock_guard<std::mutex> lock(mu_);
        changes = snapshot_changes_;
      }
      if (changes != snapshots_seen) {
        publish_snapshot();
        snapshots_seen = changes;
      }
      last_snapshot = Clock::now();
    }
  }
  for (auto& t : threads) t.join();
  publish_progress();
  cancel_abandoned();
  log_event(
      "shards_watched",
      {{"bake", job_.bake_id},
       {"previews", std::to_string(previews_)},
       {"preview_ms_mean", strprintf("%.2f", previews_ ? 1e3 * preview_s_ / previews_ : 0.0)}});
  if (failure_) {
    cancel_workers();
    return failure_.value();
  }
  if (!all_done) {
    // CancelBake cancels the shard bakes; a daemon shutdown leaves them
    // running for the next start to re-attach to.
    if (job_.by_user && job_.by_user->load()) cancel_workers();
    pipeline::BakeResult r;
    r.termination = pipeline::Termination::kCancelled;
    return r;
  }
  return merge();
}

}  // namespace

Coordinator::Coordinator(BakeStore& bakes, CoordinatorOptions options)
    : bakes_(bakes),
      options_(std::move(options)),
      pool_(std::make_unique<WorkerPool>(options_.workers)) {}

Coordinator::~Coordinator() = default;

Result<pipeline::BakeResult> Coordinator::run(const ShardedJob& job) {
  Run run(bakes_, *pool_, options_, job);
  return run.execute();
}

}  // namespace luxel::service::coordinator
