#include "output/seam_stitch.h"

#include <algorithm>
#include <cmath>

namespace luxel::output {

SeamStitcher::SeamStitcher(int width, int height, const std::vector<StitchEdge>& edges,
                           const std::vector<float>& coverage, const SeamStitchOptions& options)
    : width_(width), height_(height), options_(options) {
  for (const StitchEdge& e : edges) {
    const double len = std::max(std::hypot(e.a1.x - e.a0.x, e.a1.y - e.a0.y),
                                std::hypot(e.b1.x - e.b0.x, e.b1.y - e.b0.y));
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
  data_weight_.resize(texels_.size());
  diagonal_.resize(texels_.size());
  for (size_t u = 0; u < texels_.size(); ++u) {
    data_weight_[u] = coverage[texels_[u]] > 0.0f ? 1.0 : options_.padding_weight;
    diagonal_[u] = data_weight_[u];
  }
  for (const Row& r : rows_)
    for (int k = 0; k < r.n; ++k)
      diagonal_[r.unknown[k]] += options_.seam_weight * r.weight[k] * r.weight[k];
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

void SeamStitcher::apply(const std::vector<double>& x, std::vector<double>& y) const {
  for (size_t u = 0; u < x.size(); ++u) y[u] = data_weight_[u] * x[u];
  for (const Row& r : rows_) {
    const double v = options_.seam_weight * row_value(r, x);
    for (int k = 0; k < r.n; ++k) y[r.unknown[k]] += r.weight[k] * v;
  }
}

int SeamStitcher::stitch(std::vector<float>& pixels, int stride, int first, int count) const {
  const size_t n = texels_.size();
  if (n == 0) return 0;
  std::vector<double> x0(n), b(n), delta(n), r(n), z(n), p(n), q(n);
  int most = 0;
  for (int c = first; c < first + count; ++c) {
    for (size_t u = 0; u < n; ++u) x0[u] = pixels[size_t(texels_[u]) * size_t(stride) + c];
    // For delta = x - x0: (D + lambda R^T R) delta = -lambda R^T R x0.
    std::fill(b.begin(), b.end(), 0.0);
    for (const Row& row : rows_) {
      const double v = -options_.seam_weight * row_value(row, x0);
      for (int k = 0; k < row.n; ++k) b[row.unknown[k]] += row.weight[k] * v;
    }
    double bb = 0;
    for (double v : b) bb += v * v;
    std::fill(delta.begin(), delta.end(), 0.0);
    if (!(bb > 0) || !std::isfinite(bb)) continue;  // already continuous, or non-finite input
    r = b;
    double rz = 0;
    for (size_t u = 0; u < n; ++u) {
      z[u] = r[u] / diagonal_[u];
      rz += r[u] * z[u];
    }
    p = z;
    const double stop = options_.tolerance * options_.tolerance * bb;
    int it = 0;
    for (; it < options_.max_iterations; ++it) {
      apply(p, q);
      double pq = 0;
      for (size_t u = 0; u < n; ++u) pq += p[u] * q[u];
      if (!(pq > 0)) break;
      const double alpha = rz / pq;
      double rr = 0;
      for (size_t u = 0; u < n; ++u) {
        delta[u] += alpha * p[u];
        r[u] -= alpha * q[u];
        rr += r[u] * r[u];
      }
      if (rr <= stop) {
        ++it;
        break;
      }
      double rz_next = 0;
      for (size_t u = 0; u < n; ++u) {
        z[u] = r[u] / diagonal_[u];
        rz_next += r[u] * z[u];
      }
      const double beta = rz_next / rz;
      rz = rz_next;
      for (size_t u = 0; u < n; ++u) p[u] = z[u] + beta * p[u];
    }
    most = std::max(most, it);
    for (size_t u = 0; u < n; ++u)
      pixels[size_t(texels_[u]) * size_t(stride) + c] = static_cast<float>(x0[u] + delta[u]);
  }
  return most;
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
  const double floor = 1e-3 * std::sqrt(mean_sq / double(rows_.size())) + 1e-30;
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
