// End to end through the real daemon: upload (a .gltf with its external
// buffer, a .glb), content addressing, submit, watch (current state first,
// snapshots, final event), download and verify every artifact, idempotency,
// server counters and structured logs.
// Over 500 lines: one daemon serves the whole flow (upload, submit, watch,
// download, idempotency, counters, logs), checked in order.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <thread>

#include "daemon_harness.h"
#include "output/exr.h"
#include "shards/checkpoint.h"

namespace luxel::test {
namespace {

namespace fs = std::filesystem;

const std::string kToken = "e2e-token";

// The scene id rule of luxel.proto, computed here independently of the
// daemon: the main file's sha256 without resources, else the sha256 of a
// manifest of the main hash and each resource (sorted by uri).
std::string expected_scene_id(const std::string& main_bytes, std::vector<Resource> resources) {
  if (resources.empty()) return sha256_hex(main_bytes);
  std::sort(resources.begin(), resources.end(),
            [](const Resource& a, const Resource& b) { return a.uri < b.uri; });
  std::string manifest = "luxel-scene-v1\n" + sha256_hex(main_bytes) + "\n";
  for (const Resource& r : resources)
    manifest += r.uri + "\t" + std::to_string(r.bytes.size()) + "\t" + sha256_hex(r.bytes) + "\n";
  return sha256_hex(manifest);
}

class ServiceE2E : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir();
    daemon_ = new Daemon(dir_->path() + "/data", {"--max-upload-bytes", "4000000"}, kToken);
  }
  static void TearDownTestSuite() {
    EXPECT_EQ(daemon_->stop(SIGTERM), 0) << daemon_->log();
    delete daemon_;
    delete dir_;
  }
  static std::string upload_cornell(v1::SceneInfo* info) {
    const std::string gltf = read_file(LUXEL_SCENES_DIR "/cornell_box.gltf");
    const std::string bin = read_file(LUXEL_SCENES_DIR "/cornell_box.bin");
    auto st = upload_scene(*daemon_, "cornell_box.gltf", v1::SCENE_FORMAT_GLTF, gltf,
                           {{"cornell_box.bin", bin}}, info);
    EXPECT_TRUE(st.ok()) << st.error_message();
    return info->scene_id();
  }
  static TempDir* dir_;
  static Daemon* daemon_;
};
TempDir* ServiceE2E::dir_ = nullptr;
Daemon* ServiceE2E::daemon_ = nullptr;

TEST_F(ServiceE2E, UploadStoresContentAddressedSceneOnce) {
  v1::SceneInfo first, second;
  const std::string id = upload_cornell(&first);
  EXPECT_EQ(
      id, expected_scene_id(read_file(LUXEL_SCENES_DIR "/cornell_box.gltf"),
                            {{"cornell_box.bin", read_file(LUXEL_SCENES_DIR "/cornell_box.bin")}}));
  EXPECT_GT(first.statistics().triangles(), 0u);
  EXPECT_GT(first.statistics().emissive_triangles(), 0u);
  EXPECT_EQ(first.size(), fs::file_size(LUXEL_SCENES_DIR "/cornell_box.gltf") +
                              fs::file_size(LUXEL_SCENES_DIR "/cornell_box.bin"));
  upload_cornell(&second);
  EXPECT_TRUE(second.already_stored());
  EXPECT_EQ(second.scene_id(), id);
  EXPECT_EQ(second.uploaded_at(), first.uploaded_at());

  // One folder per scene; the resource sits beside the main file.
  const std::string scenes = daemon_->data_dir() + "/scenes";
  size_t n = 0;
  for (const auto& e : fs::directory_iterator(scenes)) {
    (void)e;
    ++n;
  }
  EXPECT_GE(n, 1u);
  EXPECT_TRUE(fs::exists(scenes + "/" + id + "/cornell_box.bin"));
  EXPECT_TRUE(fs::is_empty(daemon_->data_dir() + "/staging"));

  auto stub = daemon_->stub();
  v1::GetSceneRequest get;
  get.set_scene_id(id);
  v1::SceneInfo got;
  auto ctx = daemon_->context();
  ASSERT_TRUE(stub->GetScene(ctx.get(), get, &got).ok());
  EXPECT_EQ(got.name(), "cornell_box.gltf");
  v1::ListScenesResponse list;
  ctx = daemon_->context();
  ASSERT_TRUE(stub->ListScenes(ctx.get(), {}, &list).ok());
  bool listed = false;
  for (const auto& s : list.scenes()) listed |= s.scene_id() == id;
  EXPECT_TRUE(listed);
}

