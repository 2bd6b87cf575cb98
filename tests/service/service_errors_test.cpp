// Bad input, each with its own status, and nothing stored or lost: wrong
// hashes, truncated and oversize uploads, unknown ids, invalid settings, a
// glTF that fails validation, uris escaping the scene folder, a missing or
// wrong token, a scene in use.
#include <gtest/gtest.h>

#include <filesystem>
#include <thread>

#include "daemon_harness.h"

namespace luxel::test {
namespace {

namespace fs = std::filesystem;

const std::string kToken = "errors-token";

class ServiceErrors : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir();
    daemon_ = new Daemon(dir_->path() + "/data",
                         {"--max-upload-bytes", "200000", "--max-resolution", "256"}, kToken);
  }
  static void TearDownTestSuite() {
    EXPECT_EQ(daemon_->stop(SIGTERM), 0);
    delete daemon_;
    delete dir_;
  }
  void SetUp() override { stub_ = daemon_->stub(); }

  // The store holds no scene and no upload debris.
  static size_t stored_scenes() {
    size_t n = 0;
    for (const auto& e : fs::directory_iterator(daemon_->data_dir() + "/scenes")) {
      (void)e;
      ++n;
    }
    return n;
  }
  static bool staging_empty() { return fs::is_empty(daemon_->data_dir() + "/staging"); }

  grpc::Status submit(const v1::BakeSettings& settings, const std::string& scene_id,
                      v1::BakeInfo* out) {
    v1::SubmitBakeRequest req;
    req.set_scene_id(scene_id);
    *req.mutable_settings() = settings;
    auto ctx = daemon_->context();
    return stub_->SubmitBake(ctx.get(), req, out);
  }
  std::string cornell_id() {
    v1::SceneInfo info;
    auto st =
        upload_scene(*daemon_, "cornell_box.gltf", v1::SCENE_FORMAT_GLTF,
                     read_file(LUXEL_SCENES_DIR "/cornell_box.gltf"),
                     {{"cornell_box.bin", read_file(LUXEL_SCENES_DIR "/cornell_box.bin")}}, &info);
    EXPECT_TRUE(st.ok()) << st.error_message();
    return info.scene_id();
  }

  static TempDir* dir_;
  static Daemon* daemon_;
  std::unique_ptr<v1::Luxel::Stub> stub_;
};
TempDir* ServiceErrors::dir_ = nullptr;
Daemon* ServiceErrors::daemon_ = nullptr;

const std::string kGltf = read_file(LUXEL_SCENES_DIR "/cornell_box.gltf");
const std::string kBin = read_file(LUXEL_SCENES_DIR "/cornell_box.bin");

TEST_F(ServiceErrors, WrongHashIsDataLossAndStoresNothing) {
  const size_t before = stored_scenes();
  v1::SceneInfo info;
  auto st =
      upload_scene(*daemon_, "x.gltf", v1::SCENE_FORMAT_GLTF, kGltf, {{"cornell_box.bin", kBin}},
                   &info, {.sha256_override = std::string(64, 'a')});
  EXPECT_EQ(st.error_code(), grpc::StatusCode::DATA_LOSS) << st.error_message();
  EXPECT_NE(st.error_message().find("sha256 mismatch"), std::string::npos) << st.error_message();
  EXPECT_EQ(stored_scenes(), before);
  EXPECT_TRUE(staging_empty());
}

TEST_F(ServiceErrors, TruncatedStreamIsDataLossAndStoresNothing) {
  const size_t before = stored_scenes();
  v1::SceneInfo info;
  auto st = upload_scene(
      *daemon_, "x.gltf", v1::SCENE_FORMAT_GLTF, kGltf, {{"cornell_box.bin", kBin}}, &info,
      {.truncate_after = static_cast<long>(kGltf.size() + 100), .chunk_bytes = 1000});
  EXPECT_EQ(st.error_code(), grpc::StatusCode::DATA_LOSS) << st.error_message();
  EXPECT_NE(st.error_message().find("truncated"), std::string::npos) << st.error_message();
  // A declared size larger than what is sent is the same thing.
  st = upload_scene(*daemon_, "x.gltf", v1::SCENE_FORMAT_GLTF, kGltf, {}, &info,
                    {.size_override = kGltf.size() + 10});
  EXPECT_EQ(st.error_code(), grpc::StatusCode::DATA_LOSS) << st.error_message();
  EXPECT_EQ(stored_scenes(), before);
  EXPECT_TRUE(staging_empty());
}

