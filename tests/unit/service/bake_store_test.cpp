// BakeStore on its own, in a temporary data folder: records round trip through
// disk, the change feed (versions, watchers, the newest-snapshot slot),
// atomic record writes, loading damaged records, reopening (a restart) and ids
// that try to leave the store. No daemon, no device.
#include "service/bake_store.h"

#include <google/protobuf/util/message_differencer.h>
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <future>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace luxel::service {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using google::protobuf::util::MessageDifferencer;

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void write_file(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p, std::ios::binary | std::ios::trunc) << text;
}

std::shared_ptr<const SnapshotFrame> frame(float value) {
  output::Image image{2, 2, 4, std::vector<float>(16, value)};
  return std::make_shared<SnapshotFrame>(std::move(image), v1::BakeProgress{},
                                         v1::SNAPSHOT_FORMAT_NONE, 0, "");
}

class BakeStoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string tmpl = (fs::path(::testing::TempDir()) / "bake_store_test.XXXXXX").string();
    ASSERT_NE(::mkdtemp(tmpl.data()), nullptr);
    root_ = tmpl;
    data_ = root_ / "data";
    reopen();
  }
  void TearDown() override {
    store_.reset();
    std::error_code ec;
    fs::remove_all(root_, ec);
  }
  // A restart: drop the store and load the folder again.
  void reopen() {
    store_.reset();
    auto opened = BakeStore::open(data_.string());
    ASSERT_TRUE(opened.is_ok()) << opened.status().to_string();
    store_ = std::move(opened.value());
  }
  v1::BakeInfo create(const std::string& scene = "scene1", int priority = 0,
                      const std::string& key = "") {
    v1::BakeSettings settings;
    settings.set_priority(priority);
    settings.set_resolution(64);
    auto c = store_->create(scene, settings, key);
    EXPECT_TRUE(c.is_ok()) << c.status().to_string();
    return c.is_ok() ? c->info : v1::BakeInfo{};
  }
  fs::path record_path(const std::string& id) const { return data_ / "bakes" / id / "record.json"; }

  fs::path root_, data_;
  std::unique_ptr<BakeStore> store_;
};

// ---- create / get / update round trips -------------------------------------

TEST_F(BakeStoreTest, CreateWritesAQueuedRecordBeforeReturning) {
  const v1::BakeInfo info = create("sceneA", 3);
  EXPECT_EQ(info.bake_id().size(), 32u);
  EXPECT_EQ(info.bake_id().find_first_not_of("0123456789abcdef"), std::string::npos);
  EXPECT_EQ(info.scene_id(), "sceneA");
  EXPECT_EQ(info.state(), v1::BAKE_STATE_QUEUED);
  EXPECT_EQ(info.settings().priority(), 3);
  EXPECT_GT(info.submitted_at(), 0.0);
  EXPECT_EQ(info.progress().eta_s(), -1);
  // On disk already, complete, and nothing temporary left beside it.
  const fs::path rec = record_path(info.bake_id());
  ASSERT_TRUE(fs::exists(rec));
  const auto j = nlohmann::json::parse(read_file(rec));
  EXPECT_EQ(j["format"], "luxel.bake_record.v1");
  EXPECT_EQ(j["info"]["bakeId"], info.bake_id());
  EXPECT_FALSE(fs::exists(rec.string() + ".tmp"));

  auto got = store_->get(info.bake_id());
  ASSERT_TRUE(got.is_ok());
  EXPECT_TRUE(MessageDifferencer::Equals(*got, info));
}

TEST_F(BakeStoreTest, PersistedUpdateSurvivesARestart) {
  const v1::BakeInfo info = create("sceneA", 2);
  const uint64_t seq = store_->sequence(info.bake_id());
  ASSERT_TRUE(store_
                  ->update(
                      info.bake_id(),
                      [](v1::BakeInfo& b) {
                        b.set_state(v1::BAKE_STATE_RUNNING);
                        b.set_started_at(1234.5);
                        b.mutable_progress()->set_paths(987654321);
                        b.add_notes("resumed from checkpoint");
                      },
                      /*persist=*/true)
                  .is_ok());
  const v1::BakeInfo before = *store_->get(info.bake_id());
  reopen();
  auto after = store_->get(info.bake_id());
  ASSERT_TRUE(after.is_ok()) << after.status().to_string();
  std::string diff;
  MessageDifferencer d;
  d.ReportDifferencesToString(&diff);
  EXPECT_TRUE(d.Compare(before, *after)) << diff;
  EXPECT_EQ(store_->sequence(info.bake_id()), seq);
}