// The same .gltf with a different external buffer is different content: it
// must get its own id and be stored, not answered already_stored with the
// old buffer kept.
TEST_F(ServiceE2E, ChangedExternalBufferIsANewScene) {
  const std::string gltf = read_file(LUXEL_SCENES_DIR "/cornell_box.gltf");
  const std::string bin = read_file(LUXEL_SCENES_DIR "/cornell_box.bin");
  // Accessor 0 (POSITION of the first primitive) starts at byte 0 with a
  // 40-byte stride: nudge vertex 0's y toward the middle of its [0, 5.488]
  // range, so the buffer stays a valid scene within the accessor's min/max.
  std::string changed = bin;
  float y = 0;
  std::memcpy(&y, changed.data() + 4, sizeof y);
  y = 0.99f * y + 0.01f * 2.744f;
  std::memcpy(changed.data() + 4, &y, sizeof y);
  ASSERT_NE(changed, bin);

  v1::SceneInfo original, modified;
  const std::string original_id = upload_cornell(&original);
  auto st = upload_scene(*daemon_, "cornell_box.gltf", v1::SCENE_FORMAT_GLTF, gltf,
                         {{"cornell_box.bin", changed}}, &modified);
  ASSERT_TRUE(st.ok()) << st.error_message();
  EXPECT_NE(modified.scene_id(), original_id);
  EXPECT_EQ(modified.scene_id(), expected_scene_id(gltf, {{"cornell_box.bin", changed}}));
  EXPECT_FALSE(modified.already_stored());
  EXPECT_EQ(modified.statistics().triangles(), original.statistics().triangles());

  // Both are stored, each with its own buffer.
  const std::string scenes = daemon_->data_dir() + "/scenes/";
  EXPECT_EQ(read_file(scenes + original_id + "/cornell_box.bin"), bin);
  EXPECT_EQ(read_file(scenes + modified.scene_id() + "/cornell_box.bin"), changed);
  v1::ListScenesResponse list;
  auto ctx = daemon_->context();
  ASSERT_TRUE(daemon_->stub()->ListScenes(ctx.get(), {}, &list).ok());
  int listed = 0;
  for (const auto& s : list.scenes())
    listed += s.scene_id() == original_id || s.scene_id() == modified.scene_id();
  EXPECT_EQ(listed, 2);

  // Uploading the changed content again is the known scene.
  v1::SceneInfo again;
  st = upload_scene(*daemon_, "cornell_box.gltf", v1::SCENE_FORMAT_GLTF, gltf,
                    {{"cornell_box.bin", changed}}, &again);
  ASSERT_TRUE(st.ok()) << st.error_message();
  EXPECT_TRUE(again.already_stored());
  EXPECT_EQ(again.scene_id(), modified.scene_id());
}

TEST_F(ServiceE2E, UploadsGlb) {
  const std::string glb = read_file(LUXEL_SCENES_DIR "/foliage_instanced.glb");
  v1::SceneInfo info;
  auto st = upload_scene(*daemon_, "foliage_instanced.glb", v1::SCENE_FORMAT_GLB, glb, {}, &info,
                         {.chunk_bytes = 10000});
  ASSERT_TRUE(st.ok()) << st.error_message();
  EXPECT_EQ(info.scene_id(), sha256_hex(glb));
  EXPECT_GT(info.statistics().instances(), 1u);
}

