// Every setting checked once, at SubmitBake, by the functions the bake runs
// (job::check_bake_job): settings that would FAIL once queued are refused
// with the field named; scenes no bake can use are refused at upload. The
// property test sends random probe, reference, sun and UV settings and bakes
// whatever is accepted at 1 sample: none of those may FAIL.
#include <gtest/gtest.h>

#include <random>

#include "daemon_harness.h"

namespace luxel::test {
namespace {

class SubmitChecks : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir();
    daemon_ = new Daemon(dir_->path() + "/data", {"--max-resolution", "256"});
    scene_ = new std::string(upload_cornell(*daemon_));
  }
  static void TearDownTestSuite() {
    EXPECT_EQ(daemon_->stop(SIGTERM), 0);
    delete scene_;
    delete daemon_;
    delete dir_;
  }

  static grpc::Status submit(const v1::BakeSettings& s, v1::BakeInfo* out,
                             const std::string& scene_id = "") {
    v1::SubmitBakeRequest req;
    req.set_scene_id(scene_id.empty() ? *scene_ : scene_id);
    *req.mutable_settings() = s;
    auto ctx = daemon_->context(std::chrono::seconds(120));
    return daemon_->stub()->SubmitBake(ctx.get(), req, out);
  }
  // Refused at submit with INVALID_ARGUMENT or RESOURCE_EXHAUSTED, the
  // message starting with `field`.
  static void expect_refused(const v1::BakeSettings& s, const std::string& field,
                             const std::string& what, const std::string& scene_id = "") {
    v1::BakeInfo info;
    const grpc::Status st = submit(s, &info, scene_id);
    if (st.ok()) {
      const v1::BakeInfo end = wait_for_bake(*daemon_, info.bake_id(), is_finished);
      FAIL() << what << ": accepted as bake " << info.bake_id() << ", which ended "
             << v1::BakeState_Name(end.state()) << " " << end.error_message();
    }
    EXPECT_TRUE(st.error_code() == grpc::StatusCode::INVALID_ARGUMENT ||
                st.error_code() == grpc::StatusCode::RESOURCE_EXHAUSTED)
        << what << ": " << st.error_code() << " " << st.error_message();
    EXPECT_EQ(st.error_message().rfind(field, 0), 0u) << what << ": " << st.error_message();
    EXPECT_EQ(st.error_message().find(daemon_->data_dir()), std::string::npos)
        << what << ": names a server path: " << st.error_message();
  }
  static v1::BakeSettings tiny() {
    v1::BakeSettings s = small_settings(1, 16);
    s.set_snapshot_format(v1::SNAPSHOT_FORMAT_NONE);
    return s;
  }
  static v1::BakeSettings probes_only(const std::string& spec) {
    v1::BakeSettings s = tiny();
    s.set_lightmap(false);
    s.set_probes(spec);
    return s;
  }

  static TempDir* dir_;
  static Daemon* daemon_;
  static std::string* scene_;
};
TempDir* SubmitChecks::dir_ = nullptr;
Daemon* SubmitChecks::daemon_ = nullptr;
std::string* SubmitChecks::scene_ = nullptr;

// The grid's probe count, counted in doubles: past 2^20 probes, and spacings
// or boxes whose count overflows an int (once "no probe to bake" at run).
TEST_F(SubmitChecks, ProbeGridCountIsCheckedAtSubmit) {
  for (const std::string spec : {"grid:0.001", "grid:0.01", "adaptive:1e-6", "grid:1e-9",
                                 "grid:1e-30", "grid:1:box=-1e30,-1e30,-1e30,1e30,1e30,1e30"}) {
    expect_refused(probes_only(spec), "settings.probes", spec);
    v1::BakeSettings with_lightmap = probes_only(spec);
    with_lightmap.set_lightmap(true);
    expect_refused(with_lightmap, "settings.probes", spec + " with the lightmap");
  }
}

TEST_F(SubmitChecks, ProbeFilePositionsAreReadAtSubmit) {
  v1::BakeSettings s = probes_only("file:probes.json");
  s.set_probe_positions("[[0, 1, 0], [1e39, 0, 0]]");  // not finite as a float
  expect_refused(s, "settings.probes", "a position of 1e39");
  std::string many = "[";
  for (size_t i = 0; i <= (size_t{1} << 20); ++i) many += i ? ",[0,1,0]" : "[0,1,0]";
  s.set_probe_positions(many + "]");
  expect_refused(s, "settings.probes", "2^20 + 1 positions");
}