TEST_F(ServiceErrors, OversizeUploadIsResourceExhaustedNamingTheLimit) {
  const std::string glb = read_file(LUXEL_SCENES_DIR "/foliage_instanced.glb");  // 177 KB
  v1::SceneInfo info;
  auto st = upload_scene(*daemon_, "big.glb", v1::SCENE_FORMAT_GLB, glb + glb, {}, &info);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << st.error_message();
  EXPECT_NE(st.error_message().find("--max-upload-bytes=200000"), std::string::npos)
      << st.error_message();
  EXPECT_TRUE(staging_empty());
}

TEST_F(ServiceErrors, GltfFailingValidationIsInvalidArgument) {
  const std::string bad = R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],
    "nodes":[{"name":"n","mesh":0}],
    "meshes":[{"name":"broken","primitives":[{"attributes":{"POSITION":7}}]}]})";
  v1::SceneInfo info;
  const size_t before = stored_scenes();
  auto st = upload_scene(*daemon_, "broken.gltf", v1::SCENE_FORMAT_GLTF, bad, {}, &info);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << st.error_message();
  EXPECT_NE(st.error_message().find("broken.gltf"), std::string::npos) << st.error_message();
  // The upload's own file name, not where the daemon staged it.
  EXPECT_NE(st.error_message().find(": 'broken.gltf': "), std::string::npos) << st.error_message();
  EXPECT_EQ(st.error_message().find(daemon_->data_dir()), std::string::npos) << st.error_message();
  EXPECT_EQ(st.error_message().find("staging"), std::string::npos) << st.error_message();
  // The main file without its buffer fails too: nothing is fetched from elsewhere.
  st = upload_scene(*daemon_, "nobuffer.gltf", v1::SCENE_FORMAT_GLTF, kGltf, {}, &info);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << st.error_message();
  EXPECT_EQ(stored_scenes(), before);
  EXPECT_TRUE(staging_empty());
}

TEST_F(ServiceErrors, ResourceUrisMayNotEscapeTheSceneFolder) {
  v1::SceneInfo info;
  for (const std::string uri :
       {"../evil.bin", "/etc/passwd", "a/../../b.bin", "file:///x", "a\\b"}) {
    auto st = upload_scene(*daemon_, "x.gltf", v1::SCENE_FORMAT_GLTF, kGltf, {{uri, kBin}}, &info);
    EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << uri;
    EXPECT_NE(st.error_message().find("header.resources.uri"), std::string::npos)
        << st.error_message();
  }
  EXPECT_FALSE(fs::exists(fs::path(daemon_->data_dir()).parent_path() / "evil.bin"));
  EXPECT_TRUE(staging_empty());
}

// "a" and "a/b" in one upload: a path cannot be a file and a folder (this
// was INTERNAL, from the failed file creation).
TEST_F(ServiceErrors, AResourcePathThatIsAnothersFolderIsInvalid) {
  v1::SceneInfo info;
  for (const auto& pair : {std::pair<std::string, std::string>{"a", "a/b"}, {"t/x/y", "t/x"}}) {
    auto st = upload_scene(*daemon_, "x.gltf", v1::SCENE_FORMAT_GLTF, kGltf,
                           {{pair.first, kBin}, {pair.second, kBin}}, &info);
    EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << st.error_message();
    EXPECT_NE(st.error_message().find("a path cannot be a file and a folder"), std::string::npos)
        << st.error_message();
  }
  EXPECT_TRUE(staging_empty());
}

// Scene names are one printable line of at most 256 bytes of UTF-8: a 15 MiB
// name once went into every log line and made ListScenes exceed a client's
// 4 MiB limit; NUL and CR split log lines. The log escapes what it prints.
TEST_F(ServiceErrors, SceneNamesAreBoundedAndPrintable) {
  v1::SceneInfo info;
  struct Case {
    std::string name, why;
  };
  const std::vector<Case> cases = {{std::string(257, 'n'), "257 bytes; at most 256"},
                                   {std::string("a\0b", 3), "control character 0x00"},
                                   {"a\rb", "control character 0x0d"},
                                   {"tab\tname", "control character 0x09"}};
  // (Invalid UTF-8 never gets this far: proto3 string fields refuse it when
  // the request is parsed.)
  for (const Case& c : cases) {
    auto st = upload_scene(*daemon_, c.name, v1::SCENE_FORMAT_GLTF, kGltf, {}, &info);
    EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << c.why;
    EXPECT_NE(st.error_message().find("header.name: " + c.why), std::string::npos)
        << st.error_message();
  }
  // At the limit, and non-ASCII, is fine.
  auto fine = upload_scene(*daemon_, std::string(254, 'n') + "\xc3\xa9", v1::SCENE_FORMAT_GLTF,
                           kGltf, {{"cornell_box.bin", kBin}}, &info);
  EXPECT_TRUE(fine.ok()) << fine.error_message();
  // Every log line is one event, whatever the refused names held.
  const std::string log = daemon_->log();
  size_t start = 0;
  while (start < log.size()) {
    const size_t end = log.find('\n', start);
    const std::string line = log.substr(start, end - start);
    EXPECT_TRUE(line.empty() || line.rfind("ts=", 0) == 0 || line[0] == 'E' || line[0] == 'I' ||
                line[0] == 'W')
        << "a log line that is not an event: " << line.substr(0, 80);
    EXPECT_EQ(line.find('\r'), std::string::npos);
    if (end == std::string::npos) break;
    start = end + 1;
  }
}

