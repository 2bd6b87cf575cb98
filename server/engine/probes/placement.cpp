#include "probes/placement.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>

#include "accel/bvh_builder.h"
#include "accel/embree_tracer.h"
#include "accel/triangle_soup.h"
#include "common/clock.h"

namespace luxel::probes {

std::string ProbeLayout::describe_json() const {
  nlohmann::json j;
  j["mode"] = choice_name(mode);
  j["count"] = positions.size();
  if (grid) {
    j["grid"] = {
        {"dims", {dims[0], dims[1], dims[2]}},
        {"origin", {origin.x, origin.y, origin.z}},
        {"spacing", spacing},
        {"cells_without_probe", std::count(grid_index.begin(), grid_index.end(), int32_t{-1})}};
  }
  j["inside_detected"] = inside_detected;
  j["moved"] = moved;
  j["flagged_inside"] = flagged_inside;
  j["dropped_far_from_geometry"] = dropped_far;
  j["seconds"] = seconds;
  return j.dump();
}

namespace {

// Classification of one probe position from its test rays.
struct Probe {
  float backface_fraction = 0;
  float nearest_hit = INFINITY;  // any face
  float nearest_back = INFINITY;
  Vec3 back_dir{0, 0, 0};  // direction of the nearest back-face hit
};

class Classifier {
 public:
  static Result<Classifier> create(const scene::Scene& scene, int rays) {
    Classifier c;
    auto soup = accel::build_triangle_soup(scene);
    if (!soup) return soup.status();
    c.soup_ = std::make_unique<accel::TriangleSoup>(std::move(soup.value()));
    if (c.soup_->size() == 0) return c;
    auto bvh = accel::build_bvh(*c.soup_);
    if (!bvh) return bvh.status();
    c.bvh_ = std::make_unique<accel::DeviceBvh>(std::move(bvh.value()));
    auto tracer = accel::EmbreeTracer::create(*c.bvh_);
    if (!tracer) return tracer.status();
    c.tracer_ = std::move(tracer.value());
    // Front faces: cross(v1 - v0, v2 - v0), flipped under mirroring instances.
    c.front_.resize(c.soup_->size());
    for (size_t t = 0; t < c.soup_->size(); ++t) {
      const auto& inst = scene.instances[c.soup_->instance[t]];
      const Vec3 e1 = c.soup_->v(t, 1) - c.soup_->v(t, 0), e2 = c.soup_->v(t, 2) - c.soup_->v(t, 0);
      c.front_[t] = cross(e1, e2) * front_face_sign(inst.object_to_world);
    }
    // Spherical Fibonacci directions (deterministic, near-uniform).
    const double golden = M_PI * (3.0 - std::sqrt(5.0));
    for (int i = 0; i < rays; ++i) {
      const double z = 1.0 - (2.0 * i + 1.0) / rays, r = std::sqrt(std::max(0.0, 1.0 - z * z));
      const double phi = golden * i;
      c.dirs_.push_back(Vec3{float(r * std::cos(phi)), float(r * std::sin(phi)), float(z)});
    }
    return c;
  }
  bool empty() const { return !tracer_; }
  const Bounds3& bounds() const { return soup_->bounds; }

  // In blocks of kClassifyBlock probes, polling `cancel` between them.
  Result<std::vector<Probe>> classify(const std::vector<Vec3>& points,
                                      const CancelToken& cancel) const {
    constexpr size_t kClassifyBlock = 4096;
    if (points.size() <= kClassifyBlock) return classify_block(points);
    std::vector<Probe> out;
    out.reserve(points.size());
    for (size_t at = 0; at < points.size(); at += kClassifyBlock) {
      LUXEL_RETURN_IF_ERROR(check_cancel(cancel, "the probes' classification"));
      const size_t end = std::min(points.size(), at + kClassifyBlock);
      const std::vector<Probe> block =
          classify_block(std::vector<Vec3>(points.begin() + static_cast<ptrdiff_t>(at),
                                           points.begin() + static_cast<ptrdiff_t>(end)));
      out.insert(out.end(), block.begin(), block.end());
    }
    return out;
  }

 private:
  std::vector<Probe> classify_block(const std::vector<Vec3>& points) const {
    std::vector<Probe> out(points.size());
    if (empty()) return out;
    const size_t k = dirs_.size();
    std::vector<cl::LuxRay> rays(points.size() * k);
    for (size_t p = 0; p < points.size(); ++p)
      for (size_t d = 0; d < k; ++d) {
        cl::LuxRay& r = rays[p * k + d];
        r.org_tmin = {points[p].x, points[p].y, points[p].z, 0.0f};
        r.dir_tmax = {dirs_[d].x, dirs_[d].y, dirs_[d].z, INFINITY};
      }
    std::vector<cl::LuxHit> hits(rays.size());
    tracer_->intersect(rays, hits);
    for (size_t p = 0; p < points.size(); ++p) {
      Probe& pr = out[p];
      size_t back = 0;
      for (size_t d = 0; d < k; ++d) {
        const cl::LuxHit& h = hits[p * k + d];
        if (h.prim < 0) continue;
        pr.nearest_hit = std::min(pr.nearest_hit, h.t);
        if (dot(front_[static_cast<size_t>(h.prim)], dirs_[d]) <= 0) continue;  // a front face
        ++back;
        if (h.t < pr.nearest_back) {
          pr.nearest_back = h.t;
          pr.back_dir = dirs_[d];
        }
      }
      pr.backface_fraction = static_cast<float>(back) / static_cast<float>(k);
    }
    return out;
  }