TEST_F(BakeStoreTest, UnpersistedUpdateIsMemoryOnly) {
  // Progress between checkpoints lives in memory; a restart shows the last
  // persisted state.
  const v1::BakeInfo info = create();
  ASSERT_TRUE(store_
                  ->update(
                      info.bake_id(), [](v1::BakeInfo& b) { b.mutable_progress()->set_paths(42); },
                      /*persist=*/false)
                  .is_ok());
  EXPECT_EQ(store_->get(info.bake_id())->progress().paths(), 42u);
  reopen();
  EXPECT_EQ(store_->get(info.bake_id())->progress().paths(), 0u);
}

TEST_F(BakeStoreTest, UnknownBakeIsNotFound) {
  EXPECT_EQ(store_->get("0123456789abcdef0123456789abcdef").status().code(), StatusCode::kNotFound);
  EXPECT_EQ(store_->view("nope").status().code(), StatusCode::kNotFound);
  EXPECT_EQ(store_->wait_for_change("nope", 0, 10ms).status().code(), StatusCode::kNotFound);
  bool called = false;
  const Status st = store_->update(
      "nope", [&](v1::BakeInfo&) { called = true; }, true);
  EXPECT_EQ(st.code(), StatusCode::kNotFound);
  EXPECT_NE(st.message().find("nope"), std::string::npos) << st.message();
  EXPECT_FALSE(called);
  EXPECT_EQ(store_->sequence("nope"), 0u);
  store_->publish_snapshot("nope", frame(1));  // ignored, no crash
}

// ---- idempotency keys ------------------------------------------------------