TEST_F(ServiceErrors, FirstMessageMustBeAHeader) {
  auto ctx = daemon_->context();
  v1::SceneInfo info;
  auto writer = stub_->UploadScene(ctx.get(), &info);
  v1::UploadSceneRequest chunk;
  chunk.set_chunk("hello");
  writer->Write(chunk);
  writer->WritesDone();
  auto st = writer->Finish();
  EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << st.error_message();
}

TEST_F(ServiceErrors, UnknownIdsAreNotFound) {
  const std::string scene(64, 'b'), bake(32, 'c');
  v1::SceneInfo info;
  v1::BakeInfo binfo;
  auto ctx = daemon_->context();
  v1::GetSceneRequest gs;
  gs.set_scene_id(scene);
  EXPECT_EQ(stub_->GetScene(ctx.get(), gs, &info).error_code(), grpc::StatusCode::NOT_FOUND);
  ctx = daemon_->context();
  v1::GetBakeRequest gb;
  gb.set_bake_id(bake);
  EXPECT_EQ(stub_->GetBake(ctx.get(), gb, &binfo).error_code(), grpc::StatusCode::NOT_FOUND);
  ctx = daemon_->context();
  gb.set_bake_id("../../etc");
  EXPECT_EQ(stub_->GetBake(ctx.get(), gb, &binfo).error_code(), grpc::StatusCode::NOT_FOUND);
  ctx = daemon_->context();
  v1::CancelBakeRequest cb;
  cb.set_bake_id(bake);
  EXPECT_EQ(stub_->CancelBake(ctx.get(), cb, &binfo).error_code(), grpc::StatusCode::NOT_FOUND);
  ctx = daemon_->context();
  v1::DeleteSceneRequest ds;
  ds.set_scene_id(scene);
  v1::DeleteSceneResponse dr;
  EXPECT_EQ(stub_->DeleteScene(ctx.get(), ds, &dr).error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_EQ(submit(small_settings(16), scene, &binfo).error_code(), grpc::StatusCode::NOT_FOUND);
  ctx = daemon_->context();
  v1::WatchBakeRequest wb;
  wb.set_bake_id(bake);
  auto reader = stub_->WatchBake(ctx.get(), wb);
  v1::BakeEvent ev;
  EXPECT_FALSE(reader->Read(&ev));
  EXPECT_EQ(reader->Finish().error_code(), grpc::StatusCode::NOT_FOUND);
  std::string bytes, sha;
  uint64_t total = 0;
  EXPECT_EQ(download(*daemon_, bake, "irradiance.exr", &bytes, &sha, &total).error_code(),
            grpc::StatusCode::NOT_FOUND);
}

TEST_F(ServiceErrors, InvalidSettingsNameTheField) {
  const std::string id = cornell_id();
  struct Case {
    const char* field;
    std::function<void(v1::BakeSettings&)> edit;
  };
  const std::vector<Case> cases = {
      {"settings.max_bounces", [](v1::BakeSettings& s) { s.set_max_bounces(99); }},
      {"settings.resolution",
       [](v1::BakeSettings& s) { s.set_resolution(1024); }},  // > --max-resolution
      {"settings.encodings",
       [](v1::BakeSettings& s) { s.add_encodings(static_cast<v1::Encoding>(99)); }},
      {"settings.encodings",
       [](v1::BakeSettings& s) {
         s.add_encodings(v1::ENCODING_SH2);
         s.add_encodings(v1::ENCODING_SH2);
       }},
      {"settings.reference_bake_id",
       [](v1::BakeSettings& s) { s.set_reference_bake_id(std::string(32, 'a')); }},
      // Malformed, by the same rule as unknown (was NOT_FOUND).
      {"settings.reference_bake_id", [](v1::BakeSettings& s) { s.set_reference_bake_id("zz"); }},
      {"settings.target_metric",
       [](v1::BakeSettings& s) { s.set_target_metric(v1::TARGET_METRIC_RMSE); }},
      {"settings.solver",
       [](v1::BakeSettings& s) {
         s.add_encodings(v1::ENCODING_SG12);
         s.set_solver(static_cast<v1::Solver>(42));
       }},
      {"settings.sg_sharpness",
       [](v1::BakeSettings& s) {
         s.add_encodings(v1::ENCODING_SG12);
         s.set_sg_sharpness(-2);
       }},
      {"settings.acceleration",
       [](v1::BakeSettings& s) {
         s.add_encodings(v1::ENCODING_SG12);
         s.set_acceleration(100);
       }},
      {"settings.sky.color",
       [](v1::BakeSettings& s) {
         s.mutable_sky()->set_kind(v1::Sky::KIND_CONSTANT);
         s.mutable_sky()->add_color(1);
       }},
      {"settings.samples_per_texel", [](v1::BakeSettings& s) { s.set_samples_per_texel(0); }},
      {"settings.time_budget_s", [](v1::BakeSettings& s) { s.set_time_budget_s(-1); }},
      {"settings.paths_per_iteration", [](v1::BakeSettings& s) { s.set_paths_per_iteration(5); }},
      {"settings.snapshot_format",
       [](v1::BakeSettings& s) { s.set_snapshot_format(static_cast<v1::SnapshotFormat>(42)); }},
  };
  for (const auto& c : cases) {
    v1::BakeSettings s = small_settings(16);
    c.edit(s);
    v1::BakeInfo info;
    auto st = submit(s, id, &info);
    EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << c.field;
    EXPECT_NE(st.error_message().find(c.field), std::string::npos)
        << c.field << ": " << st.error_message();
  }
  v1::BakeInfo info;
  auto st = submit(small_settings(16, 1024), id, &info);
  EXPECT_NE(st.error_message().find("--max-resolution=256"), std::string::npos)
      << st.error_message();
  v1::ListBakesResponse list;
  auto ctx = daemon_->context();
  ASSERT_TRUE(stub_->ListBakes(ctx.get(), {}, &list).ok());
  EXPECT_EQ(list.bakes_size(), 0) << "a refused bake was stored";
}

TEST_F(ServiceErrors, MissingOrWrongTokenIsUnauthenticated) {
  v1::ListScenesResponse list;
  grpc::ClientContext none;
  auto st = stub_->ListScenes(&none, {}, &list);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::UNAUTHENTICATED) << st.error_message();
  grpc::ClientContext wrong;
  wrong.AddMetadata("authorization", "Bearer nope");
  EXPECT_EQ(stub_->ListScenes(&wrong, {}, &list).error_code(), grpc::StatusCode::UNAUTHENTICATED);
  grpc::ClientContext upload_ctx;
  v1::SceneInfo info;
  auto writer = stub_->UploadScene(&upload_ctx, &info);
  v1::UploadSceneRequest req;
  req.mutable_header()->set_name("x");
  writer->Write(req);
  writer->WritesDone();
  EXPECT_EQ(writer->Finish().error_code(), grpc::StatusCode::UNAUTHENTICATED);
  auto ctx = daemon_->context();
  EXPECT_TRUE(stub_->ListScenes(ctx.get(), {}, &list).ok());
}

