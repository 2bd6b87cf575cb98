#include "uv/segment.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <queue>

namespace luxel::uv {
namespace {

struct Candidate {
  int64_t cost;  // quantised, see kCostQuantum
  uint32_t tri;
  bool operator>(const Candidate& o) const { return cost != o.cost ? cost > o.cost : tri > o.tri; }
};

// The axis of a cone turned by `angle` towards unit vector n (spherical
// interpolation along the great circle).
DVec3 turn_towards(DVec3 axis, DVec3 n, double angle) {
  const DVec3 perp = n - axis * dot(axis, n);
  const double len = std::sqrt(dot(perp, perp));
  if (len < 1e-12) return axis;
  return normalize(axis * std::cos(angle) + perp * (std::sin(angle) / len));
}

// Symmetric meshes have many equal areas and costs that rounding of the
// positions makes unequal in the last bits, differently at each scale. Areas
// (relative to the largest) and costs are compared after rounding to these
// quanta, ties go to the lower triangle index, so a mesh and its scaled copy
// are segmented alike unless a value falls within rounding noise of a quantum
// boundary.
constexpr double kAreaQuantum = 1.0 / 4096;
constexpr double kCostQuantum = 1.0 / 65536;

}  // namespace

std::vector<std::vector<uint32_t>> grow_charts(const Topology& topo, const ChartOptions& options) {
  const size_t n = topo.valid.size();
  std::vector<uint32_t> order;
  for (uint32_t t = 0; t < n; ++t)
    if (topo.valid[t]) order.push_back(t);
  double max_area = 0;
  for (uint32_t t : order) max_area = std::max(max_area, topo.area[t]);
  std::vector<int64_t> area_key(n, 0);
  for (uint32_t t : order) area_key[t] = std::llround(topo.area[t] / max_area / kAreaQuantum);
  std::stable_sort(order.begin(), order.end(),
                   [&](uint32_t a, uint32_t b) { return area_key[a] > area_key[b]; });

  const double max_half = options.max_cone_half_angle_deg * std::numbers::pi / 180.0;
  std::vector<int32_t> chart_of(n, -1);
  std::vector<std::vector<uint32_t>> charts;
  for (uint32_t seed : order) {
    if (chart_of[seed] >= 0) continue;
    const int32_t c = static_cast<int32_t>(charts.size());
    std::vector<uint32_t> members;
    DVec3 axis = topo.normal[seed];
    double half = 0, area = 0, perimeter = 0;
    std::priority_queue<Candidate, std::vector<Candidate>, std::greater<>> heap;
    auto add = [&](uint32_t t) {
      chart_of[t] = c;
      members.push_back(t);
      area += topo.area[t];
      for (int e = 0; e < 3; ++e) {
        const int32_t nb = topo.neighbour[3 * t + e];
        perimeter += (nb >= 0 && chart_of[nb] == c) ? -topo.edge_length[3 * t + e]
                                                    : topo.edge_length[3 * t + e];
      }
      const double compact = perimeter * perimeter / area;
      for (int e = 0; e < 3; ++e) {
        const int32_t nb = topo.neighbour[3 * t + e];
        if (nb < 0 || chart_of[nb] >= 0) continue;
        double shared = 0, free = 0;
        for (int f = 0; f < 3; ++f) {
          const int32_t m = topo.neighbour[3 * nb + f];
          (m >= 0 && chart_of[m] == c ? shared : free) += topo.edge_length[3 * nb + f];
        }
        const double p2 = perimeter + free - shared;
        const double compact2 = p2 * p2 / (area + topo.area[nb]);
        const double cost = (1.0 - dot(axis, topo.normal[nb])) +
                            options.compactness_weight * (compact2 / compact - 1.0);
        heap.push({std::llround(cost / kCostQuantum), static_cast<uint32_t>(nb)});
      }
    };
    add(seed);
    while (!heap.empty() && members.size() < options.max_chart_triangles) {
      const uint32_t t = heap.top().tri;
      heap.pop();
      if (chart_of[t] >= 0) continue;
      const double angle = std::acos(std::clamp(dot(axis, topo.normal[t]), -1.0, 1.0));
      if (angle > half) {
        const double merged = 0.5 * (half + angle);
        if (merged > max_half) continue;
        axis = turn_towards(axis, topo.normal[t], merged - half);
        half = merged;
      }
      add(t);
    }
    charts.push_back(std::move(members));
  }
  return charts;
}

std::vector<std::vector<uint32_t>> connected_parts(const Topology& topo,
                                                   std::vector<uint32_t> tris) {
  std::sort(tris.begin(), tris.end());
  std::vector<uint8_t> seen(tris.size(), 0);
  auto slot = [&](int32_t t) -> int64_t {
    auto it = std::lower_bound(tris.begin(), tris.end(), static_cast<uint32_t>(t));
    return (it != tris.end() && *it == static_cast<uint32_t>(t)) ? it - tris.begin() : -1;
  };
  std::vector<std::vector<uint32_t>> parts;
  for (size_t s = 0; s < tris.size(); ++s) {
    if (seen[s]) continue;
    std::vector<uint32_t> part{tris[s]};
    seen[s] = 1;
    for (size_t k = 0; k < part.size(); ++k)
      for (int e = 0; e < 3; ++e) {
        const int32_t nb = topo.neighbour[3 * part[k] + e];
        if (nb < 0) continue;
        const int64_t i = slot(nb);
        if (i >= 0 && !seen[i]) {
          seen[i] = 1;
          part.push_back(static_cast<uint32_t>(nb));
        }
      }
    std::sort(part.begin(), part.end());
    parts.push_back(std::move(part));
  }
  return parts;
}

std::vector<std::vector<uint32_t>> split_chart(const Topology& topo,
                                               const std::vector<uint32_t>& tris) {
  DVec3 mean{};
  for (uint32_t t : tris) mean = mean + topo.centroid[t];
  mean = mean * (1.0 / static_cast<double>(tris.size()));
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (uint32_t t : tris) {
    const DVec3 d = topo.centroid[t] - mean;
    const Eigen::Vector3d v(d.x, d.y, d.z);
    cov += v * v.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  const Eigen::Vector3d axis = eig.eigenvectors().col(2);  // largest eigenvalue
  std::vector<std::pair<double, uint32_t>> keyed;
  keyed.reserve(tris.size());
  for (uint32_t t : tris) {
    const DVec3 d = topo.centroid[t] - mean;
    keyed.push_back({d.x * axis.x() + d.y * axis.y() + d.z * axis.z(), t});
  }
  std::sort(keyed.begin(), keyed.end());
  const size_t half = keyed.size() / 2;
  std::vector<uint32_t> lo, hi;
  for (size_t i = 0; i < keyed.size(); ++i) (i < half ? lo : hi).push_back(keyed[i].second);
  auto parts = connected_parts(topo, std::move(lo));
  for (auto& p : connected_parts(topo, std::move(hi))) parts.push_back(std::move(p));
  return parts;
}

}  // namespace luxel::uv