TEST_F(SubmitChecks, NodesModeNeedsTaggedNodes) {
  expect_refused(probes_only("nodes"), "settings.probes", "nodes on the Cornell box");
}

TEST_F(SubmitChecks, ReferenceOfAnotherResolutionIsRefused) {
  v1::BakeSettings ref = tiny();
  ref.set_resolution(32);
  v1::BakeInfo done;
  ASSERT_TRUE(submit(ref, &done).ok());
  done = wait_for_bake(*daemon_, done.bake_id(), is_finished);
  ASSERT_EQ(done.state(), v1::BAKE_STATE_SUCCEEDED) << done.error_message();
  v1::BakeSettings s = tiny();
  s.set_resolution(64);
  s.set_reference_bake_id(done.bake_id());
  expect_refused(s, "settings.reference_bake_id", "a 32x32 reference for a 64x64 bake");
  // The same size is accepted and runs.
  s.set_resolution(32);
  v1::BakeInfo same;
  ASSERT_TRUE(submit(s, &same).ok());
  same = wait_for_bake(*daemon_, same.bake_id(), is_finished);
  EXPECT_EQ(same.state(), v1::BAKE_STATE_SUCCEEDED) << same.error_message();
}

TEST_F(SubmitChecks, SunDirectionThatNormalisesToZeroIsRefused) {
  v1::BakeSettings s = tiny();
  s.mutable_sun()->set_illuminance(1);
  // 1e-20: its squared length is a denormal, 0 on a thread that flushes
  // denormals (common/direction.h).
  for (float x : {1e-45f, 1e-30f, 1e-20f}) {
    s.mutable_sun()->clear_direction();
    s.mutable_sun()->add_direction(x);
    s.mutable_sun()->add_direction(0);
    s.mutable_sun()->add_direction(0);
    expect_refused(s, "settings.sun.direction", "sun direction (" + std::to_string(x) + ",0,0)");
  }
}

// Generated UVs whose charts fit no 16x16 page (the instanced foliage), or
// whose instanced mesh alone outgrows the page (the city): laid out at
// submit as the bake lays them out.
TEST_F(SubmitChecks, GeneratedUvsAtATooSmallResolutionAreRefused) {
  for (const std::string name : {"foliage_instanced.glb", "procedural_city.glb"}) {
    v1::SceneInfo scene;
    const grpc::Status up =
        upload_scene(*daemon_, name, v1::SCENE_FORMAT_GLB,
                     read_file(std::string(LUXEL_SCENES_DIR) + "/" + name), {}, &scene);
    ASSERT_TRUE(up.ok()) << up.error_message();
    v1::BakeSettings s = tiny();
    s.set_uv(v1::UV_MODE_GENERATE);
    s.set_resolution(16);
    expect_refused(s, "settings.resolution", "uv=generate at 16x16 on " + name, scene.scene_id());
  }
}

// Scenes every bake would fail on: no triangle, or coordinates past 1e16.
TEST_F(SubmitChecks, UnbakeableScenesAreRefusedAtUpload) {
  struct Case {
    std::string name;
    GltfBuilder b;
  };
  std::vector<Case> cases(3);
  cases[0].name = "empty.gltf";
  cases[0].b.add_node({{"name", "nothing"}});
  cases[1].name = "far.gltf";
  cases[1].b.add_node(
      {{"mesh", cases[1].b.add_mesh(
                    "far", {cases[1].b.triangles({1e20f, 0, 0, 1e20f, 1, 0, 1e20f, 0, 1})})}});
  cases[2].name = "huge_scale.gltf";
  cases[2].b.add_node(
      {{"mesh", cases[2].b.add_mesh("tri", {cases[2].b.triangles({0, 0, 0, 1, 0, 0, 0, 1, 0})})},
       {"scale", {1e308, 1e308, 1e308}}});
  for (Case& c : cases) {
    v1::SceneInfo info;
    const grpc::Status st =
        upload_scene(*daemon_, c.name, v1::SCENE_FORMAT_GLTF, c.b.gltf_embedded(), {}, &info);
    ASSERT_FALSE(st.ok()) << c.name << " was stored as " << info.scene_id();
    EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << c.name;
    EXPECT_NE(st.error_message().find(c.name), std::string::npos) << st.error_message();
    EXPECT_EQ(st.error_message().find(daemon_->data_dir()), std::string::npos)
        << st.error_message();
  }
}