// A client can make unauthenticated calls as fast as it likes; the log gets
// one line a second, which counts the ones held back.
TEST(ServiceAuthLog, UnauthenticatedCallsAreLoggedAtMostOncePerSecond) {
  TempDir dir;
  Daemon d(dir.path() + "/data", {}, "flood-token");
  auto stub = d.stub();
  v1::ListScenesResponse list;
  auto count_lines = [&] {
    const std::string log = d.log();
    size_t n = 0;
    for (size_t at = log.find("event=unauthenticated"); at != std::string::npos;
         at = log.find("event=unauthenticated", at + 1))
      ++n;
    return n;
  };
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < 200; ++i) {
    grpc::ClientContext none;
    ASSERT_EQ(stub->ListScenes(&none, {}, &list).error_code(), grpc::StatusCode::UNAUTHENTICATED);
  }
  const double elapsed_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  // One line per started second of the flood, not 200.
  EXPECT_LE(count_lines(), static_cast<size_t>(elapsed_s) + 1) << d.log();
  EXPECT_GE(count_lines(), 1u);
  std::this_thread::sleep_for(std::chrono::milliseconds(1100));
  grpc::ClientContext none;
  EXPECT_EQ(stub->ListScenes(&none, {}, &list).error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_NE(d.log().find("suppressed_since_last="), std::string::npos) << d.log();
  EXPECT_EQ(d.stop(SIGTERM), 0);
}

