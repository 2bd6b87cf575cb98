// The exact merge of shard accumulators. Per texel and channel the shards
// hold weighted Welford states (kernels/bake/accumulate.h, West 1979): the
// weight sums W = sum w and W2 = sum w^2, the weighted mean m and
// M2 = sum w (x - m)^2. Two of them combine as (Chan, Golub and LeVeque,
// "Updating formulae and a pairwise algorithm for computing sample
// variances", 1979, weighted form):
//   W = Wa + Wb,  d = mb - ma,  m = ma + d Wb / W,
//   M2 = M2a + M2b + d^2 Wa Wb / W,  W2 = W2a + W2b,
// which is what one accumulator fed both sample sets would hold, up to
// rounding. The sums run in double, in shard-index order, so the merge is
// deterministic whatever order the shards arrive in. Projection encodings
// (kernels/bake/basis.h) hold running means of Monte Carlo moments with the
// sample weight sum in their header: weighted means merge the same way.
#include "shards/shard_merge.h"

#include <algorithm>
#include <cmath>
#include <thread>

#include "kernels/shared/bake.h"
#include "kernels/shared/shard.h"

namespace luxel::pipeline {
namespace {

bool finite4(const cl::float4& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z) && std::isfinite(v.w);
}

// The checks of one shard on its own; `who` names it in errors.
Status check_shard(const BakeCheckpoint& s, const std::string& who) {
  auto bad = [&](const std::string& why) {
    return invalid_argument(strprintf("%s: %s", who.c_str(), why.c_str()));
  };
  if (s.per_texel) return bad("holds a whole-image state (an old checkpoint), not a shard's");
  if (!s.tile.empty())
    return bad("is an unfinished tiled state (a periodic checkpoint), not a finished shard's");
  const size_t n = s.mean.size();
  if (n == 0) return bad("holds no texels");
  if (s.m2.size() != n || s.weight.size() != n || s.spp.size() != n)
    return bad(strprintf("array sizes disagree (mean %zu, m2 %zu, weight %zu, spp %zu)", n,
                         s.m2.size(), s.weight.size(), s.spp.size()));
  if (n > size_t{s.width} * s.height)
    return bad(strprintf("holds %zu texels, more than its %ux%u lightmap", n, s.width, s.height));
  uint64_t spp_sum = 0;
  for (size_t i = 0; i < n; ++i) {
    if (!finite4(s.mean[i]) || !finite4(s.m2[i]) || !std::isfinite(s.weight[i].x) ||
        !std::isfinite(s.weight[i].y))
      return bad(strprintf("texel slot %zu holds a non-finite accumulator", i));
    if (s.m2[i].x < 0 || s.m2[i].y < 0 || s.m2[i].z < 0 || s.m2[i].w < 0 || s.weight[i].x < 0 ||
        s.weight[i].y < 0)
      return bad(strprintf("texel slot %zu holds a negative M2 or weight", i));
    spp_sum += s.spp[i];
  }
  if (spp_sum != s.paths_done)
    return bad(strprintf("its texels hold %llu samples but it traced %llu paths",
                         static_cast<unsigned long long>(spp_sum),
                         static_cast<unsigned long long>(s.paths_done)));
  if (!s.basis.empty()) {
    if (s.basis_layout.empty())
      return bad("holds directional-encoding state without its layout (an old checkpoint)");
    size_t stride = 0;
    for (uint32_t e : s.basis_layout) {
      const uint32_t count = e & 0xFFFFu, solver = e >> 16;
      if (solver != LUX_SOLVER_PROJECTION)
        return bad(
            "holds progressive least-squares encoding state (order-dependent Gauss-Seidel "
            "updates, Listing 7.1), which does not merge; shard with solver=projection");
      if (count == 0 || count > LUX_ENC_MAX_LOBES) return bad("has an invalid encoding layout");
      stride += 1 + count;
    }
    if (s.basis.size() != n * stride)
      return bad(
          strprintf("holds %zu encoding values, its layout needs %zu", s.basis.size(), n * stride));
    for (size_t i = 0; i < s.basis.size(); ++i)
      if (!finite4(s.basis[i]))
        return bad(strprintf("texel slot %zu holds non-finite encoding state", i / stride));
  }
  return Status::ok();
}

}  // namespace