TEST_F(ServiceE2E, BakeWatchDownloadVerify) {
  v1::SceneInfo scene;
  const std::string scene_id = upload_cornell(&scene);
  auto stub = daemon_->stub();
  v1::SubmitBakeRequest submit;
  submit.set_scene_id(scene_id);
  *submit.mutable_settings() = small_settings(256);
  submit.mutable_settings()->set_denoise(v1::DENOISE_ATROUS);  // irradiance_denoised.exr
  submit.mutable_settings()->set_denoise_snapshots(true);      // previews through the denoiser
  v1::BakeInfo bake;
  auto ctx = daemon_->context();
  ASSERT_TRUE(stub->SubmitBake(ctx.get(), submit, &bake).ok());
  ASSERT_EQ(bake.bake_id().size(), 32u);

  // Watch from the start: the first event is the current state.
  v1::WatchBakeRequest watch;
  watch.set_bake_id(bake.bake_id());
  auto wctx = daemon_->context(std::chrono::seconds(60));
  auto reader = stub->WatchBake(wctx.get(), watch);
  v1::BakeEvent event;
  ASSERT_TRUE(reader->Read(&event));
  EXPECT_TRUE(event.info().state() == v1::BAKE_STATE_QUEUED ||
              event.info().state() == v1::BAKE_STATE_RUNNING)
      << v1::BakeState_Name(event.info().state());
  EXPECT_FALSE(event.final());
  int snapshots = 0, events = 1;
  bool saw_final = false;
  double last_paths = 0;
  while (reader->Read(&event)) {
    ++events;
    ASSERT_FALSE(saw_final) << "event after the final one";
    EXPECT_GE(double(event.info().progress().paths()), last_paths);  // progress never goes back
    last_paths = double(event.info().progress().paths());
    if (event.has_snapshot()) {
      ++snapshots;
      const auto& s = event.snapshot();
      EXPECT_EQ(s.format(), v1::SNAPSHOT_FORMAT_PNG);
      ASSERT_GE(s.data().size(), 8u);
      EXPECT_EQ(s.data().substr(1, 3), "PNG");
      EXPECT_LE(std::max(s.width(), s.height()), 32u);
      EXPECT_GT(s.progress().paths(), 0u);
      EXPECT_TRUE(s.denoised());
    }
    saw_final = event.final();
  }
  ASSERT_TRUE(reader->Finish().ok());
  ASSERT_TRUE(saw_final);
  EXPECT_EQ(event.info().state(), v1::BAKE_STATE_SUCCEEDED) << event.info().error_message();
  EXPECT_GE(snapshots, 1) << events << " events";
  EXPECT_EQ(event.info().termination(), "samples");
  // samples_per_texel is the mean; adaptive sampling (default on) keeps
  // every texel at adaptive_min_samples or more.
  EXPECT_GE(event.info().progress().mean_spp(), 256.0);
  EXPECT_GE(event.info().progress().min_spp(), 8u);
  EXPECT_FALSE(event.info().features().empty());
  EXPECT_GT(event.info().finished_at(), event.info().started_at());

  // Every artifact downloads with a matching checksum; the EXR reads back.
  // (irradiance_denoised.exr: denoise is atrous here.)
  ASSERT_EQ(event.info().artifacts_size(), 7);
  for (const auto& artifact : event.info().artifacts()) {
    std::string bytes, sha;
    uint64_t total = 0;
    auto st = download(*daemon_, bake.bake_id(), artifact, &bytes, &sha, &total);
    ASSERT_TRUE(st.ok()) << artifact << ": " << st.error_message();
    EXPECT_EQ(total, bytes.size()) << artifact;
    EXPECT_EQ(sha, sha256_hex(bytes)) << artifact;
    EXPECT_GT(bytes.size(), 0u) << artifact;
    if (artifact == "irradiance.exr" || artifact == "irradiance_denoised.exr") {
      const std::string path = dir_->path() + "/downloaded.exr";
      std::ofstream(path, std::ios::binary) << bytes;
      auto image = output::read_exr(path);
      ASSERT_TRUE(image.is_ok()) << image.status().to_string();
      EXPECT_EQ(image->width, 64);
      EXPECT_EQ(image->channels, 4);
      double lit = 0;
      for (size_t i = 0; i < image->texel_count(); ++i) lit += image->pixels[i * 4 + 1];
      EXPECT_GT(lit, 0.0) << "the Cornell box lightmap is black";
    }
  }

  // A late watcher gets the final state at once.
  auto late_ctx = daemon_->context();
  auto late = stub->WatchBake(late_ctx.get(), watch);
  ASSERT_TRUE(late->Read(&event));
  EXPECT_TRUE(event.final());
  EXPECT_EQ(event.info().state(), v1::BAKE_STATE_SUCCEEDED);
  EXPECT_FALSE(late->Read(&event));
  EXPECT_TRUE(late->Finish().ok());

  // Counters and logs.
  v1::ServerStatus status;
  ctx = daemon_->context();
  ASSERT_TRUE(stub->GetServerStatus(ctx.get(), {}, &status).ok());
  EXPECT_GE(status.paths_traced(), event.info().progress().paths());
  EXPECT_GT(status.upload_bytes(), 0u);
  EXPECT_GE(status.bakes_by_state().at("BAKE_STATE_SUCCEEDED"), 1u);
  EXPECT_GE(status.scenes(), 1u);
  EXPECT_EQ(status.max_concurrent_bakes(), 1u);
  const std::string log = daemon_->log();
  EXPECT_NE(log.find("event=bake_started bake=" + bake.bake_id() + " scene=" + scene_id),
            std::string::npos)
      << log;
  EXPECT_NE(log.find("event=bake_finished bake=" + bake.bake_id()), std::string::npos);
}