TEST_F(ServiceErrors, MalformedProtobufIsRefusedAndTheDaemonLivesOn) {
  std::string response;
  // Field 1 declared as a 100-byte string, 3 bytes present.
  auto st = raw_unary(*daemon_, "/luxel.v1.Luxel/GetBake",
                      std::string("\x0a\x64"
                                  "abc",
                                  5),
                      &response);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << st.error_message();
  EXPECT_NE(st.error_message().find("malformed"), std::string::npos) << st.error_message();
  st = raw_unary(*daemon_, "/luxel.v1.Luxel/GetBake", std::string("\xff\xff\xff\xff\xff", 5),
                 &response);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << st.error_message();
  v1::ServerStatus status;
  auto ctx = daemon_->context();
  EXPECT_TRUE(stub_->GetServerStatus(ctx.get(), {}, &status).ok());
}

TEST_F(ServiceErrors, HealthServiceReportsServing) {
  std::string response;
  // grpc.health.v1.HealthCheckRequest{service: "luxel.v1.Luxel"}
  const std::string service = "luxel.v1.Luxel";
  auto st = raw_unary(*daemon_, "/grpc.health.v1.Health/Check",
                      std::string("\x0a") + char(service.size()) + service, &response);
  ASSERT_TRUE(st.ok()) << st.error_message();
  EXPECT_EQ(response, std::string("\x08\x01", 2)) << "HealthCheckResponse{status: SERVING}";
}

TEST_F(ServiceErrors, ReflectionListsTheLuxelService) {
  std::string response;
  // ServerReflectionRequest{list_services: ""}
  auto st =
      raw_bidi_once(*daemon_, "/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo",
                    std::string("\x3a\x00", 2), &response);
  EXPECT_TRUE(st.ok()) << st.error_message();
  EXPECT_NE(response.find("luxel.v1.Luxel"), std::string::npos);
}

// A bake whose host memory (result images of every encoding, on a CPU
// device its device buffers too) passes --host-memory-budget is refused at
// submit, naming the settings and the bytes; the same bake small is
// accepted and runs.
TEST(ServiceHostMemory, OversizeBakeIsRefusedAtSubmitNamingTheSettingsAndBytes) {
  TempDir dir;
  Daemon daemon(dir.path() + "/data", {"--max-resolution", "4096", "--host-memory-budget", "2e9"});
  const std::string scene = upload_cornell(daemon);
  auto stub = daemon.stub();
  auto submit = [&](uint32_t resolution, v1::BakeInfo* out) {
    v1::SubmitBakeRequest req;
    req.set_scene_id(scene);
    *req.mutable_settings() = small_settings(1, resolution);
    for (v1::Encoding e :
         {v1::ENCODING_SH1, v1::ENCODING_SH2, v1::ENCODING_SG6, v1::ENCODING_SG9, v1::ENCODING_SG12,
          v1::ENCODING_SG6_HEMI, v1::ENCODING_SG9_HEMI, v1::ENCODING_SG12_HEMI})
      req.mutable_settings()->add_encodings(e);
    auto ctx = daemon.context();
    return stub->SubmitBake(ctx.get(), req, out);
  };
  v1::BakeInfo info;
  const grpc::Status big = submit(4096, &info);
  ASSERT_EQ(big.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << big.error_message();
  const std::string& m = big.error_message();
  for (const char* part :
       {"settings.resolution 4096", "settings.encodings 'sh1,sh2,sg6,sg9,sg12,sg6-hemi,sg9-hemi,",
        "settings.denoise", "host-memory budget of 2000000000 bytes", "--host-memory-budget",
        "result images"})
    EXPECT_NE(m.find(part), std::string::npos) << part << " in: " << m;
  // The estimate in bytes: at least the result images, 4096^2 x 207 floats.
  const size_t at = m.find("needs an estimated ");
  ASSERT_NE(at, std::string::npos) << m;
  EXPECT_GE(std::stoull(m.substr(at + 19)), 4096ull * 4096 * 207 * 4) << m;
  EXPECT_NE(daemon.log().find("bake_refused"), std::string::npos);

  const grpc::Status small = submit(64, &info);
  ASSERT_TRUE(small.ok()) << small.error_message();
  const v1::BakeInfo done = wait_for_bake(daemon, info.bake_id(), is_finished);
  EXPECT_EQ(done.state(), v1::BAKE_STATE_SUCCEEDED) << done.DebugString();
  EXPECT_EQ(daemon.stop(SIGTERM), 0);
}

}  // namespace
}  // namespace luxel::test