  std::unique_ptr<accel::TriangleSoup> soup_;
  std::unique_ptr<accel::DeviceBvh> bvh_;
  std::unique_ptr<accel::EmbreeTracer> tracer_;
  std::vector<Vec3> front_;
  std::vector<Vec3> dirs_;
};

Status read_file_positions(const PlacementSettings& s, std::vector<Vec3>& out) {
  const std::string where = s.mode == PlacementMode::kNodes
                                ? std::string("settings.probes 'nodes'")
                                : "settings.probes file '" + s.file + "'";
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(s.file_contents);
  } catch (const std::exception& e) {
    return invalid_argument(where + ": not JSON: " + e.what());
  }
  if (j.is_object() && j.contains("probes")) j = j["probes"];
  if (!j.is_array()) return invalid_argument(where + ": expected a list of positions");
  for (size_t i = 0; i < j.size(); ++i) {
    const nlohmann::json& e =
        j[i].is_object() && j[i].contains("position") ? j[i]["position"] : j[i];
    if (!e.is_array() || e.size() != 3 || !e[0].is_number() || !e[1].is_number() ||
        !e[2].is_number())
      return invalid_argument(strprintf("%s: entry %zu is not [x, y, z]", where.c_str(), i));
    const Vec3 p{e[0].get<float>(), e[1].get<float>(), e[2].get<float>()};
    if (!is_finite(p))
      return invalid_argument(strprintf("%s: entry %zu is not finite", where.c_str(), i));
    out.push_back(p);
  }
  if (out.empty()) return invalid_argument(where + ": no positions");
  return Status::ok();
}

// The world bounds of the triangles the classifier traces: the same points
// as accel::build_triangle_soup's bounds, without copying the triangles.
Bounds3 triangle_bounds(const scene::Scene& scene) {
  Bounds3 b;
  for (const scene::Instance& inst : scene.instances) {
    if (inst.mesh < 0 || static_cast<size_t>(inst.mesh) >= scene.meshes.size()) continue;
    const scene::Mesh& mesh = scene.meshes[static_cast<size_t>(inst.mesh)];
    for (uint32_t i : mesh.indices)
      b.extend(transform_point(inst.object_to_world, mesh.positions[i]));
  }
  return b;
}

}  // namespace

Result<PlacementPlan> plan_placement(const scene::Scene& scene, const PlacementSettings& s) {
  PlacementPlan plan;
  if (s.mode == PlacementMode::kFile || s.mode == PlacementMode::kNodes) {
    LUXEL_RETURN_IF_ERROR(read_file_positions(s, plan.positions));
    if (plan.positions.size() > s.max_probes)
      return resource_exhausted(strprintf("settings.probes: %zu probes, at most %zu",
                                          plan.positions.size(), s.max_probes));
    plan.count = plan.positions.size();
    return plan;
  }
  plan.box = s.has_box ? s.box : triangle_bounds(scene);
  if (plan.box.empty())
    return invalid_argument("settings.probes: the scene has no geometry to put a grid over");
  const Vec3 e = plan.box.extent();
  // Counted in doubles first: the float quotient of a tiny spacing or a
  // huge box does not fit an int (and an extent past FLT_MAX is inf).
  double cells = 1;
  for (int a = 0; a < 3; ++a) cells *= std::floor(double(e[a]) / double(s.spacing) + 1e-4) + 1;
  if (!(cells <= double(s.max_probes)))
    return resource_exhausted(strprintf(
        "settings.probes: a grid of spacing %g over this box has %.4g probes, at most %zu "
        "(use a larger spacing or a box)",
        double(s.spacing), cells, s.max_probes));
  plan.grid = true;
  plan.count = 1;
  for (int a = 0; a < 3; ++a) {
    plan.dims[a] = static_cast<int>(std::floor(e[a] / s.spacing + 1e-4f)) + 1;
    plan.count *= static_cast<size_t>(plan.dims[a]);
  }
  if (plan.count > s.max_probes)  // the float rounding of the lattice above
    return resource_exhausted(
        strprintf("settings.probes: a grid of spacing %g over this box has %zu probes, at most "
                  "%zu (use a larger spacing or a box)",
                  double(s.spacing), plan.count, s.max_probes));
  return plan;
}

