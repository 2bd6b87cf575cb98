#include "service/coordinator/shard_plan.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <optional>

#include "api/settings_translate.h"

namespace luxel::service::coordinator {

bool is_sharded(const v1::BakeSettings& s) {
  return s.shards() > 1 || s.shards_auto();
}

Status check_shard_settings(const v1::BakeSettings& s, bool have_workers,
                            const SettingsLimits& limits, uint32_t auto_count) {
  if (!is_sharded(s)) return Status::ok();
  const char* field = s.shards_auto() ? "settings.shards_auto" : "settings.shards";
  if (!have_workers)
    return invalid_argument(
        strprintf("%s: this luxeld has no workers to shard across (start it with --workers or "
                  "--workers-dns); 0 or 1 bakes on this machine",
                  field));
  if (s.samples_per_texel() == 0 && !(s.time_budget_s() > 0) && !(s.target_error() > 0))
    return invalid_argument(
        "settings.samples_per_texel: a sharded bake needs a stop rule (samples_per_texel, "
        "time_budget_s or target_error)");
  if (!s.reference_bake_id().empty())
    return invalid_argument("settings.reference_bake_id: benchmark mode is not sharded");
  // Left unset it is off for a sharded bake (the engine's rule for shards).
  if (s.has_adaptive() && s.adaptive())
    return invalid_argument(
        "settings.adaptive: sharded bakes sample uniformly; leave adaptive unset or false");
  if (s.shard_count() > 1 || s.shard_index() > 0)
    return invalid_argument(
        "settings.shard_count: set by the coordinator for its workers; not with shards");
  // What the workers will be asked (the engine's rules for shards, e.g. no
  // progressive solvers), refused here rather than FAILED on every worker.
  // The last shard has the smallest share of every texel's samples.
  const uint32_t count = std::max<uint32_t>(2, s.shards_auto() ? auto_count : s.shards());
  auto engine = to_engine_settings(shard_settings(s, count - 1, count), limits);
  return engine.status();
}

uint32_t usable_shard_count(const v1::BakeSettings& s, uint32_t wanted,
                            const SettingsLimits& limits) {
  uint32_t count = std::max<uint32_t>(wanted, 1);
  while (count > 1 && !to_engine_settings(shard_settings(s, count - 1, count), limits).is_ok())
    --count;
  return count;
}

v1::BakeSettings shard_settings(const v1::BakeSettings& s, uint32_t index, uint32_t count) {
  v1::BakeSettings out = s;
  out.set_shards(0);
  out.set_shards_auto(false);
  out.set_shard_index(index);
  out.set_shard_count(count);
  if (out.snapshot_format() != v1::SNAPSHOT_FORMAT_NONE)
    out.set_snapshot_format(v1::SNAPSHOT_FORMAT_EXR);
  return out;
}

v1::BakeProgress combine_progress(const std::vector<v1::BakeProgress>& shards) {
  v1::BakeProgress out;
  double inv_var = 0, fraction = 0, eta = 0;
  bool eta_unknown = false, error_known = !shards.empty();
  uint64_t paths = 0;
  double mean_spp = 0, elapsed = 0;
  uint64_t min_spp = 0;
  for (const v1::BakeProgress& p : shards) {
    paths += p.paths();
    mean_spp += p.mean_spp();
    min_spp += p.min_spp();
    elapsed = std::max(elapsed, p.elapsed_s());
    fraction += std::clamp(p.fraction(), 0.0, 1.0);
    if (p.eta_s() < 0) eta_unknown = true;
    eta = std::max(eta, p.eta_s());
    if (p.error() > 0 && std::isfinite(p.error()))
      inv_var += 1.0 / (p.error() * p.error());
    else
      error_known = false;
  }
  out.set_paths(paths);
  out.set_mean_spp(mean_spp);
  // A lower bound: the texel with the fewest samples in one shard need not be
  // the one with the fewest in another.
  out.set_min_spp(static_cast<uint32_t>(std::min<uint64_t>(min_spp, UINT32_MAX)));
  out.set_elapsed_s(elapsed);
  out.set_fraction(shards.empty() ? 0 : fraction / double(shards.size()));
  out.set_eta_s(eta_unknown ? -1 : eta);
  out.set_error(error_known && inv_var > 0 ? 1.0 / std::sqrt(inv_var) : 1.0);
  out.set_rmse(-1);
  out.set_rel_mse(-1);
  return out;
}

pipeline::Termination merged_termination(const ShardPlan& plan) {
  using pipeline::Termination;
  auto named = [](const std::string& t) -> std::optional<Termination> {
    if (t == "time") return Termination::kTime;
    if (t == "error") return Termination::kError;
    if (t == "stopped") return Termination::kStopped;
    return std::nullopt;
  };
  if (auto t = named(plan.stop)) return *t;
  for (const char* rule : {"time", "error", "stopped"})
    for (const ShardRecord& r : plan.shards)
      if (r.termination == rule) return *named(rule);
  return Termination::kSamples;
}

std::string shard_idempotency_key(const std::string& bake_id, uint32_t index, uint32_t attempt) {
  return strprintf("luxel-coordinator/%s/shard-%u/attempt-%u", bake_id.c_str(), index, attempt);
}

std::string plan_to_json(const ShardPlan& plan) {
  nlohmann::json j;
  j["version"] = 1;
  j["count"] = plan.count;
  j["shards"] = nlohmann::json::array();
  for (const ShardRecord& r : plan.shards)
    j["shards"].push_back({{"index", r.index},
                           {"worker", r.worker},
                           {"worker_bake_id", r.worker_bake_id},
                           {"attempts", r.attempts},
                           {"downloaded", r.downloaded},
                           {"sha256", r.sha256},
                           {"bad_workers", r.bad_workers},
                           {"termination", r.termination}});
  j["abandoned"] = nlohmann::json::array();
  for (const auto& [worker, bake] : plan.abandoned) j["abandoned"].push_back({worker, bake});
  j["stop"] = plan.stop;
  return j.dump(1) + "\n";
}

Result<ShardPlan> plan_from_json(const std::string& text) {
  try {
    const nlohmann::json j = nlohmann::json::parse(text);
    ShardPlan plan;
    plan.count = j.at("count").get<uint32_t>();
    for (const auto& s : j.at("shards")) {
      ShardRecord r;
      r.index = s.at("index").get<uint32_t>();
      r.worker = s.at("worker").get<std::string>();
      r.worker_bake_id = s.at("worker_bake_id").get<std::string>();
      r.attempts = s.at("attempts").get<uint32_t>();
      r.downloaded = s.at("downloaded").get<bool>();
      r.sha256 = s.at("sha256").get<std::string>();
      r.bad_workers = s.at("bad_workers").get<std::vector<std::string>>();
      r.termination = s.value("termination", std::string());
      plan.shards.push_back(std::move(r));
    }
    if (j.contains("abandoned"))
      for (const auto& a : j.at("abandoned"))
        plan.abandoned.emplace_back(a.at(0).get<std::string>(), a.at(1).get<std::string>());
    plan.stop = j.value("stop", std::string());
    if (!plan.stop.empty() && plan.stop != "time" && plan.stop != "error" && plan.stop != "stopped")
      return Status(StatusCode::kDataLoss, "shards.json: unknown stop rule " + plan.stop);
    if (plan.shards.size() != plan.count)
      return Status(StatusCode::kDataLoss, "shards.json: shard count does not match its list");
    for (uint32_t k = 0; k < plan.count; ++k)
      if (plan.shards[k].index != k)
        return Status(StatusCode::kDataLoss, strprintf("shards.json: shard %u out of order", k));
    return plan;
  } catch (const std::exception& e) {
    return Status(StatusCode::kDataLoss, std::string("shards.json: ") + e.what());
  }
}

}  // namespace luxel::service::coordinator