TEST_F(ServiceE2E, StalledWatcherNeitherBlocksTheBakeNorGetsABacklog) {
  v1::SceneInfo scene;
  const std::string scene_id = upload_cornell(&scene);
  auto stub = daemon_->stub();
  v1::SubmitBakeRequest submit;
  submit.set_scene_id(scene_id);
  *submit.mutable_settings() = small_settings(256);
  submit.mutable_settings()->set_snapshot_format(v1::SNAPSHOT_FORMAT_EXR);  // ~40 KB per event
  submit.mutable_settings()->set_snapshot_interval_s(0.05);
  v1::BakeInfo bake;
  auto ctx = daemon_->context();
  ASSERT_TRUE(stub->SubmitBake(ctx.get(), submit, &bake).ok());
  v1::WatchBakeRequest watch;
  watch.set_bake_id(bake.bake_id());
  auto wctx = daemon_->context(std::chrono::seconds(60));
  auto reader = stub->WatchBake(wctx.get(), watch);
  v1::BakeEvent event;
  ASSERT_TRUE(reader->Read(&event));
  // Stop reading: the bake must still finish.
  const v1::BakeInfo done =
      wait_for_bake(*daemon_, bake.bake_id(), is_finished, std::chrono::seconds(30));
  ASSERT_EQ(done.state(), v1::BAKE_STATE_SUCCEEDED) << done.error_message();
  // Reading again: newest state only, snapshots in order, then the final event.
  uint64_t last_snapshot_paths = 0;
  int events = 0;
  while (reader->Read(&event)) {
    ++events;
    if (event.has_snapshot()) {
      EXPECT_GT(event.snapshot().progress().paths(), last_snapshot_paths);
      last_snapshot_paths = event.snapshot().progress().paths();
    }
  }
  EXPECT_TRUE(reader->Finish().ok());
  EXPECT_TRUE(event.final());
  EXPECT_EQ(event.info().state(), v1::BAKE_STATE_SUCCEEDED);
  EXPECT_GE(events, 1);
}

