// Durability and control: kill -9 mid-bake and restart on the same data dir
// (the bake resumes from its checkpoint and gives the same lightmap as a bake
// restarted from zero after its checkpoint was torn); SIGTERM checkpoints
// and leaves the bake INTERRUPTED, the next start finishes it; cancel of a
// running and a queued bake; priorities; DeleteScene while a bake uses it.
#include <gtest/gtest.h>
#include <sys/mount.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <thread>

#include "daemon_harness.h"
#include "output/exr.h"

namespace luxel::test {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

std::string record_on_disk(const Daemon& d, const std::string& bake_id) {
  return read_file(d.data_dir() + "/bakes/" + bake_id + "/record.json");
}

bool has_note(const v1::BakeInfo& info, const std::string& text) {
  for (const auto& n : info.notes())
    if (n.find(text) != std::string::npos) return true;
  return false;
}

output::Image download_exr(const Daemon& d, const std::string& bake_id,
                           const std::string& scratch) {
  std::string bytes, sha;
  uint64_t total = 0;
  auto st = download(d, bake_id, "irradiance.exr", &bytes, &sha, &total);
  EXPECT_TRUE(st.ok()) << st.error_message();
  EXPECT_EQ(sha, sha256_hex(bytes));
  std::ofstream(scratch, std::ios::binary) << bytes;
  auto image = output::read_exr(scratch);
  EXPECT_TRUE(image.is_ok()) << image.status().to_string();
  return image.is_ok() ? image.value() : output::Image{};
}

TEST(ServiceRestart, KillDashNineMidBakeResumesFromCheckpoint) {
  TempDir dir;
  const std::string data = dir.path() + "/data";
  const std::vector<std::string> flags = {"--checkpoint-interval", "0.3", "--max-concurrent-bakes",
                                          "2"};
  auto daemon = std::make_unique<Daemon>(data, flags);
  const std::string scene_id = upload_cornell(*daemon);
  // Two identical bakes run side by side; both get killed after a checkpoint.
  v1::BakeSettings s = small_settings(400);
  s.set_snapshot_format(v1::SNAPSHOT_FORMAT_NONE);
  const v1::BakeInfo a = submit_bake(*daemon, scene_id, s);
  const v1::BakeInfo b = submit_bake(*daemon, scene_id, s);
  const std::string ckpt_a = data + "/bakes/" + a.bake_id() + "/checkpoint.bin";
  const std::string ckpt_b = data + "/bakes/" + b.bake_id() + "/checkpoint.bin";
  // An upload in flight when the daemon dies: half of a .glb sent.
  const std::string glb = read_file(LUXEL_SCENES_DIR "/foliage_instanced.glb");
  auto upload_stub = daemon->stub();
  auto upload_ctx = daemon->context();
  v1::SceneInfo never;
  auto upload = upload_stub->UploadScene(upload_ctx.get(), &never);
  v1::UploadSceneRequest req;
  req.mutable_header()->set_name("foliage_instanced.glb");
  req.mutable_header()->set_format(v1::SCENE_FORMAT_GLB);
  req.mutable_header()->set_total_size(glb.size());
  req.mutable_header()->set_sha256(sha256_hex(glb));
  ASSERT_TRUE(upload->Write(req));
  req.set_chunk(glb.substr(0, glb.size() / 2));
  ASSERT_TRUE(upload->Write(req));

  const auto deadline = std::chrono::steady_clock::now() + 30s;
  while (!(fs::exists(ckpt_a) && fs::exists(ckpt_b) && !fs::is_empty(data + "/staging")) &&
         std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(20ms);
  ASSERT_FALSE(fs::is_empty(data + "/staging")) << "the upload should be in its staging folder";
  ASSERT_TRUE(fs::exists(ckpt_a) && fs::exists(ckpt_b)) << daemon->log();
  EXPECT_EQ(daemon->stop(SIGKILL), 128 + SIGKILL);
  ASSERT_NE(record_on_disk(*daemon, a.bake_id()).find("BAKE_STATE_RUNNING"), std::string::npos)
      << "the bakes should have been killed while running; make them longer";
  // A half-written checkpoint for b (as if the disk lost its tail): b must
  // restart from zero and say so.
  const std::string torn = read_file(ckpt_b);
  std::ofstream(ckpt_b, std::ios::binary | std::ios::trunc) << torn.substr(0, torn.size() / 2);
  upload->WritesDone();
  EXPECT_FALSE(upload->Finish().ok());

  // The partial upload left nothing behind.
  daemon = std::make_unique<Daemon>(data, flags);
  EXPECT_TRUE(fs::is_empty(data + "/staging"));
  EXPECT_FALSE(fs::exists(data + "/scenes/" + sha256_hex(glb)));
  EXPECT_NE(daemon->log().find("event=staging_removed"), std::string::npos);
  const v1::BakeInfo ra = wait_for_bake(*daemon, a.bake_id(), is_finished);
  const v1::BakeInfo rb = wait_for_bake(*daemon, b.bake_id(), is_finished);
  ASSERT_EQ(ra.state(), v1::BAKE_STATE_SUCCEEDED) << ra.error_message() << daemon->log();
  ASSERT_EQ(rb.state(), v1::BAKE_STATE_SUCCEEDED) << rb.error_message();
  EXPECT_EQ(ra.resumed(), 1u);
  EXPECT_TRUE(has_note(ra, "resumed from checkpoint")) << ra.DebugString();
  EXPECT_TRUE(has_note(ra, "interrupted")) << ra.DebugString();
  EXPECT_EQ(rb.resumed(), 0u);
  EXPECT_TRUE(has_note(rb, "checkpoint unreadable")) << rb.DebugString();
  EXPECT_EQ(ra.progress().paths(), rb.progress().paths());
  // The checkpoint goes right after the record says SUCCEEDED.
  for (int i = 0; i < 100 && fs::exists(ckpt_a); ++i) std::this_thread::sleep_for(10ms);
  EXPECT_FALSE(fs::exists(ckpt_a)) << "checkpoint kept after success";
  const std::string log = daemon->log();
  EXPECT_NE(log.find("event=bake_interrupted bake=" + a.bake_id()), std::string::npos) << log;
  EXPECT_NE(log.find("event=bake_requeued bake=" + a.bake_id()), std::string::npos);

  // Resumed and from-zero bakes of the same settings agree bit for bit.
  const output::Image ia = download_exr(*daemon, a.bake_id(), dir.path() + "/a.exr");
  const output::Image ib = download_exr(*daemon, b.bake_id(), dir.path() + "/b.exr");
  ASSERT_EQ(ia.pixels.size(), ib.pixels.size());
  ASSERT_FALSE(ia.pixels.empty());
  EXPECT_TRUE(ia.pixels == ib.pixels) << "resume changed the lightmap";
  EXPECT_EQ(daemon->stop(SIGTERM), 0);
}

TEST(ServiceRestart, SigtermCheckpointsAndTheNextStartFinishes) {
  TempDir dir;
  const std::string data = dir.path() + "/data";
  // Checkpoints every 60 s: the only checkpoint is the one SIGTERM asks for.
  const std::vector<std::string> flags = {"--checkpoint-interval", "60"};
  auto daemon = std::make_unique<Daemon>(data, flags);
  const std::string scene_id = upload_cornell(*daemon);
  v1::BakeSettings s = small_settings(600);
  s.set_snapshot_format(v1::SNAPSHOT_FORMAT_EXR);
  const v1::BakeInfo bake = submit_bake(*daemon, scene_id, s);

  // An EXR snapshot reaches a watcher and decodes.
  {
    v1::WatchBakeRequest w;
    w.set_bake_id(bake.bake_id());
    auto ctx = daemon->context();
    auto reader = daemon->stub()->WatchBake(ctx.get(), w);
    v1::BakeEvent ev;
    bool got = false;
    while (!got && reader->Read(&ev)) got = ev.has_snapshot();
    ASSERT_TRUE(got);
    EXPECT_EQ(ev.snapshot().format(), v1::SNAPSHOT_FORMAT_EXR);
    const std::string path = dir.path() + "/snap.exr";
    std::ofstream(path, std::ios::binary) << ev.snapshot().data();
    auto image = output::read_exr(path);
    ASSERT_TRUE(image.is_ok()) << image.status().to_string();
    EXPECT_EQ(image->width, 64);
    ctx->TryCancel();  // a watcher leaving mid-stream
    reader->Finish();
  }
  EXPECT_EQ(daemon->stop(SIGTERM), 0) << daemon->log();
  const std::string record = record_on_disk(*daemon, bake.bake_id());
  ASSERT_NE(record.find("BAKE_STATE_INTERRUPTED"), std::string::npos) << record;
  EXPECT_TRUE(fs::exists(data + "/bakes/" + bake.bake_id() + "/checkpoint.bin"));
  EXPECT_NE(daemon->log().find("event=checkpoint_written bake=" + bake.bake_id()),
            std::string::npos);

  daemon = std::make_unique<Daemon>(data, flags);
  const v1::BakeInfo done = wait_for_bake(*daemon, bake.bake_id(), is_finished);
  EXPECT_EQ(done.state(), v1::BAKE_STATE_SUCCEEDED) << done.error_message();
  EXPECT_EQ(done.resumed(), 1u);
  EXPECT_GE(done.progress().mean_spp(), 600.0);  // samples_per_texel is the mean
  EXPECT_EQ(daemon->stop(SIGTERM), 0);
}

TEST(ServiceRestart, CancelPrioritiesAndSceneInUse) {
  TempDir dir;
  Daemon daemon(dir.path() + "/data", {"--max-queued", "2"});
  const std::string scene_id = upload_cornell(daemon);
  auto stub = daemon.stub();

  v1::BakeSettings long_bake = small_settings(0);
  long_bake.set_time_budget_s(120);
  const v1::BakeInfo running = submit_bake(daemon, scene_id, long_bake);
  wait_for_bake(daemon, running.bake_id(),
                [](const v1::BakeInfo& i) { return i.state() == v1::BAKE_STATE_RUNNING; });

  v1::BakeSettings low = small_settings(16, 32), high = small_settings(16, 32);
  low.set_priority(0);
  high.set_priority(5);
  const v1::BakeInfo first_low = submit_bake(daemon, scene_id, low);
  const v1::BakeInfo later_high = submit_bake(daemon, scene_id, high);
  EXPECT_EQ(later_high.state(), v1::BAKE_STATE_QUEUED);

  // The queue holds two: a third is refused, naming the limit.
  {
    v1::SubmitBakeRequest req;
    req.set_scene_id(scene_id);
    *req.mutable_settings() = low;
    v1::BakeInfo info;
    auto ctx = daemon.context();
    auto st = stub->SubmitBake(ctx.get(), req, &info);
    EXPECT_EQ(st.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
    EXPECT_NE(st.error_message().find("--max-queued=2"), std::string::npos) << st.error_message();
  }
  // The scene cannot go while bakes use it.
  {
    v1::DeleteSceneRequest req;
    req.set_scene_id(scene_id);
    v1::DeleteSceneResponse resp;
    auto ctx = daemon.context();
    auto st = stub->DeleteScene(ctx.get(), req, &resp);
    EXPECT_EQ(st.error_code(), grpc::StatusCode::FAILED_PRECONDITION) << st.error_message();
  }
  // Cancelling the running bake lets the queued ones run, high priority first.
  v1::CancelBakeRequest cancel;
  cancel.set_bake_id(running.bake_id());
  v1::BakeInfo cancelled;
  auto ctx = daemon.context();
  ASSERT_TRUE(stub->CancelBake(ctx.get(), cancel, &cancelled).ok());
  // The call returns at once; the bake ends CANCELLED at its next poll.
  EXPECT_TRUE(cancelled.cancel_requested() || cancelled.state() == v1::BAKE_STATE_CANCELLED);
  cancelled = wait_for_bake(daemon, running.bake_id(), is_finished);
  EXPECT_EQ(cancelled.state(), v1::BAKE_STATE_CANCELLED);
  EXPECT_EQ(cancelled.termination(), "cancelled");
  const v1::BakeInfo h = wait_for_bake(daemon, later_high.bake_id(), is_finished);
  const v1::BakeInfo l = wait_for_bake(daemon, first_low.bake_id(), is_finished);
  ASSERT_EQ(h.state(), v1::BAKE_STATE_SUCCEEDED) << h.error_message();
  ASSERT_EQ(l.state(), v1::BAKE_STATE_SUCCEEDED) << l.error_message();
  EXPECT_LE(h.finished_at(), l.started_at()) << "priority 5 should run before priority 0";

  // A cancelled bake has no artifacts; cancelling again is a no-op.
  std::string bytes, sha;
  uint64_t total = 0;
  EXPECT_EQ(
      download(daemon, running.bake_id(), "irradiance.exr", &bytes, &sha, &total).error_code(),
      grpc::StatusCode::FAILED_PRECONDITION);
  ctx = daemon.context();
  ASSERT_TRUE(stub->CancelBake(ctx.get(), cancel, &cancelled).ok());
  EXPECT_EQ(cancelled.state(), v1::BAKE_STATE_CANCELLED);

  // A queued bake cancels at once.
  const v1::BakeInfo blocker = submit_bake(daemon, scene_id, long_bake);
  const v1::BakeInfo queued = submit_bake(daemon, scene_id, low);
  cancel.set_bake_id(queued.bake_id());
  ctx = daemon.context();
  ASSERT_TRUE(stub->CancelBake(ctx.get(), cancel, &cancelled).ok());
  EXPECT_EQ(cancelled.state(), v1::BAKE_STATE_CANCELLED);
  cancel.set_bake_id(blocker.bake_id());
  ctx = daemon.context();
  ASSERT_TRUE(stub->CancelBake(ctx.get(), cancel, &cancelled).ok());
  // A running bake uses its scene until it has stopped (CancelBake returns
  // before that).
  EXPECT_EQ(wait_for_bake(daemon, blocker.bake_id(), is_finished).state(),
            v1::BAKE_STATE_CANCELLED);

  // Now nothing uses the scene.
  v1::DeleteSceneRequest del;
  del.set_scene_id(scene_id);
  v1::DeleteSceneResponse resp;
  ctx = daemon.context();
  auto st = stub->DeleteScene(ctx.get(), del, &resp);
  EXPECT_TRUE(st.ok()) << st.error_message();
  v1::GetSceneRequest get;
  get.set_scene_id(scene_id);
  v1::SceneInfo info;
  ctx = daemon.context();
  EXPECT_EQ(stub->GetScene(ctx.get(), get, &info).error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_FALSE(fs::exists(daemon.data_dir() + "/scenes/" + scene_id));
}

// Disk full while the results are written: the bake must end FAILED on
// disk, not only in memory (the record stayed RUNNING and the bake resumed
// after a restart), with the cause logged and results.partial removed. The
// data dir is a 3 MiB tmpfs (needs the right to mount; skipped without it).
TEST(ServiceRestart, DiskFullWhileWritingResultsFailsDurably) {
  TempDir dir;
  const std::string small = dir.path() + "/small";
  fs::create_directories(small);
  if (mount("tmpfs", small.c_str(), "tmpfs", 0, "size=3m") != 0)
    GTEST_SKIP() << "cannot mount a tmpfs here (" << std::strerror(errno) << ")";
  struct Unmount {
    std::string path;
    ~Unmount() { umount2(path.c_str(), MNT_DETACH); }
  } unmount{small};
  const std::string data = small + "/data";
  std::string bake_id;
  {
    Daemon d(data, {"--checkpoint-interval", "0", "--max-resolution", "2048"});
    const std::string scene = upload_cornell(d);
    // A 2048^2 lightmap's EXRs (~40 MiB) cannot fit the 3 MiB disk.
    v1::BakeSettings s;
    s.set_resolution(2048);
    s.set_samples_per_texel(1);
    s.set_max_bounces(0);
    s.set_snapshot_format(v1::SNAPSHOT_FORMAT_NONE);
    bake_id = submit_bake(d, scene, s).bake_id();
    const v1::BakeInfo done = wait_for_bake(d, bake_id, is_finished, 120s);
    ASSERT_EQ(done.state(), v1::BAKE_STATE_FAILED) << done.error_message();
    const std::string record = record_on_disk(d, bake_id);
    EXPECT_NE(record.find("BAKE_STATE_FAILED"), std::string::npos) << record;
    EXPECT_FALSE(fs::exists(data + "/bakes/" + bake_id + "/results.partial"));
    EXPECT_NE(d.log().find("event=bake_failed bake=" + bake_id), std::string::npos) << d.log();
    EXPECT_EQ(d.stop(SIGTERM), 0) << d.log();
  }
  // After a restart it stays FAILED: not resumed, not re-run.
  Daemon again(data, {"--checkpoint-interval", "0", "--max-resolution", "2048"});
  v1::GetBakeRequest get;
  get.set_bake_id(bake_id);
  v1::BakeInfo info;
  auto ctx = again.context();
  ASSERT_TRUE(again.stub()->GetBake(ctx.get(), get, &info).ok());
  EXPECT_EQ(info.state(), v1::BAKE_STATE_FAILED);
  EXPECT_EQ(info.resumed(), 0u);
  EXPECT_EQ(again.stop(SIGTERM), 0) << again.log();
}

}  // namespace
}  // namespace luxel::test