TEST_F(BakeStoreTest, IdempotencyKeyReturnsTheFirstBake) {
  const v1::BakeInfo first = create("sceneA", 0, "key-1");
  auto again = store_->create("sceneA", v1::BakeSettings{}, "key-1");
  ASSERT_TRUE(again.is_ok());
  EXPECT_FALSE(again->created);
  EXPECT_EQ(again->info.bake_id(), first.bake_id());
  EXPECT_EQ(store_->list({}).size(), 1u);

  auto other_scene = store_->create("sceneB", v1::BakeSettings{}, "key-1");
  ASSERT_FALSE(other_scene.is_ok());
  EXPECT_EQ(other_scene.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(other_scene.status().message().find("key-1"), std::string::npos);

  ASSERT_TRUE(store_->find_by_key("key-1").has_value());
  EXPECT_EQ(store_->find_by_key("key-1")->bake_id(), first.bake_id());
  EXPECT_FALSE(store_->find_by_key("key-2").has_value());

  // The key is part of the record: still honoured after a restart.
  reopen();
  auto after = store_->create("sceneA", v1::BakeSettings{}, "key-1");
  ASSERT_TRUE(after.is_ok());
  EXPECT_FALSE(after->created);
  EXPECT_EQ(after->info.bake_id(), first.bake_id());
}

TEST_F(BakeStoreTest, EmptyIdempotencyKeyNeverDeduplicates) {
  const v1::BakeInfo a = create("sceneA", 0, "");
  const v1::BakeInfo b = create("sceneA", 0, "");
  EXPECT_NE(a.bake_id(), b.bake_id());
  EXPECT_FALSE(store_->find_by_key("").has_value());
}

// ---- states, listing, counts -----------------------------------------------

TEST(BakeStateTest, TerminalStates) {
  EXPECT_FALSE(is_terminal(v1::BAKE_STATE_QUEUED));
  EXPECT_FALSE(is_terminal(v1::BAKE_STATE_RUNNING));
  EXPECT_FALSE(is_terminal(v1::BAKE_STATE_INTERRUPTED));
  EXPECT_TRUE(is_terminal(v1::BAKE_STATE_SUCCEEDED));
  EXPECT_TRUE(is_terminal(v1::BAKE_STATE_FAILED));
  EXPECT_TRUE(is_terminal(v1::BAKE_STATE_CANCELLED));
}

TEST_F(BakeStoreTest, SceneInUseFollowsTheBakeThroughItsStates) {
  const v1::BakeInfo info = create("sceneA");
  auto set_state = [&](v1::BakeState s) {
    ASSERT_TRUE(store_
                    ->update(
                        info.bake_id(), [s](v1::BakeInfo& b) { b.set_state(s); }, true)
                    .is_ok());
  };
  std::string user;
  EXPECT_TRUE(store_->scene_in_use("sceneA", &user));
  EXPECT_EQ(user, info.bake_id());
  EXPECT_FALSE(store_->scene_in_use("sceneB"));
  for (v1::BakeState s : {v1::BAKE_STATE_RUNNING, v1::BAKE_STATE_INTERRUPTED}) {
    set_state(s);
    EXPECT_TRUE(store_->scene_in_use("sceneA")) << v1::BakeState_Name(s);
  }
  for (v1::BakeState s :
       {v1::BAKE_STATE_SUCCEEDED, v1::BAKE_STATE_FAILED, v1::BAKE_STATE_CANCELLED}) {
    set_state(s);
    EXPECT_FALSE(store_->scene_in_use("sceneA")) << v1::BakeState_Name(s);
    reopen();
    EXPECT_EQ(store_->get(info.bake_id())->state(), s) << "state lost across a restart";
  }
}

TEST_F(BakeStoreTest, ListIsInSubmissionOrderAndFiltersByState) {
  std::vector<std::string> ids;
  for (int i = 0; i < 6; ++i) ids.push_back(create("s", i % 3).bake_id());
  // Random ids sort differently from submission order; the list must not.
  auto ids_of = [](const std::vector<v1::BakeInfo>& v) {
    std::vector<std::string> out;
    for (const auto& b : v) out.push_back(b.bake_id());
    return out;
  };
  EXPECT_EQ(ids_of(store_->list({})), ids);
  ASSERT_TRUE(store_
                  ->update(
                      ids[1], [](v1::BakeInfo& b) { b.set_state(v1::BAKE_STATE_RUNNING); }, true)
                  .is_ok());
  ASSERT_TRUE(store_
                  ->update(
                      ids[4], [](v1::BakeInfo& b) { b.set_state(v1::BAKE_STATE_FAILED); }, true)
                  .is_ok());
  EXPECT_EQ(ids_of(store_->list({v1::BAKE_STATE_RUNNING})), (std::vector<std::string>{ids[1]}));
  EXPECT_EQ(ids_of(store_->list({v1::BAKE_STATE_FAILED, v1::BAKE_STATE_RUNNING})),
            (std::vector<std::string>{ids[1], ids[4]}));
  EXPECT_TRUE(store_->list({v1::BAKE_STATE_SUCCEEDED}).empty());
  const auto counts = store_->count_by_state();
  EXPECT_EQ(counts.at("BAKE_STATE_QUEUED"), 4u);
  EXPECT_EQ(counts.at("BAKE_STATE_RUNNING"), 1u);
  EXPECT_EQ(counts.at("BAKE_STATE_FAILED"), 1u);
  EXPECT_EQ(counts.at("BAKE_STATE_SUCCEEDED"), 0u);  // every state is listed

  // Same order after a restart, and new bakes sort after the old ones.
  reopen();
  EXPECT_EQ(ids_of(store_->list({})), ids);
  ids.push_back(create("s").bake_id());
  EXPECT_EQ(ids_of(store_->list({})), ids);
  EXPECT_GT(store_->sequence(ids.back()), store_->sequence(ids[5]));
}

// ---- versions, watchers, the snapshot slot ---------------------------------

TEST_F(BakeStoreTest, EveryChangeBumpsTheVersion) {
  const std::string id = create().bake_id();
  const uint64_t v0 = store_->view(id)->version;
  ASSERT_TRUE(store_
                  ->update(
                      id, [](v1::BakeInfo&) {}, false)
                  .is_ok());
  const uint64_t v1 = store_->view(id)->version;
  EXPECT_GT(v1, v0);
  store_->publish_snapshot(id, frame(1));
  EXPECT_GT(store_->view(id)->version, v1);
}

TEST_F(BakeStoreTest, WaitForChangeReturnsAtOnceTimesOutOrWakes) {
  const std::string id = create().bake_id();
  const uint64_t v = store_->view(id)->version;
  // No wall-clock assertions: a wait that should return at once is given a
  // day, so a wrong wait hangs the test (ctest's timeout fails it) instead of
  // depending on how loaded the machine is.
  constexpr auto kDay = std::chrono::hours(24);
  // An older version than the current one: no wait at all.
  EXPECT_EQ(store_->wait_for_change(id, v - 1, kDay)->version, v);
  // Nothing changes: back after the timeout with the same version.
  EXPECT_EQ(store_->wait_for_change(id, v, 100ms)->version, v);
  // A change from another thread wakes the watcher long before its timeout.
  auto watcher = std::async(std::launch::async, [&] {
    auto view = store_->wait_for_change(id, v, kDay);
    return view->version;
  });
  std::this_thread::sleep_for(50ms);
  ASSERT_TRUE(store_
                  ->update(
                      id, [](v1::BakeInfo& b) { b.set_state(v1::BAKE_STATE_RUNNING); }, false)
                  .is_ok());
  EXPECT_GT(watcher.get(), v);
}

TEST_F(BakeStoreTest, SnapshotSlotKeepsOnlyTheNewest) {
  const std::string id = create().bake_id();
  EXPECT_EQ(store_->view(id)->snapshot, nullptr);
  EXPECT_EQ(store_->view(id)->snapshot_seq, 0u);
  auto first = frame(1);
  std::weak_ptr<const SnapshotFrame> first_weak = first;
  store_->publish_snapshot(id, std::move(first));
  auto second = frame(2);
  const SnapshotFrame* second_raw = second.get();
  store_->publish_snapshot(id, std::move(second));
  const BakeView view = *store_->view(id);
  EXPECT_EQ(view.snapshot.get(), second_raw);
  EXPECT_EQ(view.snapshot_seq, 2u);
  EXPECT_TRUE(first_weak.expired()) << "an older snapshot is still held";
}

TEST_F(BakeStoreTest, FinishedBakeDropsItsSnapshot) {
  const std::string id = create().bake_id();
  store_->publish_snapshot(id, frame(1));
  ASSERT_TRUE(store_
                  ->update(
                      id, [](v1::BakeInfo& b) { b.set_state(v1::BAKE_STATE_RUNNING); }, false)
                  .is_ok());
  EXPECT_NE(store_->view(id)->snapshot, nullptr) << "a running bake keeps its snapshot";
  ASSERT_TRUE(store_
                  ->update(
                      id, [](v1::BakeInfo& b) { b.set_state(v1::BAKE_STATE_SUCCEEDED); }, true)
                  .is_ok());
  EXPECT_EQ(store_->view(id)->snapshot, nullptr);
}

TEST_F(BakeStoreTest, SnapshotsAreNotKeptAcrossARestart) {
  const std::string id = create().bake_id();
  store_->publish_snapshot(id, frame(1));
  // Scratch files a watcher left in the bake folder.
  const fs::path scratch = data_ / "bakes" / id / "snapshot-0001.png";
  write_file(scratch, "partial");
  reopen();
  EXPECT_EQ(store_->view(id)->snapshot, nullptr);
  EXPECT_EQ(store_->view(id)->snapshot_seq, 0u);
  EXPECT_FALSE(fs::exists(scratch));
  EXPECT_TRUE(fs::exists(record_path(id)));
}

// ---- durability ------------------------------------------------------------

TEST_F(BakeStoreTest, ReadersNeverSeeAHalfWrittenRecord) {
  // The record is replaced by rename: a reader sees the old or the new file,
  // whole. Records grow with each note, so a torn write would be visible.
  const std::string id = create().bake_id();
  const fs::path rec = record_path(id);
  std::atomic<bool> done{false};
  std::atomic<int> reads{0}, torn{0};
  std::string bad;
  std::thread reader([&] {
    while (!done) {
      const std::string text = read_file(rec);
      ++reads;
      if (nlohmann::json::parse(text, nullptr, false).is_discarded() && torn++ == 0) bad = text;
    }
  });
  for (int i = 0; i < 300; ++i) {
    ASSERT_TRUE(store_
                    ->update(
                        id,
                        [i](v1::BakeInfo& b) {
                          b.add_notes("note " + std::to_string(i) + std::string(64, 'x'));
                        },
                        true)
                    .is_ok());
  }
  done = true;
  reader.join();
  EXPECT_EQ(torn.load(), 0) << "of " << reads.load() << " reads; first torn one (" << bad.size()
                            << " bytes): " << bad.substr(0, 200);
  EXPECT_FALSE(fs::exists(rec.string() + ".tmp"));
  reopen();
  EXPECT_EQ(store_->get(id)->notes_size(), 300);
}

TEST_F(BakeStoreTest, LeftoverTemporaryFileDoesNotShadowTheRecord) {
  // A crash after writing record.json.tmp but before the rename.
  const v1::BakeInfo info = create("sceneA");
  write_file(record_path(info.bake_id()).string() + ".tmp", "{\"format\": \"luxel.bake_rec");
  reopen();
  auto got = store_->get(info.bake_id());
  ASSERT_TRUE(got.is_ok());
  EXPECT_EQ(got->scene_id(), "sceneA");
  // And the next write still succeeds over it.
  EXPECT_TRUE(store_
                  ->update(
                      info.bake_id(), [](v1::BakeInfo&) {}, true)
                  .is_ok());
}

TEST_F(BakeStoreTest, FolderWithoutRecordIsRemovedOnOpen) {
  // A crash between creating the folder and writing the first record: the
  // submit was never acknowledged.
  const fs::path orphan = data_ / "bakes" / "ffffffffffffffffffffffffffffffff";
  write_file(orphan / "checkpoint.bin", "x");
  reopen();
  EXPECT_FALSE(fs::exists(orphan));
  EXPECT_TRUE(store_->list({}).empty());
}

struct DamagedRecord {
  const char* name;
  std::string text;
};

TEST_F(BakeStoreTest, DamagedRecordsAreSkippedWithALoggedErrorNotACrash) {
  const v1::BakeInfo good = create("good");
  const v1::BakeInfo victim = create("victim");
  const std::string whole = read_file(record_path(victim.bake_id()));
  const std::vector<DamagedRecord> damaged = {
      {"truncated", whole.substr(0, whole.size() / 2)},
      {"empty", ""},
      {"binary", std::string("\x00\xff\x10garbage", 10)},
      {"not_an_object", "[1, 2, 3]\n"},
      {"wrong_format", R"({"format": "something.else", "seq": 1, "info": {}})"},
      {"no_seq", R"({"format": "luxel.bake_record.v1", "info": {"bakeId": "x"}})"},
      {"negative_seq", R"({"format": "luxel.bake_record.v1", "seq": -4, "info": {}})"},
      {"no_info", R"({"format": "luxel.bake_record.v1", "seq": 7})"},
      {"bad_info", R"({"format": "luxel.bake_record.v1", "seq": 7, "info": {"state": 12.5}})"},
  };
  for (const DamagedRecord& d : damaged) {
    SCOPED_TRACE(d.name);
    write_file(record_path(victim.bake_id()), d.text);
    ::testing::internal::CaptureStderr();
    reopen();
    const std::string log = ::testing::internal::GetCapturedStderr();
    ASSERT_NE(store_, nullptr);
    EXPECT_EQ(store_->get(victim.bake_id()).status().code(), StatusCode::kNotFound);
    EXPECT_TRUE(store_->get(good.bake_id()).is_ok()) << "one bad record took others with it";
    EXPECT_NE(log.find("bake_record_unreadable"), std::string::npos) << log;
    EXPECT_NE(log.find(victim.bake_id()), std::string::npos) << "log names the file: " << log;
    // The damaged file is kept for a human to look at, not deleted.
    EXPECT_TRUE(fs::exists(record_path(victim.bake_id())));
  }
  // The store stays usable.
  EXPECT_TRUE(store_->create("after", v1::BakeSettings{}, "").is_ok());
}

// ---- ids that try to leave the store ---------------------------------------

TEST_F(BakeStoreTest, PathLikeIdsAreUnknownAndTouchNothing) {
  create();
  for (const std::string id : {"../x", "..", ".", "", "a/b", "/etc/passwd", "../../data"}) {
    SCOPED_TRACE(id);
    EXPECT_EQ(store_->get(id).status().code(), StatusCode::kNotFound);
    EXPECT_EQ(store_
                  ->update(
                      id, [](v1::BakeInfo&) {}, true)
                  .code(),
              StatusCode::kNotFound);
    store_->publish_snapshot(id, frame(1));
  }
  EXPECT_FALSE(fs::exists(data_ / "x"));
  EXPECT_FALSE(fs::exists(root_ / "x"));
  std::vector<std::string> entries;
  for (const auto& e : fs::directory_iterator(data_)) entries.push_back(e.path().filename());
  EXPECT_EQ(entries, (std::vector<std::string>{"bakes"}));
}

TEST_F(BakeStoreTest, RecordWhoseIdIsNotItsFolderIsRejected) {
  // A record is trusted only for the folder it sits in: an id such as "../x"
  // inside it would make every later write land outside the store.
  const v1::BakeInfo info = create("sceneA");
  auto j = nlohmann::json::parse(read_file(record_path(info.bake_id())));
  for (const std::string forged : {"../x", "../../escape", "0123456789abcdef0123456789abcdef"}) {
    SCOPED_TRACE(forged);
    j["info"]["bakeId"] = forged;
    const fs::path dir = data_ / "bakes" / "00000000000000000000000000000001";
    write_file(dir / "record.json", j.dump(1));
    ::testing::internal::CaptureStderr();
    reopen();
    const std::string log = ::testing::internal::GetCapturedStderr();
    EXPECT_EQ(store_->get(forged).status().code(), StatusCode::kNotFound);
    EXPECT_EQ(store_->get("00000000000000000000000000000001").status().code(),
              StatusCode::kNotFound);
    EXPECT_NE(log.find("bake_record_unreadable"), std::string::npos) << log;
    EXPECT_TRUE(store_->get(info.bake_id()).is_ok());
    EXPECT_EQ(store_->list({}).size(), 1u);
  }
}

}  // namespace
}  // namespace luxel::service
