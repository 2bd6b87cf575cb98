#include "output/seam_stitch.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <thread>

namespace luxel::output {

SeamStitcher::SeamStitcher(int width, int height, const std::vector<StitchEdge>& edges,
                           const std::vector<float>& coverage, const SeamStitchOptions& options)
    : width_(width), height_(height), options_(options) {
  for (const StitchEdge& e : edges) {
    const double len_a = std::hypot(e.a1.x - e.a0.x, e.a1.y - e.a0.y);
    const double len_b = std::hypot(e.b1.x - e.b0.x, e.b1.y - e.b0.y);
    if (!std::isfinite(len_a) || !std::isfinite(len_b)) continue;  // no place to fetch from
    if (std::min(len_a, len_b) < options_.min_edge_texels) {
      ++short_edges_;
      continue;
    }
    if (e.chart_texels < options_.min_chart_texels) {
      ++narrow_chart_edges_;
      continue;
    }
    const double len = std::max(len_a, len_b);
    const double want = std::ceil(options_.samples_per_texel * len);
    const int n = std::isfinite(want) ? static_cast<int>(std::clamp(want, 2.0, 1e6)) : 2;
    for (int k = 0; k < n; ++k) {
      const float t = (float(k) + 0.5f) / float(n);
      Row row;
      add_sample(row, {e.a0.x + t * (e.a1.x - e.a0.x), e.a0.y + t * (e.a1.y - e.a0.y)}, 1.0);
      add_sample(row, {e.b0.x + t * (e.b1.x - e.b0.x), e.b0.y + t * (e.b1.y - e.b0.y)}, -1.0);
      rows_.push_back(row);
    }
  }
  unknown_index_.clear();
  split_components();
  data_weight_.resize(texels_.size());
  covered_.resize(texels_.size());
  diagonal_.resize(texels_.size());
  for (size_t u = 0; u < texels_.size(); ++u) {
    covered_[u] = coverage[texels_[u]] > 0.0f;
    data_weight_[u] = covered_[u] ? 1.0 : options_.padding_weight;
    diagonal_[u] = data_weight_[u];
  }
  for (const Row& r : rows_)
    for (int k = 0; k < r.n; ++k)
      diagonal_[r.unknown[k]] += options_.seam_weight * r.weight[k] * r.weight[k];
}

// Renumbers unknowns and rows so that every connected component (unknowns
// linked through a row) is one contiguous range of each: the components
// are independent systems, each solved by its own CG run, so a small seam
// stops after the few iterations it needs instead of the largest one's.
void SeamStitcher::split_components() {
  const size_t n = texels_.size();
  std::vector<uint32_t> parent(n);
  for (size_t u = 0; u < n; ++u) parent[u] = static_cast<uint32_t>(u);
  auto find = [&](uint32_t u) {
    while (parent[u] != u) u = parent[u] = parent[parent[u]];
    return u;
  };
  for (const Row& r : rows_)
    for (int k = 1; k < r.n; ++k) {
      const uint32_t a = find(r.unknown[0]), b = find(r.unknown[k]);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);  // root: the smallest unknown
    }
  // Components in the order of their smallest unknown; unknowns within one
  // in their old order.
  std::vector<uint32_t> root(n), first_of(n, UINT32_MAX), slot(n);
  std::vector<uint32_t> order;
  for (size_t u = 0; u < n; ++u) {
    root[u] = find(static_cast<uint32_t>(u));
    if (first_of[root[u]] == UINT32_MAX) {
      first_of[root[u]] = static_cast<uint32_t>(order.size());
      order.push_back(root[u]);
    }
  }
  std::vector<uint32_t> size(order.size(), 0), begin(order.size() + 1, 0);
  for (size_t u = 0; u < n; ++u) ++size[first_of[root[u]]];
  for (size_t c = 0; c < order.size(); ++c) begin[c + 1] = begin[c] + size[c];
  std::vector<uint32_t> next(begin.begin(), begin.end() - 1);
  std::vector<uint32_t> texels(n);
  for (size_t u = 0; u < n; ++u) {
    slot[u] = next[first_of[root[u]]]++;
    texels[slot[u]] = texels_[u];
  }
  texels_ = std::move(texels);
  for (Row& r : rows_)
    for (int k = 0; k < r.n; ++k) r.unknown[k] = slot[r.unknown[k]];
  // Rows by component (in their old order within one), then the ranges.
  std::vector<std::vector<Row>> by_component(order.size());
  for (const Row& r : rows_) {
    const uint32_t u = r.unknown[0];
    const size_t c = std::upper_bound(begin.begin(), begin.end(), u) - begin.begin() - 1;
    by_component[c].push_back(r);
  }
  rows_.clear();
  components_.clear();
  for (size_t c = 0; c < order.size(); ++c) {
    Component comp;
    comp.unknown_begin = begin[c];
    comp.unknown_end = begin[c + 1];
    comp.row_begin = static_cast<uint32_t>(rows_.size());
    rows_.insert(rows_.end(), by_component[c].begin(), by_component[c].end());
    comp.row_end = static_cast<uint32_t>(rows_.size());
    components_.push_back(comp);
  }
}