TEST_F(ServiceE2E, DirectionalEncodingsAreArtifacts) {
  v1::SceneInfo scene;
  const std::string scene_id = upload_cornell(&scene);
  auto stub = daemon_->stub();
  v1::SubmitBakeRequest submit;
  submit.set_scene_id(scene_id);
  *submit.mutable_settings() = small_settings(16, 32);
  for (auto e : {v1::ENCODING_IRRADIANCE, v1::ENCODING_SH2, v1::ENCODING_AMBIENT_DICE9})
    submit.mutable_settings()->add_encodings(e);
  v1::BakeInfo bake;
  auto ctx = daemon_->context();
  ASSERT_TRUE(stub->SubmitBake(ctx.get(), submit, &bake).ok());
  const v1::BakeInfo done =
      wait_for_bake(*daemon_, bake.bake_id(), is_finished, std::chrono::seconds(60));
  ASSERT_EQ(done.state(), v1::BAKE_STATE_SUCCEEDED) << done.error_message();
  EXPECT_NE(done.features().find("basis"), std::string::npos) << done.features();
  const std::vector<std::string> names(done.artifacts().begin(), done.artifacts().end());
  for (const char* want : {"sh2.exr", "ambient-dice9.exr"})
    EXPECT_NE(std::find(names.begin(), names.end(), want), names.end()) << want;
  std::string bytes, sha;
  uint64_t total = 0;
  ASSERT_TRUE(download(*daemon_, bake.bake_id(), "sh2.exr", &bytes, &sha, &total).ok());
  EXPECT_EQ(sha, sha256_hex(bytes));
  const std::string path = dir_->path() + "/sh2.exr";
  std::ofstream(path, std::ios::binary) << bytes;
  output::ExrInfo exr;
  auto image = output::read_exr(path, &exr);
  ASSERT_TRUE(image.is_ok()) << image.status().to_string();
  EXPECT_EQ(image->channels, 27);  // 9 coefficients x RGB
  EXPECT_EQ(exr.metadata["luxel/encoding"], "sh2");
  ASSERT_TRUE(download(*daemon_, bake.bake_id(), "manifest.json", &bytes, &sha, &total).ok());
  EXPECT_NE(bytes.find("\"encodings\""), std::string::npos);
  EXPECT_NE(bytes.find("ambient-dice9"), std::string::npos);
}

// A shard of a distributed bake: adaptive left unset is off, and the
// SUCCEEDED shard offers its accumulators (accumulators.bin, the checkpoint
// format) for the coordinator's merge (shards/shard_merge.h).
TEST_F(ServiceE2E, ShardBakeOffersItsAccumulators) {
  v1::SceneInfo scene;
  const std::string scene_id = upload_cornell(&scene);
  auto stub = daemon_->stub();
  v1::SubmitBakeRequest submit;
  submit.set_scene_id(scene_id);
  *submit.mutable_settings() = small_settings(40, 32);
  submit.mutable_settings()->set_shard_index(1);
  submit.mutable_settings()->set_shard_count(2);
  submit.mutable_settings()->add_encodings(v1::ENCODING_SH2);
  v1::BakeInfo bake;
  auto ctx = daemon_->context();
  ASSERT_TRUE(stub->SubmitBake(ctx.get(), submit, &bake).ok());
  const v1::BakeInfo done =
      wait_for_bake(*daemon_, bake.bake_id(), is_finished, std::chrono::seconds(60));
  ASSERT_EQ(done.state(), v1::BAKE_STATE_SUCCEEDED) << done.error_message();
  // 40 samples = blocks of 16, 16 and 8: shard 1 of 2 traces the second.
  EXPECT_EQ(done.progress().min_spp(), 16u);
  const std::vector<std::string> names(done.artifacts().begin(), done.artifacts().end());
  ASSERT_NE(std::find(names.begin(), names.end(), "accumulators.bin"), names.end());
  std::string bytes, sha;
  uint64_t total = 0;
  ASSERT_TRUE(download(*daemon_, bake.bake_id(), "accumulators.bin", &bytes, &sha, &total).ok());
  const std::string path = dir_->path() + "/accumulators.bin";
  std::ofstream(path, std::ios::binary) << bytes;
  auto state = pipeline::read_checkpoint(path);
  ASSERT_TRUE(state) << state.status().to_string();
  EXPECT_EQ(state->shard_index, 1u);
  EXPECT_EQ(state->shard_count, 2u);
  EXPECT_FALSE(state->fingerprint.empty());
  EXPECT_EQ(state->basis_layout.size(), 1u);
  for (uint32_t n : state->spp) ASSERT_EQ(n, 16u);
  // adaptive = true is refused for a shard, naming the field.
  submit.mutable_settings()->set_adaptive(true);
  v1::BakeInfo refused;
  auto ctx2 = daemon_->context();
  const grpc::Status st = stub->SubmitBake(ctx2.get(), submit, &refused);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(st.error_message().find("settings.adaptive"), std::string::npos) << st.error_message();
}