Result<BakeCheckpoint> merge_shard_states(std::vector<BakeCheckpoint> shards) {
  if (shards.empty()) return invalid_argument("shard merge: no shard states given");
  auto who = [&](size_t i) {
    return strprintf("shard %u of %u (input %zu)", shards[i].shard_index, shards[i].shard_count, i);
  };
  const BakeCheckpoint& first = shards[0];
  const uint32_t count = first.shard_count;
  if (count == 0 || count > 4096)
    return invalid_argument(strprintf("%s: invalid shard_count", who(0).c_str()));
  if (shards.size() > count)
    return invalid_argument(
        strprintf("shard merge: %zu states for a bake of %u shards", shards.size(), count));
  for (size_t i = 0; i < shards.size(); ++i) {
    const BakeCheckpoint& s = shards[i];
    LUXEL_RETURN_IF_ERROR(check_shard(s, who(i)));
    auto bad = [&](const std::string& why) {
      return invalid_argument(strprintf("%s: %s", who(i).c_str(), why.c_str()));
    };
    if (s.fingerprint != first.fingerprint)
      return bad(strprintf("belongs to another bake (fingerprint %s, input 0 has %s)",
                           s.fingerprint.c_str(), first.fingerprint.c_str()));
    if (s.shard_count != count)
      return bad(strprintf("is one of %u shards, input 0 one of %u", s.shard_count, count));
    if (s.shard_index >= count) return bad("shard_index is not below shard_count");
    if (s.width != first.width || s.height != first.height || s.mean.size() != first.mean.size())
      return bad(strprintf("is a %ux%u lightmap with %zu covered texels, input 0 %ux%u with %zu",
                           s.width, s.height, s.mean.size(), first.width, first.height,
                           first.mean.size()));
    if (s.basis_layout != first.basis_layout || s.basis.size() != first.basis.size())
      return bad("has other directional encodings than input 0");
    for (size_t j = 0; j < i; ++j)
      if (shards[j].shard_index == s.shard_index)
        return bad(strprintf("duplicates input %zu (same shard_index)", j));
  }
  if (shards.size() < count) {
    std::vector<bool> seen(count, false);
    for (const BakeCheckpoint& s : shards) seen[s.shard_index] = true;
    const size_t missing = std::find(seen.begin(), seen.end(), false) - seen.begin();
    return invalid_argument(strprintf("shard merge: shard %zu of %u is missing (%zu of %u given)",
                                      missing, count, shards.size(), count));
  }
  std::sort(shards.begin(), shards.end(), [](const BakeCheckpoint& a, const BakeCheckpoint& b) {
    return a.shard_index < b.shard_index;
  });
  ShardMerger merger;
  for (size_t i = 0; i < shards.size(); ++i) {
    LUXEL_RETURN_IF_ERROR(merger.add(shards[i], false));  // each checked above
    shards[i] = BakeCheckpoint{};                         // its memory back as the fold goes on
  }
  return merger.finish();
}

// Per texel the fold keeps, in double: mean[4], M2[4], sum w, sum w^2
// (kTexelDoubles), and the sample count; per encoding value four running
// means, and per encoding the weight total. The arithmetic per texel is the
// same, in the same shard order, as a loop over all shards at once.
constexpr size_t kTexelDoubles = 10;

Status ShardMerger::add(const BakeCheckpoint& s) {
  return add(s, true);
}