uint32_t SeamStitcher::unknown_of(uint32_t texel) {
  auto [it, added] = unknown_index_.try_emplace(texel, static_cast<uint32_t>(texels_.size()));
  if (added) texels_.push_back(texel);
  return it->second;
}

// The 2x2 texels a bilinear fetch at p reads, with their weights times
// `sign`, merged into the row (a texel read by both sides, or twice after
// clamping, appears once).
void SeamStitcher::add_sample(Row& row, Vec2 p, double sign) {
  const double sx = double(p.x) - 0.5, sy = double(p.y) - 0.5;
  const double fx0 = std::floor(sx), fy0 = std::floor(sy);
  const double fx = sx - fx0, fy = sy - fy0;
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 2; ++i) {
      const double w = sign * (i ? fx : 1 - fx) * (j ? fy : 1 - fy);
      const int x = static_cast<int>(std::clamp(fx0 + i, 0.0, double(width_ - 1)));
      const int y = static_cast<int>(std::clamp(fy0 + j, 0.0, double(height_ - 1)));
      const uint32_t u = unknown_of(static_cast<uint32_t>(y) * uint32_t(width_) + uint32_t(x));
      int k = 0;
      while (k < row.n && row.unknown[k] != u) ++k;
      if (k == row.n) {
        row.unknown[row.n] = u;
        row.weight[row.n++] = 0;
      }
      row.weight[k] += w;
    }
}

double SeamStitcher::row_value(const Row& row, const std::vector<double>& x) const {
  double v = 0;
  for (int k = 0; k < row.n; ++k) v += row.weight[k] * x[row.unknown[k]];
  return v;
}

void SeamStitcher::apply(const Component& c, const Weights& w, const std::vector<double>& x,
                         std::vector<double>& y) const {
  for (uint32_t u = c.unknown_begin; u < c.unknown_end; ++u) y[u] = w.data[u] * x[u];
  for (uint32_t i = c.row_begin; i < c.row_end; ++i) {
    if (!w.on(i)) continue;
    const Row& r = rows_[i];
    const double v = options_.seam_weight * row_value(r, x);
    for (int k = 0; k < r.n; ++k) y[r.unknown[k]] += r.weight[k] * v;
  }
}

// A sample point's gap against its noise: the standard deviation of
// bilerp_A - bilerp_B is sqrt(sum_k w_k^2 sigma_k^2) over its texels, sigma_k
// = rel_error_k times the texel's RMS over the channels (rel_error is that of
// the texel mean's luminance). Padding has no estimate of its own (dilation
// averages neighbours, possibly of another chart); it is given the largest
// sigma of the row's covered texels, which errs towards stitching.
std::vector<uint8_t> SeamStitcher::noise_rows(const std::vector<float>& pixels, int stride,
                                              int first, int count,
                                              const std::vector<float>& rel_error,
                                              size_t& structural) const {
  std::vector<uint8_t> on(rows_.size(), 1);
  if (rel_error.empty()) return on;
  auto rms = [&](uint32_t u) { return texel_rms(pixels, stride, first, count, u); };
  for (size_t i = 0; i < rows_.size(); ++i) {
    const Row& row = rows_[i];
    double sigma[8] = {}, pad_sigma = 0;
    for (int k = 0; k < row.n; ++k) {
      const uint32_t u = row.unknown[k];
      const double rel = rel_error[texels_[u]];
      if (!covered_[u]) continue;
      sigma[k] = std::isfinite(rel) ? std::max(0.0, rel) * rms(u)
                                    : std::numeric_limits<double>::infinity();
      pad_sigma = std::max(pad_sigma, sigma[k]);
    }
    double var = 0, gap = 0, mean = 0;
    for (int k = 0; k < row.n; ++k) {
      const double s = covered_[row.unknown[k]] ? sigma[k] : pad_sigma;
      var += row.weight[k] * row.weight[k] * s * s;
    }
    for (int ch = first; ch < first + count; ++ch) {
      double g = 0, m = 0;
      for (int k = 0; k < row.n; ++k) {
        const double x = pixels[size_t(texels_[row.unknown[k]]) * size_t(stride) + ch];
        g += row.weight[k] * x;
        m += 0.5 * std::abs(row.weight[k]) * x;
      }
      gap += g * g;
      mean += m * m;
    }
    gap = std::sqrt(gap / count);
    mean = std::sqrt(mean / count);
    if (gap > options_.structure_sigmas * std::sqrt(var) &&
        gap > options_.structure_rel_gap * mean) {
      on[i] = 0;
      ++structural;
    }
  }
  return on;
}