TEST_F(ServiceE2E, ReferenceBakeGivesTrueErrorInProgress) {
  v1::SceneInfo scene;
  const std::string scene_id = upload_cornell(&scene);
  auto stub = daemon_->stub();
  auto submit = [&](const v1::BakeSettings& settings, v1::BakeInfo* out) {
    v1::SubmitBakeRequest req;
    req.set_scene_id(scene_id);
    *req.mutable_settings() = settings;
    auto ctx = daemon_->context();
    return stub->SubmitBake(ctx.get(), req, out);
  };
  v1::BakeInfo ref;
  ASSERT_TRUE(submit(small_settings(64, 32), &ref).ok());
  const v1::BakeInfo ref_done =
      wait_for_bake(*daemon_, ref.bake_id(), is_finished, std::chrono::seconds(60));
  ASSERT_EQ(ref_done.state(), v1::BAKE_STATE_SUCCEEDED) << ref_done.error_message();

  v1::BakeSettings settings = small_settings(16, 32);
  settings.set_seed(9);
  settings.set_reference_bake_id(ref.bake_id());
  v1::BakeInfo bake;
  ASSERT_TRUE(submit(settings, &bake).ok());
  const v1::BakeInfo done =
      wait_for_bake(*daemon_, bake.bake_id(), is_finished, std::chrono::seconds(60));
  ASSERT_EQ(done.state(), v1::BAKE_STATE_SUCCEEDED) << done.error_message();
  EXPECT_GT(done.progress().rmse(), 0.0);
  EXPECT_GT(done.progress().rel_mse(), 0.0);
  std::string bytes, sha;
  uint64_t total = 0;
  ASSERT_TRUE(download(*daemon_, bake.bake_id(), "error_series.csv", &bytes, &sha, &total).ok());
  EXPECT_EQ(bytes.rfind("elapsed_s,paths,mean_spp,min_spp,rel_error,rmse,rel_mse\n", 0), 0u)
      << bytes;
  EXPECT_EQ(bytes.find(",,"), std::string::npos)
      << "every point carries rmse and rel_mse: " << bytes;

  // A reference of another size is refused at submit, naming the field
  // (its size read from the reference's stored EXR header).
  v1::BakeSettings other = small_settings(16, 64);
  other.set_reference_bake_id(ref.bake_id());
  const grpc::Status refused = submit(other, &bake);
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(refused.error_message().rfind("settings.reference_bake_id", 0), 0u)
      << refused.error_message();
}