Status ShardMerger::add(const BakeCheckpoint& s, bool check) {
  const std::string who = strprintf("shard %u of %u", s.shard_index, s.shard_count);
  auto bad = [&](const std::string& why) {
    return invalid_argument(strprintf("%s: %s", who.c_str(), why.c_str()));
  };
  if (s.shard_count == 0 || s.shard_count > 4096) return bad("invalid shard_count");
  if (check) LUXEL_RETURN_IF_ERROR(check_shard(s, who));
  if (added_ == 0) {
    out_ = BakeCheckpoint{};
    out_.fingerprint = s.fingerprint;
    out_.shard_index = 0;
    out_.shard_count = s.shard_count;
    out_.width = s.width;
    out_.height = s.height;
    out_.basis_layout = s.basis_layout;
    texels_ = s.mean.size();
    stride_ = s.basis.empty() ? 0 : s.basis.size() / texels_;
    acc_.assign(texels_ * kTexelDoubles, 0.0);
    spp_.assign(texels_, 0);
    basis_.assign(texels_ * stride_ * 4, 0.0);
    totals_.assign(texels_ * out_.basis_layout.size(), 0.0);
  } else {
    if (s.fingerprint != out_.fingerprint)
      return bad(strprintf("belongs to another bake (fingerprint %s, shard 0 has %s)",
                           s.fingerprint.c_str(), out_.fingerprint.c_str()));
    if (s.shard_count != out_.shard_count)
      return bad(
          strprintf("is one of %u shards, shard 0 one of %u", s.shard_count, out_.shard_count));
    if (s.width != out_.width || s.height != out_.height || s.mean.size() != texels_)
      return bad(strprintf("is a %ux%u lightmap with %zu covered texels, shard 0 %ux%u with %zu",
                           s.width, s.height, s.mean.size(), out_.width, out_.height, texels_));
    if (s.basis_layout != out_.basis_layout || s.basis.size() != texels_ * stride_)
      return bad("has other directional encodings than shard 0");
  }
  if (s.shard_index != added_)
    return bad(
        strprintf("arrives out of order: shard %u is next (shards fold in index order)", added_));
  out_.paths_done += s.paths_done;
  out_.nonfinite += s.nonfinite;
  out_.iteration = std::max(out_.iteration, s.iteration);
  out_.elapsed_s = std::max(out_.elapsed_s, s.elapsed_s);
  // Texels are independent: ranges fold on several threads, each texel's
  // arithmetic unchanged (same bits whatever the thread count).
  auto fold = [&](size_t begin, size_t end) {
    for (size_t t = begin; t < end; ++t) {
      double* a = &acc_[t * kTexelDoubles];  // mean[4], m2[4], w, w2
      const double wb = s.weight[t].x;
      spp_[t] += s.spp[t];
      a[9] += s.weight[t].y;
      if (!(wb > 0)) continue;  // nothing accumulated here
      const double wa = a[8];
      const double w = wa + wb;
      a[8] = w;
      const float* mb = &s.mean[t].x;
      const float* m2b = &s.m2[t].x;
      for (int c = 0; c < 4; ++c) {
        const double d = double{mb[c]} - a[c];
        a[c] += d * (wb / w);
        a[4 + c] += double{m2b[c]} + d * d * (wa * wb / w);
      }
    }
    // Encodings: per encoding, the header's weight sum adds, every other
    // value (running means) is the weight-sum-weighted mean.
    for (size_t t = begin; t < end && stride_ > 0; ++t) {
      size_t offset = t * stride_;
      for (size_t e = 0; e < out_.basis_layout.size(); ++e) {
        const size_t values = 1 + (out_.basis_layout[e] & 0xFFFFu);
        const cl::float4* st = &s.basis[offset];
        const double wb = st[0].x;
        double& total = totals_[t * out_.basis_layout.size() + e];
        if (wb > 0) {
          total += wb;
          const double f = wb / total;
          double* acc = &basis_[offset * 4];
          const float* h = &st[0].x;
          for (int c = 1; c < 4; ++c) acc[c] += (double{h[c]} - acc[c]) * f;
          for (size_t k = 1; k < values; ++k) {
            const float* l = &st[k].x;
            for (int c = 0; c < 4; ++c) acc[k * 4 + c] += (double{l[c]} - acc[k * 4 + c]) * f;
          }
        }
        offset += values;
      }
    }
  };
  constexpr size_t kMinTexelsPerThread = size_t{1} << 16;
  const size_t threads =
      threads_ > 0 ? std::min<size_t>(threads_, std::max<size_t>(texels_, 1))
                   : std::clamp<size_t>(texels_ / kMinTexelsPerThread, 1,
                                        std::max(1u, std::thread::hardware_concurrency()));
  std::vector<std::thread> pool;
  const size_t chunk = (texels_ + threads - 1) / threads;
  for (size_t i = 1; i < threads; ++i)
    pool.emplace_back(fold, std::min(texels_, i * chunk), std::min(texels_, (i + 1) * chunk));
  fold(0, std::min(texels_, chunk));
  for (std::thread& t : pool) t.join();
  ++added_;
  return Status::ok();
}