int SeamStitcher::stitch(std::vector<float>& pixels, int stride, int first, int count,
                         bool clamp_negative, const std::vector<float>& rel_error,
                         size_t* structural) const {
  const size_t n = texels_.size();
  if (n == 0 || count <= 0) return 0;
  // The rows the solve keeps, and the normal matrix's diagonal without the
  // others.
  size_t left_out = 0;
  Weights plain{
      data_weight_, diagonal_, {}, noise_rows(pixels, stride, first, count, rel_error, left_out)};
  if (structural) *structural += left_out;
  if (left_out > 0) {
    plain.diagonal = data_weight_;
    for (size_t i = 0; i < rows_.size(); ++i)
      if (plain.row_on[i])
        for (int k = 0; k < rows_[i].n; ++k)
          plain.diagonal[rows_[i].unknown[k]] +=
              options_.seam_weight * rows_[i].weight[k] * rows_[i].weight[k];
  } else {
    plain.row_on.clear();
  }
  // Channels are independent solves of the same matrix: one thread per
  // group of channels. Each writes only its own channels, and a channel's
  // arithmetic does not depend on the split, so the result is the same
  // for any thread count.
  const int threads =
      std::clamp(static_cast<int>(std::thread::hardware_concurrency()), 1, std::min(count, 16));
  // How far each unknown may move (the same for every channel): covered
  // texels by max_move_sigmas standard errors (move_reach), padding freely
  // but for the range below.
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::vector<double> reach(n, kInf);
  if (!rel_error.empty()) reach = move_reach(pixels, stride, first, count, rel_error, plain);
  std::vector<int> most(threads, 0);
  auto work = [&](int t) {
    std::vector<double> x0(n), lo(n), hi(n), delta(n), r(n), z(n), p(n), q(n);
    for (int ch = first + t; ch < first + count; ch += threads) {
      for (size_t u = 0; u < n; ++u) {
        x0[u] = pixels[size_t(texels_[u]) * size_t(stride) + ch];
        lo[u] = x0[u] - reach[u];
        hi[u] = x0[u] + reach[u];
      }
      if (!rel_error.empty()) padding_range(x0, lo, hi);
      bool bounded = false;
      for (size_t u = 0; u < n; ++u) {
        if (clamp_negative) lo[u] = std::max(lo[u], 0.0);
        hi[u] = std::max(hi[u], lo[u]);  // a negative baked value is raised to 0
        bounded = bounded || lo[u] > -kInf || hi[u] < kInf;
      }
      std::fill(delta.begin(), delta.end(), 0.0);
      for (const Component& c : components_)
        most[t] = std::max(most[t], solve(c, plain, x0, delta, r, z, p, q));
      if (bounded) most[t] = std::max(most[t], pin_to_bounds(plain, x0, lo, hi, delta, r, z, p, q));
      for (size_t u = 0; u < n; ++u)
        pixels[size_t(texels_[u]) * size_t(stride) + ch] =
            static_cast<float>(std::clamp(x0[u] + delta[u], lo[u], hi[u]));
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(work, t);
  work(0);
  for (auto& th : pool) th.join();
  return *std::max_element(most.begin(), most.end());
}

// How far each covered texel may move: max_move_sigmas standard errors of
// its mean (infinite without an estimate). The standard error of a texel is
// its relative error times its RMS over the stitched channels; with
// pool_move_sigmas it is pooled (RMS) over the covered texels that the
// texel's kept sample points read, both sides of the seam. At a few samples
// per texel a texel's own estimate follows its value: one that drew a bright
// path has a wide spread, one that drew none almost none. Own errors then let
// the bright side of a seam fall further than the dark side rises, and the
// stitch darkens the seams of a noisy map on average.
std::vector<double> SeamStitcher::move_reach(const std::vector<float>& pixels, int stride,
                                             int first, int count,
                                             const std::vector<float>& rel_error,
                                             const Weights& w) const {
  const size_t n = texels_.size();
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::vector<double> var(n, -1.0);  // own standard error squared; < 0: none
  for (size_t u = 0; u < n; ++u) {
    const double rel = rel_error[texels_[u]];
    if (!covered_[u] || !std::isfinite(rel)) continue;
    const double sigma = std::max(0.0, rel) * texel_rms(pixels, stride, first, count, u);
    if (std::isfinite(sigma)) var[u] = sigma * sigma;
  }
  std::vector<double> pooled(var);
  if (options_.pool_move_sigmas) {
    std::vector<double> sum(n, 0.0);
    std::vector<uint32_t> rows(n, 0);
    for (size_t i = 0; i < rows_.size(); ++i) {
      if (!w.on(static_cast<uint32_t>(i))) continue;
      const Row& row = rows_[i];
      double s = 0;
      int m = 0;
      for (int k = 0; k < row.n; ++k)
        if (var[row.unknown[k]] >= 0) {
          s += var[row.unknown[k]];
          ++m;
        }
      if (m == 0) continue;
      for (int k = 0; k < row.n; ++k) {
        sum[row.unknown[k]] += s / m;
        ++rows[row.unknown[k]];
      }
    }
    for (size_t u = 0; u < n; ++u)
      if (var[u] >= 0 && rows[u] > 0) pooled[u] = sum[u] / rows[u];
  }
  std::vector<double> reach(n, kInf);
  for (size_t u = 0; u < n; ++u)
    if (pooled[u] >= 0) reach[u] = options_.max_move_sigmas * std::sqrt(pooled[u]);
  return reach;
}

double SeamStitcher::texel_rms(const std::vector<float>& pixels, int stride, int first, int count,
                               uint32_t u) const {
  double sq = 0;
  for (int ch = first; ch < first + count; ++ch) {
    const double v = pixels[size_t(texels_[u]) * size_t(stride) + ch];
    sq += v * v;
  }
  return std::sqrt(sq / count);
}

// Padding stays within the range of the baked texels its (kept) sample
// points read on either side: with the covered texels held near their
// values, the solve would otherwise swing padding far past both sides to
// close a gap (and charts one texel apart share that padding).
void SeamStitcher::padding_range(const std::vector<double>& x0, std::vector<double>& lo,
                                 std::vector<double>& hi) const {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::vector<double> pad_lo(x0), pad_hi(x0);
  for (const Row& row : rows_) {
    double rlo = kInf, rhi = -kInf;
    for (int k = 0; k < row.n; ++k)
      if (covered_[row.unknown[k]]) {
        rlo = std::min(rlo, x0[row.unknown[k]]);
        rhi = std::max(rhi, x0[row.unknown[k]]);
      }
    for (int k = 0; k < row.n; ++k) {
      const uint32_t u = row.unknown[k];
      pad_lo[u] = std::min(pad_lo[u], rlo);
      pad_hi[u] = std::max(pad_hi[u], rhi);
    }
  }
  for (size_t u = 0; u < x0.size(); ++u)
    if (!covered_[u]) {
      lo[u] = std::max(lo[u], pad_lo[u]);
      hi[u] = std::min(hi[u], pad_hi[u]);
    }
}

// A small active-set step towards the bounded least-squares solution:
// texels the solve took outside [lo, hi] (below 0, or further from their
// baked value than their noise allows) are pinned to the bound they crossed
// (a data weight of 1e6 towards it) and their components solved again, up
// to 3 rounds; what is still outside after that is clamped by the caller.
int SeamStitcher::pin_to_bounds(const Weights& base, const std::vector<double>& x0,
                                const std::vector<double>& lo, const std::vector<double>& hi,
                                std::vector<double>& delta, std::vector<double>& r,
                                std::vector<double>& z, std::vector<double>& p,
                                std::vector<double>& q) const {
  constexpr double kPin = 1e6;
  Weights w{base.data, base.diagonal, std::vector<double>(texels_.size(), 0.0), base.row_on};
  int most = 0;
  for (int round = 0; round < 3; ++round) {
    bool any = false;
    for (const Component& c : components_) {
      bool pinned = false;
      for (uint32_t u = c.unknown_begin; u < c.unknown_end; ++u) {
        const double v = x0[u] + delta[u];
        if (w.data[u] >= kPin || (v >= lo[u] && v <= hi[u])) continue;
        w.diagonal[u] += kPin - w.data[u];
        w.data[u] = kPin;
        w.target_shift[u] = (v < lo[u] ? lo[u] : hi[u]) - x0[u];  // t - x0, t the bound
        pinned = true;
      }
      if (!pinned) continue;
      any = true;
      for (uint32_t u = c.unknown_begin; u < c.unknown_end; ++u) delta[u] = 0;
      most = std::max(most, solve(c, w, x0, delta, r, z, p, q));
    }
    if (!any) break;
  }
  return most;
}

// Preconditioned CG on one component for delta = x - x0:
// (D + lambda R^T R) delta = D (t - x0) - lambda R^T R x0, from delta = 0
// (t = x0 but for pinned texels).
int SeamStitcher::solve(const Component& c, const Weights& w, const std::vector<double>& x0,
                        std::vector<double>& delta, std::vector<double>& r, std::vector<double>& z,
                        std::vector<double>& p, std::vector<double>& q) const {
  const uint32_t u0 = c.unknown_begin, u1 = c.unknown_end;
  for (uint32_t u = u0; u < u1; ++u)
    r[u] = w.target_shift.empty() ? 0 : w.data[u] * w.target_shift[u];
  for (uint32_t i = c.row_begin; i < c.row_end; ++i) {
    if (!w.on(i)) continue;
    const Row& row = rows_[i];
    const double v = -options_.seam_weight * row_value(row, x0);
    for (int k = 0; k < row.n; ++k) r[row.unknown[k]] += row.weight[k] * v;
  }
  double bb = 0, rz = 0;
  for (uint32_t u = u0; u < u1; ++u) {
    bb += r[u] * r[u];
    z[u] = r[u] / w.diagonal[u];
    rz += r[u] * z[u];
    p[u] = z[u];
  }
  if (!(bb > 0) || !std::isfinite(bb)) return 0;  // already continuous, or non-finite input
  const double stop = options_.tolerance * options_.tolerance * bb;
  int it = 0;
  while (it < options_.max_iterations) {
    ++it;
    apply(c, w, p, q);
    double pq = 0;
    for (uint32_t u = u0; u < u1; ++u) pq += p[u] * q[u];
    if (!(pq > 0)) break;
    const double alpha = rz / pq;
    double rr = 0;
    for (uint32_t u = u0; u < u1; ++u) {
      delta[u] += alpha * p[u];
      r[u] -= alpha * q[u];
      rr += r[u] * r[u];
    }
    if (rr <= stop) break;
    double rz_next = 0;
    for (uint32_t u = u0; u < u1; ++u) {
      z[u] = r[u] / w.diagonal[u];
      rz_next += r[u] * z[u];
    }
    const double beta = rz_next / rz;
    rz = rz_next;
    for (uint32_t u = u0; u < u1; ++u) p[u] = z[u] + beta * p[u];
  }
  return it;
}

SeamDiscontinuity SeamStitcher::measure(const std::vector<float>& pixels, int stride, int first,
                                        int count) const {
  SeamDiscontinuity d;
  d.points = rows_.size();
  if (rows_.empty() || count <= 0) return d;
  // Per point and channel: the difference is the row itself; the mean of
  // the two sides is half the row with every weight made positive.
  std::vector<double> diff(rows_.size()), mean(rows_.size());
  double mean_sq = 0;
  for (size_t i = 0; i < rows_.size(); ++i) {
    const Row& row = rows_[i];
    double dd = 0, mm = 0;
    for (int c = first; c < first + count; ++c) {
      double v = 0, m = 0;
      for (int k = 0; k < row.n; ++k) {
        const double x = pixels[size_t(texels_[row.unknown[k]]) * size_t(stride) + c];
        v += row.weight[k] * x;
        m += 0.5 * std::abs(row.weight[k]) * x;
      }
      dd += v * v;
      mm += m * m;
    }
    diff[i] = std::sqrt(dd / count);
    mean[i] = std::sqrt(mm / count);
    mean_sq += mean[i] * mean[i];
  }
  const double floor = 1e-2 * std::sqrt(mean_sq / double(rows_.size())) + 1e-30;
  double sa = 0, sr = 0;
  for (size_t i = 0; i < rows_.size(); ++i) {
    const double rel = diff[i] / std::max(mean[i], floor);
    sa += diff[i] * diff[i];
    sr += rel * rel;
    d.max_abs = std::max(d.max_abs, diff[i]);
    d.max_rel = std::max(d.max_rel, rel);
  }
  d.rms_abs = std::sqrt(sa / double(rows_.size()));
  d.rms_rel = std::sqrt(sr / double(rows_.size()));
  return d;
}

}  // namespace luxel::output