TEST_F(ServiceE2E, IdempotencyKeyReturnsTheSameBake) {
  v1::SceneInfo scene;
  const std::string scene_id = upload_cornell(&scene);
  auto stub = daemon_->stub();
  v1::SubmitBakeRequest submit;
  submit.set_scene_id(scene_id);
  *submit.mutable_settings() = small_settings(16, 32);
  submit.set_idempotency_key("retry-me-" + dir_->path());
  v1::BakeInfo a, b;
  auto ctx = daemon_->context();
  ASSERT_TRUE(stub->SubmitBake(ctx.get(), submit, &a).ok());
  ctx = daemon_->context();
  ASSERT_TRUE(stub->SubmitBake(ctx.get(), submit, &b).ok());
  EXPECT_EQ(a.bake_id(), b.bake_id());
  EXPECT_EQ(b.idempotency_key(), submit.idempotency_key());
  v1::ListBakesRequest list_req;
  v1::ListBakesResponse list;
  ctx = daemon_->context();
  ASSERT_TRUE(stub->ListBakes(ctx.get(), list_req, &list).ok());
  int with_key = 0;
  for (const auto& x : list.bakes()) with_key += x.idempotency_key() == submit.idempotency_key();
  EXPECT_EQ(with_key, 1);
  // The same key with other settings is not a retry: FAILED_PRECONDITION,
  // not the first job.
  v1::SubmitBakeRequest other = submit;
  other.mutable_settings()->set_samples_per_texel(17);
  v1::BakeInfo c;
  ctx = daemon_->context();
  const grpc::Status st = stub->SubmitBake(ctx.get(), other, &c);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::FAILED_PRECONDITION) << st.error_message();
  EXPECT_NE(st.error_message().find("with other settings"), std::string::npos);
  EXPECT_TRUE(c.bake_id().empty());
  auto done = wait_for_bake(*daemon_, a.bake_id(), is_finished);
  EXPECT_EQ(done.state(), v1::BAKE_STATE_SUCCEEDED) << done.error_message();

  // Filter by state.
  list_req.add_states(v1::BAKE_STATE_SUCCEEDED);
  ctx = daemon_->context();
  list.Clear();
  ASSERT_TRUE(stub->ListBakes(ctx.get(), list_req, &list).ok());
  for (const auto& x : list.bakes()) EXPECT_EQ(x.state(), v1::BAKE_STATE_SUCCEEDED);
  EXPECT_GE(list.bakes_size(), 1);
}

// Four separate 2 x 2 quads without TEXCOORD_1 (each its own mesh and node).
std::string quads_glb() {
  GltfBuilder b;
  b.add_material({{"name", "grey"}, {"pbrMetallicRoughness", {{"metallicFactor", 0.0}}}});
  for (int i = 0; i < 4; ++i) {
    json prim = b.triangles({-1, 0, -1, 1, 0, -1, 1, 0, 1, -1, 0, 1}, {0, 2, 1, 0, 3, 2}, kUInt,
                            /*with_uv1=*/false);
    prim["material"] = 0;
    b.add_node({{"name", "quad" + std::to_string(i)},
                {"mesh", b.add_mesh("quad" + std::to_string(i), {prim})},
                {"translation", {3.0 * i, 0, 0}}});
  }
  return b.glb();
}