Result<BakeCheckpoint> ShardMerger::finish() {
  if (added_ == 0) return invalid_argument("shard merge: no shard states given");
  if (added_ < out_.shard_count) {
    const Status missing =
        invalid_argument(strprintf("shard merge: shard %u of %u is missing (%u of %u given)",
                                   added_, out_.shard_count, added_, out_.shard_count));
    reset();
    return missing;
  }
  out_.mean.resize(texels_);
  out_.m2.resize(texels_);
  out_.weight.resize(texels_);
  out_.spp.resize(texels_);
  out_.basis.resize(texels_ * stride_);
  auto f4 = [](const double* v) {
    return cl::float4{static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2]),
                      static_cast<float>(v[3])};
  };
  for (size_t t = 0; t < texels_; ++t) {
    const double* a = &acc_[t * kTexelDoubles];
    if (spp_[t] > 0xFFFFFFFFull)
      return invalid_argument(
          strprintf("shard merge: texel slot %zu would hold %llu samples, past 2^32 - 1", t,
                    static_cast<unsigned long long>(spp_[t])));
    out_.mean[t] = f4(a);
    out_.m2[t] = f4(a + 4);
    out_.weight[t] = {static_cast<float>(a[8]), static_cast<float>(a[9])};
    out_.spp[t] = static_cast<uint32_t>(spp_[t]);
  }
  for (size_t t = 0; t < texels_ && stride_ > 0; ++t) {
    size_t offset = t * stride_;
    for (size_t e = 0; e < out_.basis_layout.size(); ++e) {
      const size_t values = 1 + (out_.basis_layout[e] & 0xFFFFu);
      basis_[offset * 4] = totals_[t * out_.basis_layout.size() + e];
      for (size_t k = 0; k < values; ++k) out_.basis[offset + k] = f4(&basis_[(offset + k) * 4]);
      offset += values;
    }
  }
  BakeCheckpoint merged = std::move(out_);
  merged.shard_count = 1;
  reset();
  return merged;
}

void ShardMerger::reset() {
  out_ = BakeCheckpoint{};
  added_ = 0;
  acc_ = {};
  spp_ = {};
  basis_ = {};
  totals_ = {};
}

Result<BakeResult> finish_merged_bake(const scene::Scene& scene, const BakeSettings& settings,
                                      device::Context& ctx, const BakeCheckpoint& merged,
                                      Termination why, const BakeHooks& hooks) {
  if (merged.shard_count != 1)
    return invalid_argument(
        strprintf("finish_merged_bake: the state is shard %u of %u, not a merge of all shards",
                  merged.shard_index, merged.shard_count));
  if (why == Termination::kCancelled)
    return invalid_argument("finish_merged_bake: a cancelled bake has no result to finish");
  BakeSettings whole = settings;
  whole.shard_index = 0;
  whole.shard_count = 1;
  whole.adaptive = false;
  if (why == Termination::kSamples) {
    if (whole.samples_per_texel == 0)
      return invalid_argument(
          "settings.samples_per_texel: a bake that ended on its sample count needs that count "
          "(0: none)");
    for (size_t t = 0; t < merged.spp.size(); ++t)
      if (merged.spp[t] != whole.samples_per_texel)
        return invalid_argument(strprintf(
            "settings.samples_per_texel: texel slot %zu of the merged state holds %u samples, "
            "the bake asks for %u (a shard missing, stopped early, or from another bake)",
            t, merged.spp[t], whole.samples_per_texel));
  } else {
    if (whole.samples_per_texel > 0)
      for (size_t t = 0; t < merged.spp.size(); ++t)
        if (merged.spp[t] > whole.samples_per_texel)
          return invalid_argument(strprintf(
              "settings.samples_per_texel: texel slot %zu of the merged state holds %u samples, "
              "more than the bake's %u (shards of another bake)",
              t, merged.spp[t], whole.samples_per_texel));
  }
  static const std::atomic<bool> kFinishNow{true};
  BakeHooks h = hooks;
  h.fingerprint = merged.fingerprint;
  h.resume = &merged;
  h.finish_now = &kFinishNow;
  auto result = bake(scene, whole, ctx, h);
  if (result) result.value().termination = why;
  return result;
}

}  // namespace luxel::pipeline