// The property: random probe, reference, sun and UV settings; whatever is
// accepted at submit, baked at 1 sample on a small lightmap, does not FAIL.
TEST_F(SubmitChecks, WhatSubmitAcceptsDoesNotFailAtRun) {
  v1::BakeSettings ref_settings = tiny();
  ref_settings.set_resolution(32);
  v1::BakeInfo ref;
  ASSERT_TRUE(submit(ref_settings, &ref).ok());
  ref = wait_for_bake(*daemon_, ref.bake_id(), is_finished);
  ASSERT_EQ(ref.state(), v1::BAKE_STATE_SUCCEEDED) << ref.error_message();

  std::mt19937 rng(20261129);
  auto pick = [&](auto... options) {
    const std::vector<std::common_type_t<decltype(options)...>> v{options...};
    return v[std::uniform_int_distribution<size_t>(0, v.size() - 1)(rng)];
  };
  const char* kSpecs[] = {"",
                          "grid:1",
                          "grid:0.02",
                          "grid:1e-9",
                          "adaptive:2",
                          "adaptive:1e-6",
                          "nodes",
                          "file:p.json",
                          "grid:2:box=0,0,0,1,1,1",
                          "grid:1:box=-1e30,0,0,1e30,1,1"};
  const char* kPositions[] = {"[[0,1,0]]", "[[1e39,0,0]]", "[]", "[[0,1,0],[1,1,1]]"};
  const float kSun[] = {0, 1, -1, 1e-45f, 1e-20f, 1e-30f, 3e38f};
  size_t accepted = 0, refused = 0;
  for (int i = 0; i < 48; ++i) {
    v1::BakeSettings s = tiny();
    s.set_resolution(pick(8u, 16u, 32u, 64u));
    s.set_uv(pick(v1::UV_MODE_UNSPECIFIED, v1::UV_MODE_GENERATE, v1::UV_MODE_EXISTING));
    // Half without probes, so that the other fields are exercised alone too.
    const std::string spec =
        pick(0, 1) == 0 ? "" : kSpecs[std::uniform_int_distribution<int>(0, 9)(rng)];
    s.set_probes(spec);
    if (!spec.empty() && pick(0, 1) == 1) s.set_lightmap(false);
    if (spec.rfind("file:", 0) == 0)
      s.set_probe_positions(kPositions[std::uniform_int_distribution<int>(0, 3)(rng)]);
    if (pick(0, 1) == 1) {
      s.mutable_sun()->set_illuminance(pick(1.0f, 1e30f));
      for (int k = 0; k < 3; ++k)
        s.mutable_sun()->add_direction(kSun[std::uniform_int_distribution<int>(0, 6)(rng)]);
    }
    if (pick(0, 1, 2) == 2) s.set_reference_bake_id(ref.bake_id());
    v1::BakeInfo info;
    const grpc::Status st = submit(s, &info);
    if (!st.ok()) {
      ++refused;
      EXPECT_EQ(st.error_message().rfind("settings.", 0), 0u)
          << "case " << i << ": " << st.error_message() << "\n"
          << s.DebugString();
      continue;
    }
    ++accepted;
    info = wait_for_bake(*daemon_, info.bake_id(), is_finished, std::chrono::seconds(300));
    EXPECT_EQ(info.state(), v1::BAKE_STATE_SUCCEEDED)
        << "case " << i << ": accepted at submit, then " << v1::BakeState_Name(info.state()) << ": "
        << info.error_message() << "\n"
        << s.DebugString();
  }
  std::printf("random settings: %zu accepted and baked, %zu refused at submit\n", accepted,
              refused);
  EXPECT_GT(accepted, 0u);
  EXPECT_GT(refused, 0u);
}

}  // namespace
}  // namespace luxel::test