// A scene without lightmap UVs bakes through the daemon with generated UVs:
// the written-back scene is an artifact; past the daemon's --max-resolution
// the lightmap goes on pages, whose files are artifacts and whose
// snapshots arrive stacked with Snapshot.pages.
TEST(ServiceUv, GeneratedUvsAndPagesAreArtifacts) {
  TempDir dir;
  Daemon daemon(dir.path() + "/data", {"--max-resolution", "64"}, kToken);
  v1::SceneInfo scene;
  ASSERT_TRUE(
      upload_scene(daemon, "quads.glb", v1::SCENE_FORMAT_GLB, quads_glb(), {}, &scene).ok());
  auto stub = daemon.stub();
  struct Case {
    float density;
    int pages;
  };
  // 8 texels per unit: all four quads on one 64^2 page; 20: each quad's
  // 40 x 40 texels (with padding) takes more than half a page.
  for (const Case c : {Case{8, 1}, Case{20, 4}}) {
    v1::SubmitBakeRequest submit;
    submit.set_scene_id(scene.scene_id());
    // Enough samples that snapshots (every 0.1 s) come before the end.
    *submit.mutable_settings() = small_settings(512, 0);
    submit.mutable_settings()->set_texel_density(c.density);
    submit.mutable_settings()->set_denoise(v1::DENOISE_ATROUS);  // per-page denoised maps too
    submit.mutable_settings()->mutable_sky()->set_kind(v1::Sky::KIND_CONSTANT);
    v1::BakeInfo bake;
    auto ctx = daemon.context();
    ASSERT_TRUE(stub->SubmitBake(ctx.get(), submit, &bake).ok());
    v1::WatchBakeRequest watch;
    watch.set_bake_id(bake.bake_id());
    auto wctx = daemon.context(std::chrono::seconds(60));
    auto reader = stub->WatchBake(wctx.get(), watch);
    v1::BakeEvent event;
    uint32_t snapshot_pages = 0;
    while (reader->Read(&event))
      if (event.has_snapshot()) snapshot_pages = std::max(snapshot_pages, event.snapshot().pages());
    ASSERT_TRUE(reader->Finish().ok());
    ASSERT_EQ(event.info().state(), v1::BAKE_STATE_SUCCEEDED) << event.info().error_message();
    const std::vector<std::string> names(event.info().artifacts().begin(),
                                         event.info().artifacts().end());
    auto has = [&](const std::string& n) {
      return std::find(names.begin(), names.end(), n) != names.end();
    };
    EXPECT_TRUE(has("quads_lightmapped.glb")) << c.density;
    // Where the UVs came from, with timing and quality, on the bake's record.
    const std::string& layout = event.info().lightmap_layout();
    EXPECT_EQ(layout.rfind("generated (", 0), 0u) << layout;
    EXPECT_NE(layout.find("4 meshes in"), std::string::npos) << layout;
    EXPECT_EQ(layout.find(", 4 pages") != std::string::npos, c.pages > 1) << layout;
    EXPECT_NE(layout.find(" 0 overlapping texels"), std::string::npos) << layout;
    EXPECT_TRUE(has("manifest.json"));
    if (c.pages == 1) {
      EXPECT_TRUE(has("irradiance.exr"));
      EXPECT_FALSE(has("irradiance_0.exr"));
      EXPECT_LE(snapshot_pages, 1u);
    } else {
      for (int p = 0; p < c.pages; ++p)
        for (const char* stem :
             {"irradiance_", "irradiance_denoised_", "preview_", "samples_", "rel_error_"}) {
          const std::string ext = std::string(stem) == "preview_" ? ".png" : ".exr";
          EXPECT_TRUE(has(stem + std::to_string(p) + ext)) << stem << p;
        }
      EXPECT_FALSE(has("irradiance.exr"));
      EXPECT_FALSE(has("irradiance_" + std::to_string(c.pages) + ".exr"));
      EXPECT_EQ(snapshot_pages, static_cast<uint32_t>(c.pages));
    }
    std::string bytes, sha;
    uint64_t total = 0;
    ASSERT_TRUE(
        download(daemon, bake.bake_id(), "quads_lightmapped.glb", &bytes, &sha, &total).ok());
    EXPECT_EQ(bytes.substr(0, 4), "glTF");
    EXPECT_NE(bytes.find("TEXCOORD_1"), std::string::npos);
    EXPECT_NE(bytes.find("lightmapScaleOffset"), std::string::npos);
    EXPECT_EQ(bytes.find("lightmapIndex") != std::string::npos, c.pages > 1);
    ASSERT_TRUE(download(daemon, bake.bake_id(), "manifest.json", &bytes, &sha, &total).ok());
    const json manifest = json::parse(bytes);
    EXPECT_EQ(manifest.value("pages", 1), c.pages);
    EXPECT_EQ(manifest["uv_layout"]["pages"], c.pages);
    EXPECT_EQ(manifest["uv_layout"]["overlapping_texels"], 0);
    // Artifacts name the scene as uploaded, never by its path on the server.
    EXPECT_EQ(manifest["scene_name"], "quads.glb") << manifest.dump();
    for (const std::string& artifact : names) {
      ASSERT_TRUE(download(daemon, bake.bake_id(), artifact, &bytes, &sha, &total).ok());
      EXPECT_EQ(bytes.find(daemon.data_dir()), std::string::npos) << artifact;
    }
  }
  EXPECT_EQ(daemon.stop(SIGTERM), 0) << daemon.log();
}

}  // namespace
}  // namespace luxel::test
