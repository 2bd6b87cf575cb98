#include "service/bake_store.h"

#include <google/protobuf/util/json_util.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "service/files.h"
#include "service/log.h"

namespace luxel::service {

namespace fs = std::filesystem;
namespace pbu = google::protobuf::util;
using nlohmann::json;

namespace {

constexpr const char* kRecordFormat = "luxel.bake_record.v1";

Result<std::string> record_to_json(const v1::BakeInfo& info, uint64_t seq) {
  std::string info_json;
  if (auto st = pbu::MessageToJsonString(info, &info_json); !st.ok())
    return internal_error("bake record to JSON: " + st.ToString());
  json record = {{"format", kRecordFormat}, {"seq", seq}, {"info", json::parse(info_json)}};
  return record.dump(1) + "\n";
}

// Records written before the settings had typed fields carried encoding,
// solver and target_metric as strings ("irradiance,sh2", "progressive-nn",
// "rmse"); they become the enum names of today's fields, so a bake queued
// before an upgrade resumes with the same settings.
void upgrade_settings(json& info) {
  if (!info.contains("settings") || !info["settings"].is_object()) return;
  json& s = info["settings"];
  auto enum_name = [](const char* prefix, std::string v) {
    for (char& c : v)
      c = c == '-' ? '_' : static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    return prefix + v;
  };
  if (s.contains("encoding") && s["encoding"].is_string()) {
    json list = json::array();
    std::string text = s["encoding"].get<std::string>();
    for (size_t start = 0; start <= text.size();) {
      size_t end = std::min(text.find(',', start), text.size());
      if (end > start) list.push_back(enum_name("ENCODING_", text.substr(start, end - start)));
      start = end + 1;
    }
    s.erase("encoding");
    if (!list.empty()) s["encodings"] = list;
  }
  for (auto [key, prefix] : {std::pair{"solver", "SOLVER_"}, {"targetMetric", "TARGET_METRIC_"}}) {
    if (!s.contains(key) || !s[key].is_string()) continue;
    const std::string v = s[key].get<std::string>();
    if (v.rfind(prefix, 0) == 0) continue;  // already an enum name
    if (v.empty())
      s.erase(key);
    else
      s[key] = enum_name(prefix, v);
  }
}

Status record_from_json(const std::string& text, const std::string& what, v1::BakeInfo* info,
                        uint64_t* seq) {
  const json record = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (record.is_discarded() || !record.is_object() || record.value("format", "") != kRecordFormat ||
      !record.contains("info") || !record.contains("seq") || !record["seq"].is_number_unsigned())
    return data_loss(strprintf("%s: not a %s record", what.c_str(), kRecordFormat));
  *seq = record["seq"].get<uint64_t>();
  json info_json = record["info"];
  upgrade_settings(info_json);
  pbu::JsonParseOptions options;
  options.ignore_unknown_fields = true;  // records written by a newer daemon
  if (auto st = pbu::JsonStringToMessage(info_json.dump(), info, options); !st.ok())
    return data_loss(strprintf("%s: %s", what.c_str(), st.ToString().c_str()));
  return Status::ok();
}

}  // namespace

bool is_terminal(v1::BakeState state) {
  return state == v1::BAKE_STATE_SUCCEEDED || state == v1::BAKE_STATE_FAILED ||
         state == v1::BAKE_STATE_CANCELLED;
}

BakeStore::BakeStore(std::string data_dir) : bakes_dir_(data_dir + "/bakes") {}

Result<std::unique_ptr<BakeStore>> BakeStore::open(const std::string& data_dir) {
  std::unique_ptr<BakeStore> store(new BakeStore(data_dir));
  LUXEL_RETURN_IF_ERROR(make_directories(store->bakes_dir_));
  std::error_code ec;
  for (const auto& dir : fs::directory_iterator(store->bakes_dir_, ec)) {
    const std::string path = dir.path().string() + "/record.json";
    auto text = read_whole_file(path);
    if (!text) {
      // A crash between creating the folder and writing the first record:
      // the submit was never acknowledged, so nothing is lost.
      log_event("bake_dir_without_record_removed", {{"path", dir.path().string()}});
      remove_tree(dir.path().string());
      continue;
    }
    auto entry = std::make_shared<Entry>();
    if (Status st = record_from_json(text.value(), path, &entry->info, &entry->seq); !st.is_ok()) {
      log_event("bake_record_unreadable", {{"path", path}, {"error", st.to_string()}});
      continue;
    }
    // Snapshots and transient files from the previous run.
    // Left-overs of a forced exit (a second SIGTERM, kill -9) are removed too:
    // a temporary file of an atomic write (the file it was to replace is
    // intact) and results half written (the record never said SUCCEEDED).
    for (const auto& f : fs::directory_iterator(dir.path(), ec)) {
      const std::string name = f.path().filename().string();
      const bool tmp = name.size() > 4 && name.compare(name.size() - 4, 4, ".tmp") == 0;
      if (tmp || name == "results.partial")
        log_event("partial_file_removed", {{"path", f.path().string()}});
      if (name.rfind("snapshot-", 0) == 0 || tmp || name == "results.partial")
        remove_tree(f.path().string());
    }
    const std::string id = entry->info.bake_id();
    if (id != dir.path().filename().string()) {
      // Every later write goes to bake_dir(id): an id that is not the folder's
      // name would write elsewhere, outside the store for one like "../x".
      log_event("bake_record_unreadable",
                {{"path", path}, {"error", "bake_id '" + id + "' is not the folder's name"}});
      continue;
    }
    if (!entry->info.idempotency_key().empty()) store->by_key_[entry->info.idempotency_key()] = id;
    store->next_seq_ = std::max(store->next_seq_, entry->seq + 1);
    store->bakes_[id] = std::move(entry);
  }
  log_event("bake_store_opened", {{"bakes", std::to_string(store->bakes_.size())}});
  return store;
}

std::shared_ptr<BakeStore::Entry> BakeStore::find(const std::string& bake_id) const {
  std::lock_guard<std::mutex> lock(mu_);
  auto it = bakes_.find(bake_id);
  return it == bakes_.end() ? nullptr : it->second;
}

Status BakeStore::persist(Entry& entry) {
  std::lock_guard<std::mutex> file_lock(entry.file_mu);
  Result<std::string> text = internal_error("unset");
  std::string id;
  {
    std::lock_guard<std::mutex> lock(mu_);
    // Serialised under file_mu, so the newest state is what lands last.
    text = record_to_json(entry.info, entry.seq);
    id = entry.info.bake_id();
  }
  if (!text) return text.status();
  return write_file_atomic(bake_dir(id) + "/record.json", text.value());
}

Result<BakeStore::Created> BakeStore::create(const std::string& scene_id,
                                             const v1::BakeSettings& settings,
                                             const std::string& idempotency_key) {
  // One creation at a time, so two retries with one key cannot both create.
  static std::mutex create_mu;
  std::lock_guard<std::mutex> create_lock(create_mu);
  if (!idempotency_key.empty()) {
    std::lock_guard<std::mutex> lock(mu_);
    if (auto it = by_key_.find(idempotency_key); it != by_key_.end()) {
      const v1::BakeInfo& existing = bakes_.at(it->second)->info;
      if (existing.scene_id() != scene_id)
        return Status(StatusCode::kInvalidArgument,
                      strprintf("idempotency_key '%s' was used for bake %s of another scene (%s)",
                                idempotency_key.c_str(), existing.bake_id().c_str(),
                                existing.scene_id().c_str()));
      return Created{existing, false};
    }
  }
  auto entry = std::make_shared<Entry>();
  v1::BakeInfo& info = entry->info;
  info.set_bake_id(random_hex_id());
  info.set_scene_id(scene_id);
  *info.mutable_settings() = settings;
  info.set_state(v1::BAKE_STATE_QUEUED);
  info.mutable_progress()->set_eta_s(-1);
  info.mutable_progress()->set_rmse(-1);
  info.mutable_progress()->set_rel_mse(-1);
  info.set_submitted_at(unix_now());
  info.set_idempotency_key(idempotency_key);
  {
    std::lock_guard<std::mutex> lock(mu_);
    entry->seq = next_seq_++;
  }
  LUXEL_RETURN_IF_ERROR(make_directories(bake_dir(info.bake_id())));
  LUXEL_RETURN_IF_ERROR(persist(*entry));
  std::lock_guard<std::mutex> lock(mu_);
  bakes_[info.bake_id()] = entry;
  if (!idempotency_key.empty()) by_key_[idempotency_key] = info.bake_id();
  return Created{info, true};
}

Result<v1::BakeInfo> BakeStore::get(const std::string& bake_id) const {
  auto v = view(bake_id);
  if (!v) return v.status();
  return v->info;
}

std::optional<v1::BakeInfo> BakeStore::find_by_key(const std::string& idempotency_key) const {
  std::lock_guard<std::mutex> lock(mu_);
  auto it = by_key_.find(idempotency_key);
  if (idempotency_key.empty() || it == by_key_.end()) return std::nullopt;
  return bakes_.at(it->second)->info;
}

std::vector<v1::BakeInfo> BakeStore::list(const std::vector<v1::BakeState>& states) const {
  std::vector<std::pair<uint64_t, v1::BakeInfo>> found;
  {
    std::lock_guard<std::mutex> lock(mu_);
    for (const auto& [id, e] : bakes_)
      if (states.empty() ||
          std::find(states.begin(), states.end(), e->info.state()) != states.end())
        found.emplace_back(e->seq, e->info);
  }
  std::sort(found.begin(), found.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<v1::BakeInfo> out;
  for (auto& [seq, info] : found) out.push_back(std::move(info));
  return out;
}

uint64_t BakeStore::sequence(const std::string& bake_id) const {
  std::lock_guard<std::mutex> lock(mu_);
  auto it = bakes_.find(bake_id);
  return it == bakes_.end() ? 0 : it->second->seq;
}

Status BakeStore::update(const std::string& bake_id,
                         const std::function<void(v1::BakeInfo&)>& change, bool persist_now) {
  auto entry = find(bake_id);
  if (!entry) return not_found(strprintf("bake_id: no bake '%s'", bake_id.c_str()));
  {
    std::lock_guard<std::mutex> lock(mu_);
    change(entry->info);
    // A finished bake's image is in its results; the float snapshot (up to
    // hundreds of MB for a large lightmap) would only pin memory.
    if (is_terminal(entry->info.state())) entry->snapshot.reset();
    ++entry->version;
  }
  entry->changed.notify_all();
  return persist_now ? persist(*entry) : Status::ok();
}

void BakeStore::publish_snapshot(const std::string& bake_id,
                                 std::shared_ptr<const SnapshotFrame> frame) {
  auto entry = find(bake_id);
  if (!entry) return;
  {
    std::lock_guard<std::mutex> lock(mu_);
    entry->snapshot = std::move(frame);
    ++entry->snapshot_seq;
    ++entry->version;
  }
  entry->changed.notify_all();
}

Result<BakeView> BakeStore::view(const std::string& bake_id) const {
  return wait_for_change(bake_id, 0, std::chrono::milliseconds(0));
}

Result<BakeView> BakeStore::wait_for_change(const std::string& bake_id, uint64_t seen,
                                            std::chrono::milliseconds timeout) const {
  auto entry = find(bake_id);
  if (!entry) return not_found(strprintf("bake_id: no bake '%s'", bake_id.c_str()));
  std::unique_lock<std::mutex> lock(mu_);
  if (timeout.count() > 0)
    entry->changed.wait_for(lock, timeout, [&] { return entry->version != seen; });
  return BakeView{entry->info, entry->version, entry->snapshot, entry->snapshot_seq};
}

void BakeStore::wake_all() const {
  std::lock_guard<std::mutex> lock(mu_);
  for (const auto& [id, e] : bakes_) e->changed.notify_all();
}

bool BakeStore::scene_in_use(const std::string& scene_id, std::string* bake_id) const {
  std::lock_guard<std::mutex> lock(mu_);
  for (const auto& [id, e] : bakes_) {
    if (e->info.scene_id() == scene_id && !is_terminal(e->info.state())) {
      if (bake_id) *bake_id = id;
      return true;
    }
  }
  return false;
}

std::map<std::string, uint64_t> BakeStore::count_by_state() const {
  std::map<std::string, uint64_t> counts;
  for (int s = v1::BAKE_STATE_QUEUED; s <= v1::BAKE_STATE_INTERRUPTED; ++s)
    counts[v1::BakeState_Name(static_cast<v1::BakeState>(s))] = 0;
  std::lock_guard<std::mutex> lock(mu_);
  for (const auto& [id, e] : bakes_) ++counts[v1::BakeState_Name(e->info.state())];
  return counts;
}

}  // namespace luxel::service
