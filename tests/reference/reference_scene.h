// The scene as the CPU reference tracer sees it: world triangles (the engine's
// triangle soup order, so (instance, mesh triangle) maps to the same world
// triangle), their shading data, an Embree scene for ray queries, and an
// area-weighted table of emissive triangles for next-event estimation.
//
// Tests only. Written independently of the bake kernels: nothing here
// includes kernels/ code. Only what the reference models is accepted (see
// ReferenceScene::create); anything else is an INVALID_ARGUMENT that names
// the material or light, so a test never compares against a model that
// silently differs from the engine's.
#pragma once

#include <embree3/rtcore.h>

#include <cstdint>
#include <memory>
#include <vector>

#include "common/math.h"
#include "common/status.h"
#include "reference/reference_bsdf.h"
#include "reference/rgb.h"
#include "scene/scene.h"

namespace luxel::reference {

// A glTF metallic-roughness material with optional emission. In a scene
// whose materials are all rough dielectrics (metallic 0, roughness 1) every
// material is Lambertian (f = albedo / pi), as the engine leaves the GGX
// layer out of such scenes (docs/accuracy.md, "Material model"); otherwise
// every material is the glTF BRDF of reference_bsdf.h (`ggx`).
struct ReferenceMaterial {
  Rgb albedo;    // baseColorFactor.rgb
  Rgb emission;  // emissiveFactor * emissive_strength (W/(m^2 sr))
  bool emissive = false;
  bool double_sided = false;
  bool ggx = false;  // shaded by the glTF BRDF (else Lambert)
  double metallic = 0, roughness = 1;
  std::shared_ptr<const GgxAlbedo> albedo_table;  // E for `roughness` when ggx

  // The BRDF of a `ggx` material under `model`.
  GgxBrdf brdf(BrdfModel model) const {
    return {albedo, metallic, roughness, albedo_table.get(), model};
  }
};

// A point on a world triangle with its frame.
struct SurfacePoint {
  Vec3 p;                 // world position
  Vec3 ng;                // unit geometric normal, on the side of ns
  Vec3 ns;                // unit interpolated shading normal
  Vec3 ng_front;          // unit geometric normal of the front face (emitting side)
  uint32_t triangle = 0;  // world triangle
  int material = 0;
};

// One point sampled on the emitters, uniformly by area over all of them.
struct EmitterSample {
  Vec3 p;
  Vec3 ng_front;
  uint32_t triangle = 0;
  int material = 0;
  double pdf_area = 0;  // 1 / total emissive area
};

class ReferenceScene {
 public:
  // Fails with INVALID_ARGUMENT for what the reference does not model:
  // punctual lights, textures, alpha-masked materials, KHR_materials_ior
  // other than 1.5, KHR_materials_specular, roughness below kMinRoughness
  // (its sampling is not built for near-mirror lobes).
  static constexpr double kMinRoughness = 0.2;
  static Result<std::unique_ptr<ReferenceScene>> create(const scene::Scene& scene);
  ~ReferenceScene();
  ReferenceScene(const ReferenceScene&) = delete;
  ReferenceScene& operator=(const ReferenceScene&) = delete;

  size_t triangle_count() const { return triangles_.size(); }
  // World triangle of `mesh_triangle` of `instance` (checked against the soup).
  uint32_t world_triangle(uint32_t instance, uint32_t mesh_triangle) const;
  // Barycentric weights w of vertices 0, 1, 2 (sum 1).
  SurfacePoint surface_at(uint32_t triangle, double w0, double w1, double w2) const;
  const ReferenceMaterial& material(int index) const {
    return materials_[static_cast<size_t>(index)];
  }

  // Closest hit of the ray org + t dir, t > 0. False on a miss.
  bool intersect(Vec3 org, Vec3 dir, SurfacePoint* hit) const;
  // True when something blocks org + t dir for t in (0, tmax).
  bool occluded(Vec3 org, Vec3 dir, float tmax) const;
  // Origin moved off the surface to the side `dir` leaves from, so a ray
  // cannot hit the surface it starts on (a relative offset: the reference
  // needs no tighter bound than the scale of its test scenes).
  Vec3 offset_origin(const SurfacePoint& s, Vec3 dir) const;

  bool has_emitters() const { return !emitters_.empty(); }
  // Some material is shaded by the glTF BRDF (then all are).
  bool uses_ggx() const { return uses_ggx_; }
  double emissive_area() const { return emissive_area_; }
  // u_select, u1, u2 uniform in [0, 1).
  EmitterSample sample_emitter(double u_select, double u1, double u2) const;

 private:
  struct Triangle {
    Vec3 p[3];
    Vec3 n[3];      // world vertex normals
    Vec3 ng_front;  // unit; the winding's, reversed under a mirroring instance
    double area = 0;
    int material = 0;
  };

  ReferenceScene() = default;

  std::vector<Triangle> triangles_;
  std::vector<ReferenceMaterial> materials_;
  std::vector<uint32_t> instance_first_;  // first world triangle of each instance
  std::vector<uint32_t> emitters_;        // emissive world triangles
  std::vector<double> emitter_cdf_;       // running area / total, last = 1
  double emissive_area_ = 0;
  bool uses_ggx_ = false;
  float offset_scale_ = 0;  // absolute ray offset
  RTCDevice device_ = nullptr;
  RTCScene rtc_scene_ = nullptr;
};

}  // namespace luxel::reference
