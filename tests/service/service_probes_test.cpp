// Light probes through luxeld: a probes-only bake (lightmap off) killed
// with -9 after a checkpoint resumes and writes the same probes.bin as a bake
// run from zero; a lightmap + probes job serves both as artifacts and its
// manifest describes the probe layout.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <thread>

#include "daemon_harness.h"

namespace luxel::test {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

std::string fetch(const Daemon& d, const std::string& bake_id, const std::string& name) {
  std::string bytes, sha;
  uint64_t total = 0;
  auto st = download(d, bake_id, name, &bytes, &sha, &total);
  EXPECT_TRUE(st.ok()) << name << ": " << st.error_message();
  EXPECT_EQ(sha, sha256_hex(bytes));
  return bytes;
}

bool has_artifact(const v1::BakeInfo& info, const std::string& name) {
  for (const auto& a : info.artifacts())
    if (a == name) return true;
  return false;
}

TEST(ServiceProbes, ProbesOnlyBakeResumesAfterKillDashNine) {
  TempDir dir;
  const std::string data = dir.path() + "/data";
  const std::vector<std::string> flags = {"--checkpoint-interval", "0.3"};
  auto daemon = std::make_unique<Daemon>(data, flags);
  const std::string scene_id = upload_cornell(*daemon);
  v1::BakeSettings s = small_settings(2048);
  s.set_snapshot_format(v1::SNAPSHOT_FORMAT_NONE);
  s.set_probes("grid:0.5");
  s.set_lightmap(false);
  const v1::BakeInfo a = submit_bake(*daemon, scene_id, s);
  const std::string ckpt = data + "/bakes/" + a.bake_id() + "/checkpoint.bin";
  const auto deadline = std::chrono::steady_clock::now() + 60s;
  while (!fs::exists(ckpt) && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(20ms);
  ASSERT_TRUE(fs::exists(ckpt)) << daemon->log();
  EXPECT_EQ(daemon->stop(SIGKILL), 128 + SIGKILL);
  ASSERT_NE(read_file(data + "/bakes/" + a.bake_id() + "/record.json").find("BAKE_STATE_RUNNING"),
            std::string::npos)
      << "the bake should have been killed while running; make it longer";

  daemon = std::make_unique<Daemon>(data, flags);
  const v1::BakeInfo ra = wait_for_bake(*daemon, a.bake_id(), is_finished);
  ASSERT_EQ(ra.state(), v1::BAKE_STATE_SUCCEEDED) << ra.error_message() << daemon->log();
  EXPECT_EQ(ra.resumed(), 1u);
  EXPECT_TRUE(has_artifact(ra, "probes.bin")) << ra.DebugString();
  EXPECT_TRUE(has_artifact(ra, "probes.json"));
  EXPECT_FALSE(has_artifact(ra, "irradiance.exr")) << "lightmap off";
  // The same settings from zero: the resumed bake's probes bit for bit.
  const v1::BakeInfo b = submit_bake(*daemon, scene_id, s);
  const v1::BakeInfo rb = wait_for_bake(*daemon, b.bake_id(), is_finished);
  ASSERT_EQ(rb.state(), v1::BAKE_STATE_SUCCEEDED) << rb.error_message();
  EXPECT_EQ(rb.resumed(), 0u);
  const std::string pa = fetch(*daemon, a.bake_id(), "probes.bin");
  const std::string pb = fetch(*daemon, b.bake_id(), "probes.bin");
  ASSERT_GT(pa.size(), 96u);
  EXPECT_EQ(std::memcmp(pa.data(), "LUXPROBE", 8), 0);
  EXPECT_TRUE(pa == pb) << "resume changed the probes";
  EXPECT_NE(fetch(*daemon, a.bake_id(), "probes.json").find("\"luxel-probes\""), std::string::npos);
  EXPECT_EQ(daemon->stop(SIGTERM), 0);
}

TEST(ServiceProbes, LightmapAndProbesInOneJob) {
  TempDir dir;
  Daemon daemon(dir.path() + "/data");
  const std::string scene_id = upload_cornell(daemon);
  v1::BakeSettings s = small_settings(16);
  s.set_probes("adaptive:1");
  s.set_probe_sh_order(1);
  s.set_probe_window("lanczos");
  const v1::BakeInfo a = submit_bake(daemon, scene_id, s);
  const v1::BakeInfo ra = wait_for_bake(daemon, a.bake_id(), is_finished);
  ASSERT_EQ(ra.state(), v1::BAKE_STATE_SUCCEEDED) << ra.error_message() << daemon.log();
  EXPECT_TRUE(has_artifact(ra, "irradiance.exr"));
  EXPECT_TRUE(has_artifact(ra, "probes.bin"));
  const std::string manifest = fetch(daemon, a.bake_id(), "manifest.json");
  EXPECT_NE(manifest.find("\"probes\""), std::string::npos) << manifest;
  EXPECT_NE(manifest.find("\"adaptive\""), std::string::npos);
  const std::string json = fetch(daemon, a.bake_id(), "probes.json");
  EXPECT_NE(json.find("\"lanczos\""), std::string::npos);
  EXPECT_NE(json.find("\"sh1\""), std::string::npos);
  // A bad probe spec is refused at submit, naming the field.
  v1::SubmitBakeRequest req;
  req.set_scene_id(scene_id);
  *req.mutable_settings() = s;
  req.mutable_settings()->set_probes("cube:1");
  v1::BakeInfo info;
  auto ctx = daemon.context();
  auto st = daemon.stub()->SubmitBake(ctx.get(), req, &info);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(st.error_message().find("settings.probes"), std::string::npos) << st.error_message();
}

TEST(ServiceProbes, ProbesAtTaggedGltfNodes) {
  // The Cornell box with two nodes tagged extras.luxelProbe: the daemon
  // reads them from the stored scene file.
  TempDir dir;
  Daemon daemon(dir.path() + "/data");
  json doc = json::parse(read_file(LUXEL_SCENES_DIR "/cornell_box.gltf"));
  const size_t n = doc["nodes"].size();
  doc["nodes"].push_back({{"translation", {0, 1, 0}}, {"extras", {{"luxelProbe", true}}}});
  doc["nodes"].push_back({{"translation", {0.2, 0.5, -0.2}}, {"extras", {{"luxelProbe", true}}}});
  doc["scenes"][doc.value("scene", 0)]["nodes"].push_back(n);
  doc["scenes"][doc.value("scene", 0)]["nodes"].push_back(n + 1);
  v1::SceneInfo info;
  auto up =
      upload_scene(daemon, "cb_probes.gltf", v1::SCENE_FORMAT_GLTF, doc.dump(),
                   {{"cornell_box.bin", read_file(LUXEL_SCENES_DIR "/cornell_box.bin")}}, &info);
  ASSERT_TRUE(up.ok()) << up.error_message();
  v1::BakeSettings s = small_settings(32);
  s.set_probes("nodes");
  s.set_lightmap(false);
  const v1::BakeInfo a = submit_bake(daemon, info.scene_id(), s);
  const v1::BakeInfo ra = wait_for_bake(daemon, a.bake_id(), is_finished);
  ASSERT_EQ(ra.state(), v1::BAKE_STATE_SUCCEEDED) << ra.error_message() << daemon.log();
  const json meta = json::parse(fetch(daemon, a.bake_id(), "probes.json"));
  EXPECT_EQ(meta["layout"]["mode"], "nodes");
  ASSERT_EQ(meta["probes"].size(), 2u);
  // The untagged Cornell box: refused at submit, naming the setting.
  const std::string plain = upload_cornell(daemon);
  v1::SubmitBakeRequest req;
  req.set_scene_id(plain);
  *req.mutable_settings() = s;
  v1::BakeInfo b;
  auto ctx = daemon.context();
  const grpc::Status st = daemon.stub()->SubmitBake(ctx.get(), req, &b);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(st.error_message().rfind("settings.probes", 0), 0u) << st.error_message();
  EXPECT_NE(st.error_message().find("luxelProbe"), std::string::npos) << st.error_message();
}

}  // namespace
}  // namespace luxel::test
