#include "bake/tile_plan.h"

#include <algorithm>

namespace luxel::pipeline {

namespace {

double mib(size_t bytes) {
  return static_cast<double>(bytes) / (1024.0 * 1024.0);
}

// Words of the record of covered slot k (records are consecutive).
size_t record_words(const atlas::SampleInfo& info, size_t k) {
  const auto& cov = info.covered_texels;
  const size_t next = k + 1 < cov.size() ? info.offsets[cov[k + 1]] : info.words.size();
  return next - info.offsets[cov[k]];
}

}  // namespace

size_t default_memory_budget(uint64_t global_mem_bytes) {
  const uint64_t four_gib = uint64_t{4} << 30;
  return static_cast<size_t>(std::min<uint64_t>(global_mem_bytes / 5 * 4, four_gib));
}

Result<TilePlan> plan_tiles(const atlas::SampleInfo& info, const MemoryModel& m) {
  const size_t n = info.covered_texels.size();
  TilePlan plan;
  if (m.fixed >= m.budget)
    return resource_exhausted(strprintf(
        "settings.device_memory_budget_mib: %.0f MiB do not hold the bake's fixed device memory "
        "(scene, BVH, path state of paths_per_iteration: %.0f MiB); raise the budget or lower "
        "paths_per_iteration",
        mib(m.budget), mib(m.fixed)));
  const size_t room = m.budget - m.fixed;
  const size_t word_limit = m.max_alloc / 4;
  const size_t slot_limit = m.largest_per_slot ? m.max_alloc / m.largest_per_slot : n;
  // Tile capacity: S slots and W words with S * per_slot + W * 4 <= room,
  // split by the atlas's mean words per texel; every tile keeps within both,
  // so buffers sized for the largest tile stay within the budget.
  const size_t total_words = info.words.size();
  size_t S = n, W = total_words;
  if (n * m.per_slot + total_words * 4 > room || n > slot_limit || total_words > word_limit) {
    const double per = static_cast<double>(m.per_slot) + 4.0 * total_words / std::max<size_t>(n, 1);
    S = std::min({static_cast<size_t>(room / per), slot_limit, n});
    W = S == 0 ? 0 : std::min((room - S * m.per_slot) / 4, word_limit);
  }
  Tile t;
  for (size_t k = 0; k < n; ++k) {
    const size_t w = record_words(info, k);
    if (S == 0 || w > W)
      return resource_exhausted(strprintf(
          "settings.device_memory_budget_mib: %.0f MiB leave %.0f MiB beside the fixed device "
          "memory, too little for the state of one texel",
          mib(m.budget), mib(room)));
    if (k - t.begin + 1 > S || t.words + w > W) {
      t.end = k;
      plan.tiles.push_back(t);
      t = Tile{k, k, 0};
    }
    t.words += w;
  }
  t.end = n;
  plan.tiles.push_back(t);
  if (plan.tiles.size() > 1 && !m.tileable)
    return resource_exhausted(strprintf(
        "the bake needs %.0f MiB of device memory for its %zu covered texels beside %.0f MiB "
        "fixed, more than settings.device_memory_budget_mib (%.0f MiB) or the device's largest "
        "allocation (%.0f MiB) allow, and it cannot be baked in tiles: %s",
        mib(n * m.per_slot + info.words.size() * 4), n, mib(m.fixed), mib(m.budget),
        mib(m.max_alloc), m.why_not));
  for (const Tile& x : plan.tiles) {
    plan.max_slots = std::max(plan.max_slots, x.end - x.begin);
    plan.max_words = std::max(plan.max_words, x.words);
  }
  plan.device_bytes = m.fixed + plan.max_slots * m.per_slot + plan.max_words * 4;
  return plan;
}

}  // namespace luxel::pipeline
