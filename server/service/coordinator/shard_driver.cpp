// The coordinator's shard threads (sharded_run.h): each shard is assigned
// to a worker, watched, re-attached, reassigned when its worker is lost,
// and downloaded; and the state they share (notes, the persisted plan).
#include <algorithm>
#include <chrono>
#include <fstream>
#include <thread>

#include "common/sha256.h"
#include "output/reference_exr.h"
#include "service/coordinator/sharded_run.h"
#include "service/files.h"
#include "service/log.h"
#include "service/metrics.h"
#include "settings/fingerprint.h"
#include "shards/checkpoint.h"

namespace luxel::service::coordinator {

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

bool Run::refused_credentials(uint32_t k, const std::string& worker, const grpc::Status& st) {
  if (st.error_code() != grpc::StatusCode::UNAUTHENTICATED &&
      st.error_code() != grpc::StatusCode::PERMISSION_DENIED)
    return false;
  {
    std::lock_guard<std::mutex> lock(mu_);
    credential_refusals_[k].push_back(worker + ": " + grpc_text(st));
  }
  reassign(k, worker, "refused the coordinator's credentials (" + grpc_text(st) + ")");
  return true;
}

grpc::Status Run::ensure_scene(const std::string& worker) {
  auto stub = pool_.stub(worker);
  const std::string scene_id = job_.info.scene_id();
  {
    grpc::ClientContext ctx;
    pool_.prepare(ctx, 10);
    v1::GetSceneRequest req;
    req.set_scene_id(scene_id);
    v1::SceneInfo info;
    grpc::Status st = stub->GetScene(&ctx, req, &info);
    if (st.ok()) return st;
    if (st.error_code() != grpc::StatusCode::NOT_FOUND) {
      log_event("worker_unreachable",
                {{"bake", job_.bake_id}, {"worker", worker}, {"error", grpc_text(st)}});
      return st;
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
  if (st.ok() && info.scene_id() != scene_id)
    st = grpc::Status(grpc::StatusCode::INTERNAL, "the worker's scene id differs");
  if (!st.ok()) {
    log_event("worker_upload_failed",
              {{"bake", job_.bake_id}, {"worker", worker}, {"error", grpc_text(st)}});
    return st;
  }
  log_event("worker_scene_uploaded",
            {{"bake", job_.bake_id}, {"worker", worker}, {"bytes", std::to_string(bytes)}});
  return st;
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
    std::vector<std::string> refusals;
    {
      std::lock_guard<std::mutex> lock(mu_);
      refusals = credential_refusals_[k];
    }
    if (!refusals.empty()) {
      // Configuration, not a fault: say so instead of a generic give-up.
      std::string who;
      for (const std::string& r : refusals) who += (who.empty() ? "" : "; ") + r;
      fail(Status(StatusCode::kUnauthenticated,
                  strprintf("shard %u: workers refused the coordinator's credentials (%s); give "
                            "the coordinator the workers' token (--token-file or LUXELD_TOKEN)",
                            k, who.c_str())));
    } else {
      fail(Status(
          StatusCode::kUnavailable,
          strprintf("shard %u: given up after %u attempts on workers (see notes)", k, give_up)));
    }
    return false;
  }
  if (grpc::Status scene = ensure_scene(worker); !scene.ok())
    return refused_credentials(k, worker, scene);
  grpc::ClientContext ctx;
  pool_.prepare(ctx, 30);
  v1::SubmitBakeRequest req;
  req.set_scene_id(job_.info.scene_id());
  *req.mutable_settings() = shard_settings(job_.info.settings(), k, plan_.count);
  req.set_idempotency_key(shard_idempotency_key(job_.bake_id, k, attempt));
  v1::BakeInfo info;
  grpc::Status st = pool_.stub(worker)->SubmitBake(&ctx, req, &info);
  if (!st.ok()) {
    if (refused_credentials(k, worker, st)) return true;
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
  const auto since = SteadyClock::now();
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
  const auto t0 = SteadyClock::now();
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
  std::optional<SteadyClock::time_point> no_worker_since;
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
      if (!no_worker_since) no_worker_since = SteadyClock::now();
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

}  // namespace luxel::service::coordinator
