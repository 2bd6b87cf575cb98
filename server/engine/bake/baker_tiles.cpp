// The Baker's setup and its tiles: the device buffers under the memory
// budget, the plan of tiles, the whole bake's progress from a tile's, and
// checkpoints and resumes across tiles (tile_plan.h).
#include <algorithm>
#include <cmath>

#include "bake/baker.h"
#include "bake/resource_estimate.h"

namespace luxel::pipeline {

Status Baker::setup() {
  const CancelToken cancel(hooks_->cancel);
  auto setup = prepare_bake(scene_, layout_.atlas, settings_, ctx_, probes_, cancel);
  if (!setup) return setup.status();
  s_ = std::move(setup.value());
  auto sort = RadixSort::create(ctx_, s_.capacity);
  if (!sort) return sort.status();
  sort_ = std::move(sort.value());
  if (settings_.compaction) {
    auto compaction = StreamCompaction::create(ctx_, s_.capacity);
    if (!compaction) return compaction.status();
    compaction_ = std::move(compaction.value());
  }
  LUXEL_RETURN_IF_ERROR(check_cancel(cancel, "the sort's setup"));
  LUXEL_RETURN_IF_ERROR(plan_memory());
  LUXEL_RETURN_IF_ERROR(check_cancel(cancel, "the tile plan"));
  auto buffers =
      BakeBuffers::create(ctx_, scene_, s_, settings_, {plan_.max_slots, plan_.max_words});
  if (!buffers) return buffers.status();
  b_ = std::move(buffers.value());
  auto offsets = OffsetBuffer::create(ctx_, s_.capacity, static_cast<uint32_t>(plan_.max_slots));
  if (!offsets) return offsets.status();
  offset_buffer_ = std::move(offsets.value());
  LUXEL_RETURN_IF_ERROR(check_cancel(cancel, "the buffers' allocation"));
  auto kernels = BakeKernels::create(ctx_, s_.features);
  if (!kernels) return kernels.status();
  kernels_ = std::move(kernels.value());
  return check_cancel(cancel, "the kernels' setup");
}

// The tiles of the covered texels under the device-memory budget.
Status Baker::plan_memory() {
  const device::DeviceInfo& info = ctx_.info();
  budget_ = memory_budget(settings_, info.global_mem_bytes);
  auto fixed = BakeBuffers::fixed_bytes(ctx_, scene_, s_, settings_);
  if (!fixed) return fixed.status();
  // The batch's buffers, checked as at submit (resource_estimate.h).
  const PathStateBytes per_path = path_state_bytes(!s_.plan.empty());
  const size_t path_bytes = s_.capacity * per_path.per_path;
  LUXEL_RETURN_IF_ERROR(check_path_state(s_.capacity, per_path,
                                         fixed.value() - std::min(fixed.value(), path_bytes),
                                         budget_, info.max_alloc_bytes));
  MemoryModel m;
  m.budget = budget_;
  m.max_alloc = info.max_alloc_bytes;
  m.fixed = fixed.value() + s_.tracer->device_bytes() + sort_->device_bytes() +
            (compaction_ ? compaction_->device_bytes() : 0);
  m.per_slot = BakeBuffers::per_slot_bytes(s_);
  m.largest_per_slot = BakeBuffers::largest_per_slot_bytes(s_);
  // The Gaussian filter gathers neighbours' paths of the same iteration,
  // across tile edges too.
  m.tileable = settings_.filter != Filter::kGaussian;
  m.why_not =
      "settings.filter 'gaussian' gathers the paths of neighbouring texels, which may lie "
      "in another tile (use the box filter, or a larger budget)";
  auto plan = plan_tiles(s_.info, m);
  if (!plan) return plan.status();
  plan_ = std::move(plan.value());
  if (tiled()) {
    tile_coverage_.assign(1, 0.0);
    for (const Tile& t : plan_.tiles)
      tile_coverage_.push_back(tile_coverage_.back() +
                               atlas::coverage_sum(s_.info, t.begin, t.end));
  }
  if (!tiled() || !settings_.reference) return Status::ok();
  const std::vector<float>& ref = *settings_.reference;
  for (const Tile& t : plan_.tiles) {
    double sq = 0, rel = 0;
    for (size_t k = t.begin; k < t.end; ++k) {
      const float* r = &ref[size_t{s_.info.covered_texels[k]} * 4];
      for (int c = 0; c < 3; ++c) {
        const double r2 = double{r[c]} * r[c];
        sq += r2 / 3.0;
        rel += r2 / (r2 + 1e-2) / 3.0;
      }
    }
    black_ref_.push_back({sq, rel});
  }
  return Status::ok();
}

double Baker::coverage_before(size_t slot) const {
  // Tiles are in slot order; `slot` is one's begin or the last one's end.
  const auto it = std::lower_bound(plan_.tiles.begin(), plan_.tiles.end(), slot,
                                   [](const Tile& t, size_t s) { return t.begin < s; });
  return tile_coverage_[size_t(it - plan_.tiles.begin())];
}

BakeProgress Baker::globalize(const BakeProgress& tile) const {
  if (!tiled()) return tile;
  BakeProgress p = tile;
  const double n = b_.args().params.covered_count;
  const double all = static_cast<double>(s_.info.covered_texels.size());
  const size_t black = s_.info.covered_texels.size() - done_.slots - b_.args().params.covered_count;
  double sq_black = 0, rel_black = 0;
  for (size_t i = plan_.tiles.size(); i-- > 0 && plan_.tiles[i].begin >= done_.slots + n;) {
    if (i < black_ref_.size()) {
      sq_black += black_ref_[i].first;
      rel_black += black_ref_[i].second;
    }
  }
  p.paths = done_.paths + tile.paths;
  p.mean_spp = static_cast<double>(p.paths) / all;
  p.min_spp = black > 0 ? 0 : std::min(done_.min_spp, tile.min_spp);
  // The error is coverage-weighted (kernels/bake/stats.h); texels not yet
  // reached count as 100 % error.
  const size_t tile_end = done_.slots + b_.args().params.covered_count;
  const double before = coverage_before(done_.slots), through = coverage_before(tile_end);
  const double total = tile_coverage_.back();
  p.error = (done_.error_sum + tile.error * (through - before) + (total - through)) / total;
  if (settings_.reference) {
    p.rmse = std::sqrt((done_.sq_sum + tile.rmse * tile.rmse * n + sq_black) / all);
    p.rel_mse = (done_.rel_sum + tile.rel_mse * n + rel_black) / all;
  }
  return p;
}

void Baker::append_state(BakeCheckpoint& to, const BakeCheckpoint& from) {
  to.mean.insert(to.mean.end(), from.mean.begin(), from.mean.end());
  to.m2.insert(to.m2.end(), from.m2.begin(), from.m2.end());
  to.weight.insert(to.weight.end(), from.weight.begin(), from.weight.end());
  to.spp.insert(to.spp.end(), from.spp.begin(), from.spp.end());
  to.basis.insert(to.basis.end(), from.basis.begin(), from.basis.end());
}

BakeCheckpoint Baker::tiled_checkpoint(const BakeCheckpoint& current, size_t ti) {
  BakeCheckpoint c;
  c.mean = std::move(finished_.mean);
  c.m2 = std::move(finished_.m2);
  c.weight = std::move(finished_.weight);
  c.spp = std::move(finished_.spp);
  c.basis = std::move(finished_.basis);
  label_state(c);
  c.width = current.width;
  c.height = current.height;
  c.paths_done = current.paths_done;
  c.nonfinite = current.nonfinite;
  append_state(c, current);
  const size_t n = s_.info.covered_texels.size();
  const size_t stride = s_.params.encoding_count == 0 ? 0 : s_.params.basis_stride;
  c.mean.resize(n, cl::float4{});
  c.m2.resize(n, cl::float4{});
  c.weight.resize(n, cl::float2{});
  c.spp.resize(n, 0);
  c.basis.resize(n * stride, cl::float4{});
  const Tile& t = plan_.tiles[ti];
  // The learned state (radiance cache, guide) is the current tile's alone:
  // finished tiles' is never read again, so it is neither kept nor stored
  // (zeros there keep the slots aligned).
  auto place = [&](std::vector<cl::float4>& to, const std::vector<cl::float4>& from, size_t k) {
    if (from.empty()) return;
    to.assign(n * k, cl::float4{});
    std::copy(from.begin(), from.end(), to.begin() + static_cast<std::ptrdiff_t>(t.begin * k));
  };
  place(c.radiance_cache, current.radiance_cache, 1);
  place(c.guide, current.guide, kGuideStride);
  c.tile.assign(kTileFields, 0.0);
  c.tile[kTileIndex] = static_cast<double>(ti);
  c.tile[kTileBegin] = static_cast<double>(t.begin);
  c.tile[kTileEnd] = static_cast<double>(t.end);
  c.tile[kTileCount] = static_cast<double>(plan_.tiles.size());
  c.tile[kTileDonePaths] = static_cast<double>(done_.paths);
  c.tile[kTileDoneNonfinite] = static_cast<double>(done_.nonfinite);
  c.tile[kTileDoneError] = done_.error_sum;
  c.tile[kTileDoneSq] = done_.sq_sum;
  c.tile[kTileDoneRel] = done_.rel_sum;
  c.tile[kTileDoneMinSpp] = static_cast<double>(done_.min_spp);
  return c;
}

void Baker::return_finished(BakeCheckpoint& c) {
  // Slots [0, done_.slots) are the finished tiles'; the arrays keep their
  // capacity for the next checkpoint.
  const size_t n = done_.slots;
  const size_t stride = s_.params.encoding_count == 0 ? 0 : s_.params.basis_stride;
  c.mean.resize(n);
  c.m2.resize(n);
  c.weight.resize(n);
  c.spp.resize(n);
  c.basis.resize(n * stride);
  finished_.mean = std::move(c.mean);
  finished_.m2 = std::move(c.m2);
  finished_.weight = std::move(c.weight);
  finished_.spp = std::move(c.spp);
  finished_.basis = std::move(c.basis);
}

Result<size_t> Baker::resume_tiles(const BakeCheckpoint& c, BakeResult& result) {
  const auto other_plan = [&] {
    return invalid_argument(
        strprintf("checkpoint was written under another tile plan than this bake's %zu tile(s) "
                  "(settings.device_memory_budget_mib or the device changed)",
                  plan_.tiles.size()));
  };
  if (c.tile.empty()) {
    if (tiled() && c.mean.size() == s_.info.covered_texels.size() && !c.per_texel) {
      whole_state_ = &c;
      LUXEL_RETURN_IF_ERROR(b_.load_tile(ctx_, s_, plan_.tiles[0].begin, plan_.tiles[0].end));
      LUXEL_RETURN_IF_ERROR(restore_whole_state(plan_.tiles[0].begin, plan_.tiles[0].end));
      return size_t{0};
    }
    if (tiled()) return other_plan();
    LUXEL_RETURN_IF_ERROR(b_.load_tile(ctx_, s_, plan_.tiles[0].begin, plan_.tiles[0].end));
    LUXEL_RETURN_IF_ERROR(b_.restore_state(ctx_, c, s_.info.covered_texels));
    return size_t{0};
  }
  const auto ti = static_cast<size_t>(c.tile[kTileIndex]);
  if (c.tile[kTileCount] != static_cast<double>(plan_.tiles.size()) || ti >= plan_.tiles.size() ||
      c.tile[kTileBegin] != static_cast<double>(plan_.tiles[ti].begin) ||
      c.tile[kTileEnd] != static_cast<double>(plan_.tiles[ti].end) ||
      c.mean.size() != s_.info.covered_texels.size())
    return other_plan();
  const Tile& t = plan_.tiles[ti];
  if (t.begin > 0) {
    BakeCheckpoint done = slice_checkpoint(c, 0, t.begin);
    done.nonfinite = static_cast<uint64_t>(c.tile[kTileDoneNonfinite]);
    write_state(s_, done, 0, result);
    done.radiance_cache.clear();  // finished tiles' learned state is never read
    done.guide.clear();
    if (keep_finished_) finished_ = std::move(done);
  }
  done_.slots = t.begin;
  done_.paths = static_cast<uint64_t>(c.tile[kTileDonePaths]);
  done_.nonfinite = static_cast<uint64_t>(c.tile[kTileDoneNonfinite]);
  done_.error_sum = c.tile[kTileDoneError];
  done_.sq_sum = c.tile[kTileDoneSq];
  done_.rel_sum = c.tile[kTileDoneRel];
  done_.min_spp = static_cast<uint32_t>(c.tile[kTileDoneMinSpp]);
  LUXEL_RETURN_IF_ERROR(b_.load_tile(ctx_, s_, t.begin, t.end));
  LUXEL_RETURN_IF_ERROR(
      b_.restore_state(ctx_, slice_checkpoint(c, t.begin, t.end), s_.info.covered_texels));
  return ti;
}

}  // namespace luxel::pipeline