Result<ProbeLayout> place_probes(const scene::Scene& scene, const PlacementSettings& s,
                                 CancelToken cancel) {
  const auto t0 = std::chrono::steady_clock::now();
  auto planned = plan_placement(scene, s);
  if (!planned) return planned.status();
  PlacementPlan& plan = planned.value();
  auto classifier = Classifier::create(scene, std::max(8, s.test_rays));
  if (!classifier) return classifier.status();
  const Classifier& c = classifier.value();
  ProbeLayout out;
  out.mode = s.mode;
  float cap = s.spacing * 2.0f;
  if (!plan.grid) {
    out.positions = std::move(plan.positions);
    out.flags.assign(out.positions.size(), kProbeUser);
    // User positions have no spacing: the visibility cap is the scene's size.
    const Vec3 e = c.empty() ? Vec3{1, 1, 1} : c.bounds().extent();
    cap = std::max(1e-3f, length(e));
  } else {
    const Bounds3& box = plan.box;
    const Vec3 e = box.extent();
    for (int a = 0; a < 3; ++a) out.dims[a] = plan.dims[a];
    out.grid = true;
    out.spacing = s.spacing;
    // Centred in the box.
    const Vec3 used{(out.dims[0] - 1) * s.spacing, (out.dims[1] - 1) * s.spacing,
                    (out.dims[2] - 1) * s.spacing};
    out.origin = box.lo + (e - used) * 0.5f;
    out.positions.reserve(plan.count);
    for (int k = 0; k < out.dims[2]; ++k)
      for (int j = 0; j < out.dims[1]; ++j)
        for (int i = 0; i < out.dims[0]; ++i)
          out.positions.push_back(out.origin + Vec3{float(i), float(j), float(k)} * s.spacing);
    out.flags.assign(out.positions.size(), 0u);
    out.grid_index.resize(out.positions.size());
    for (size_t i = 0; i < out.positions.size(); ++i) out.grid_index[i] = static_cast<int32_t>(i);
  }

  auto classified = c.classify(out.positions, cancel);
  if (!classified) return classified.status();
  std::vector<Probe> cls = std::move(classified.value());
  const bool adaptive = s.mode == PlacementMode::kAdaptive;
  for (size_t p = 0; p < out.positions.size(); ++p)
    if (cls[p].backface_fraction > s.inside_fraction) ++out.inside_detected;
  if (adaptive) {
    // Relocation: through the nearest back face seen, a small step past it
    // (a tenth of the spacing, at most), up to three times.
    for (int round = 0; round < 3; ++round) {
      std::vector<size_t> todo;
      std::vector<Vec3> moved;
      for (size_t p = 0; p < out.positions.size(); ++p) {
        if (!(cls[p].backface_fraction > s.inside_fraction) || !std::isfinite(cls[p].nearest_back))
          continue;
        const float step = cls[p].nearest_back + std::max(1e-4f, 0.1f * s.spacing);
        todo.push_back(p);
        moved.push_back(out.positions[p] + cls[p].back_dir * step);
      }
      if (todo.empty()) break;
      auto reclassified = c.classify(moved, cancel);
      if (!reclassified) return reclassified.status();
      const std::vector<Probe>& again = reclassified.value();
      for (size_t i = 0; i < todo.size(); ++i) {
        out.positions[todo[i]] = moved[i];
        out.flags[todo[i]] |= kProbeMoved;
        cls[todo[i]] = again[i];
      }
    }
  }
  for (size_t p = 0; p < out.positions.size(); ++p) {
    if (cls[p].backface_fraction > s.inside_fraction) {
      out.flags[p] |= kProbeInside;
      ++out.flagged_inside;
    } else if (out.flags[p] & kProbeMoved) {
      ++out.moved;
    }
  }
  out.max_distance.assign(out.positions.size(), cap);
  if (adaptive) {
    // Keep the probes near geometry (the nearest hit of the test rays).
    const float keep = s.keep_distance > 0 ? s.keep_distance : 1.5f * s.spacing;
    ProbeLayout kept = out;
    kept.positions.clear();
    kept.flags.clear();
    kept.max_distance.clear();
    for (size_t p = 0; p < out.positions.size(); ++p) {
      if (!(cls[p].nearest_hit <= keep)) {
        kept.grid_index[p] = -1;
        ++kept.dropped_far;
        continue;
      }
      kept.grid_index[p] = static_cast<int32_t>(kept.positions.size());
      kept.positions.push_back(out.positions[p]);
      kept.flags.push_back(out.flags[p]);
      kept.max_distance.push_back(out.max_distance[p]);
    }
    out = std::move(kept);
    if (out.positions.empty())
      return invalid_argument(
          "settings.probes: adaptive placement kept no probe (no geometry "
          "within the keep distance of any grid point)");
  }
  out.seconds = seconds_since(t0);
  return out;
}

}  // namespace luxel::probes
