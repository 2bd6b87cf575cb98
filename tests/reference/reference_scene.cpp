#include "reference/reference_scene.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "accel/triangle_soup.h"

namespace luxel::reference {
namespace {

double triangle_area(Vec3 a, Vec3 b, Vec3 c) {
  const double ux = double{b.x} - a.x, uy = double{b.y} - a.y, uz = double{b.z} - a.z;
  const double vx = double{c.x} - a.x, vy = double{c.y} - a.y, vz = double{c.z} - a.z;
  const double cx = uy * vz - uz * vy, cy = uz * vx - ux * vz, cz = ux * vy - uy * vx;
  return 0.5 * std::sqrt(cx * cx + cy * cy + cz * cz);
}

// What the reference does not model is refused rather than approximated.
Status check_material(const scene::Material& m) {
  auto refuse = [&](const char* why) {
    return invalid_argument(
        strprintf("material '%s': %s; the reference tracer models only untextured opaque "
                  "glTF metallic-roughness materials (ior 1.5, roughness >= %.2g)",
                  m.name.c_str(), why, ReferenceScene::kMinRoughness));
  };
  if (m.roughness_factor < ReferenceScene::kMinRoughness) return refuse("roughness too low");
  if (m.ior != 1.5f) return refuse("KHR_materials_ior other than 1.5");
  if (m.specular_factor != 1.0f || m.specular_color_factor.x != 1.0f ||
      m.specular_color_factor.y != 1.0f || m.specular_color_factor.z != 1.0f)
    return refuse("has KHR_materials_specular");
  if (m.base_color_texture.texture >= 0 || m.metallic_roughness_texture.texture >= 0 ||
      m.emissive_texture.texture >= 0 || m.normal_texture.texture >= 0)
    return refuse("has a texture");
  if (m.alpha_mode != scene::AlphaMode::kOpaque) return refuse("alpha mode is not OPAQUE");
  return Status::ok();
}

// Lambert in the reference (and the engine) when every used material is one.
bool is_rough_dielectric(const scene::Material& m) {
  return m.metallic_factor <= 0.0f && m.roughness_factor >= 1.0f;
}

ReferenceMaterial to_reference(const scene::Material& m) {
  ReferenceMaterial r;
  r.albedo = {std::max(0.0f, m.base_color_factor.x), std::max(0.0f, m.base_color_factor.y),
              std::max(0.0f, m.base_color_factor.z)};
  const double s = m.emissive_strength;
  r.emissive = m.is_emissive();
  if (r.emissive)
    r.emission = Rgb{m.emissive_factor.x, m.emissive_factor.y, m.emissive_factor.z} * s;
  r.double_sided = m.double_sided;
  r.metallic = std::clamp(double{m.metallic_factor}, 0.0, 1.0);
  r.roughness = std::clamp(double{m.roughness_factor}, 0.0, 1.0);
  return r;
}

}  // namespace

Result<std::unique_ptr<ReferenceScene>> ReferenceScene::create(const scene::Scene& scene) {
  if (!scene.lights.empty())
    return invalid_argument(
        strprintf("light '%s': punctual lights are not modelled by the "
                  "reference tracer (emissive triangles only)",
                  scene.lights.front().name.c_str()));
  auto soup_or = accel::build_triangle_soup(scene);
  if (!soup_or) return soup_or.status();
  const accel::TriangleSoup& soup = soup_or.value();

  std::unique_ptr<ReferenceScene> rs(new ReferenceScene());
  std::vector<bool> used(scene.materials.size(), false);
  rs->instance_first_.assign(scene.instances.size(), std::numeric_limits<uint32_t>::max());
  rs->triangles_.resize(soup.size());
  for (size_t t = 0; t < soup.size(); ++t) {
    const uint32_t inst = soup.instance[t];
    const scene::Instance& instance = scene.instances[inst];
    const scene::Mesh& mesh = scene.meshes[static_cast<size_t>(instance.mesh)];
    const size_t mt = soup.mesh_triangle[t];
    if (rs->instance_first_[inst] == std::numeric_limits<uint32_t>::max())
      rs->instance_first_[inst] = static_cast<uint32_t>(t - mt);
    Triangle& tri = rs->triangles_[t];
    for (int k = 0; k < 3; ++k) {
      tri.p[k] = soup.v(t, k);
      const uint32_t vi = mesh.indices[mt * 3 + static_cast<size_t>(k)];
      tri.n[k] = normalize(transform_normal(instance.object_to_world, mesh.normals[vi]));
    }
    // glTF 2.0 §3.7.4: under a mirroring instance the front face is the
    // clockwise one (front_face_sign).
    tri.ng_front = normalize(cross(tri.p[1] - tri.p[0], tri.p[2] - tri.p[0])) *
                   front_face_sign(instance.object_to_world);
    tri.area = triangle_area(tri.p[0], tri.p[1], tri.p[2]);
    tri.material = mesh.triangle_material[mt];
    used[static_cast<size_t>(tri.material)] = true;
  }
  // world_triangle() relies on the soup's order: instance by instance, each
  // in mesh triangle order.
  for (size_t t = 0; t < soup.size(); ++t)
    if (rs->instance_first_[soup.instance[t]] + soup.mesh_triangle[t] != t)
      return internal_error(strprintf("triangle soup entry %zu is out of instance order", t));
  for (size_t m = 0; m < scene.materials.size(); ++m) {
    if (!used[m]) continue;
    LUXEL_RETURN_IF_ERROR(check_material(scene.materials[m]));
    if (!is_rough_dielectric(scene.materials[m])) rs->uses_ggx_ = true;
  }
  for (size_t m = 0; m < scene.materials.size(); ++m) {
    ReferenceMaterial r = to_reference(scene.materials[m]);
    if (rs->uses_ggx_ && used[m]) {
      r.ggx = true;
      r.albedo_table = GgxAlbedo::get(r.roughness);
    }
    rs->materials_.push_back(std::move(r));
  }

  // Emitters, chosen by area: every point of the emitting surface equally.
  for (size_t t = 0; t < rs->triangles_.size(); ++t) {
    const Triangle& tri = rs->triangles_[t];
    if (!rs->materials_[static_cast<size_t>(tri.material)].emissive || !(tri.area > 0)) continue;
    rs->emitters_.push_back(static_cast<uint32_t>(t));
    rs->emissive_area_ += tri.area;
    rs->emitter_cdf_.push_back(rs->emissive_area_);
  }
  for (double& c : rs->emitter_cdf_) c /= rs->emissive_area_;
  if (!rs->emitter_cdf_.empty()) rs->emitter_cdf_.back() = 1.0;

  // A ray offset of 1e-5 of the scene's size: far above float rounding at
  // that scale, far below any feature of a test scene.
  const Vec3 lo = soup.bounds.lo, hi = soup.bounds.hi;
  float scale = 1e-3f;
  for (int a = 0; a < 3; ++a) scale = std::max({scale, std::abs(lo[a]), std::abs(hi[a])});
  rs->offset_scale_ = 1e-5f * scale;

  rs->device_ = rtcNewDevice(nullptr);
  if (!rs->device_) return unavailable("reference tracer: rtcNewDevice failed");
  rs->rtc_scene_ = rtcNewScene(rs->device_);
  rtcSetSceneFlags(rs->rtc_scene_, RTC_SCENE_FLAG_ROBUST);
  const size_t n = soup.size();
  if (n > 0) {
    RTCGeometry geom = rtcNewGeometry(rs->device_, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), n * 3));
    auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), n));
    if (!v || !idx) {
      rtcReleaseGeometry(geom);
      return resource_exhausted(strprintf("reference tracer: Embree buffers for %zu triangles", n));
    }
    for (size_t i = 0; i < n * 3; ++i) {
      v[i * 3 + 0] = soup.vertices[i].x;
      v[i * 3 + 1] = soup.vertices[i].y;
      v[i * 3 + 2] = soup.vertices[i].z;
      idx[i] = static_cast<unsigned>(i);
    }
    rtcCommitGeometry(geom);
    rtcAttachGeometry(rs->rtc_scene_, geom);  // geometry id 0: primID = world triangle
    rtcReleaseGeometry(geom);
  }
  rtcCommitScene(rs->rtc_scene_);
  if (const RTCError err = rtcGetDeviceError(rs->device_); err != RTC_ERROR_NONE)
    return internal_error(
        strprintf("reference tracer: Embree scene build failed (error %d)", static_cast<int>(err)));
  return rs;
}

ReferenceScene::~ReferenceScene() {
  if (rtc_scene_) rtcReleaseScene(rtc_scene_);
  if (device_) rtcReleaseDevice(device_);
}

uint32_t ReferenceScene::world_triangle(uint32_t instance, uint32_t mesh_triangle) const {
  LUXEL_CHECK(instance < instance_first_.size());
  const uint32_t t = instance_first_[instance] + mesh_triangle;
  LUXEL_CHECK(t < triangles_.size());
  return t;
}

SurfacePoint ReferenceScene::surface_at(uint32_t triangle, double w0, double w1, double w2) const {
  const Triangle& t = triangles_[triangle];
  SurfacePoint s;
  s.triangle = triangle;
  s.material = t.material;
  auto mix = [&](const Vec3* v) {
    return Vec3{static_cast<float>(w0 * v[0].x + w1 * v[1].x + w2 * v[2].x),
                static_cast<float>(w0 * v[0].y + w1 * v[1].y + w2 * v[2].y),
                static_cast<float>(w0 * v[0].z + w1 * v[1].z + w2 * v[2].z)};
  };
  s.p = mix(t.p);
  s.ng_front = t.ng_front;
  const Vec3 n = mix(t.n);
  s.ns = length(n) > 1e-20f ? normalize(n) : t.ng_front;
  // The geometric normal is taken on the shading normal's side: the vertex
  // normals say which side of the surface is "outside".
  s.ng = dot(s.ns, t.ng_front) < 0 ? t.ng_front * -1.0f : t.ng_front;
  return s;
}

bool ReferenceScene::intersect(Vec3 org, Vec3 dir, SurfacePoint* hit) const {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRayHit rh{};
  rh.ray.org_x = org.x;
  rh.ray.org_y = org.y;
  rh.ray.org_z = org.z;
  rh.ray.dir_x = dir.x;
  rh.ray.dir_y = dir.y;
  rh.ray.dir_z = dir.z;
  rh.ray.tnear = 0.0f;
  rh.ray.tfar = std::numeric_limits<float>::infinity();
  rh.ray.mask = 0xFFFFFFFFu;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(rtc_scene_, &ctx, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
  // Embree's (u, v) weight vertices 1 and 2.
  const double u = rh.hit.u, v = rh.hit.v;
  *hit = surface_at(rh.hit.primID, 1.0 - u - v, u, v);
  return true;
}

bool ReferenceScene::occluded(Vec3 org, Vec3 dir, float tmax) const {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRay ray{};
  ray.org_x = org.x;
  ray.org_y = org.y;
  ray.org_z = org.z;
  ray.dir_x = dir.x;
  ray.dir_y = dir.y;
  ray.dir_z = dir.z;
  ray.tnear = 0.0f;
  ray.tfar = tmax;
  ray.mask = 0xFFFFFFFFu;
  rtcOccluded1(rtc_scene_, &ctx, &ray);
  return ray.tfar < 0.0f;  // Embree sets tfar = -inf on a hit
}

Vec3 ReferenceScene::offset_origin(const SurfacePoint& s, Vec3 dir) const {
  const Vec3 n = dot(dir, s.ng) >= 0 ? s.ng : s.ng * -1.0f;
  return s.p + n * offset_scale_;
}

EmitterSample ReferenceScene::sample_emitter(double u_select, double u1, double u2) const {
  LUXEL_CHECK(!emitters_.empty());
  const size_t i = static_cast<size_t>(
      std::upper_bound(emitter_cdf_.begin(), emitter_cdf_.end(), u_select) - emitter_cdf_.begin());
  const uint32_t t = emitters_[std::min(i, emitters_.size() - 1)];
  // Uniform point on the triangle (the square-root warp).
  const double su = std::sqrt(u1);
  const SurfacePoint s = surface_at(t, 1.0 - su, u2 * su, (1.0 - u2) * su);
  EmitterSample e;
  e.p = s.p;
  e.ng_front = s.ng_front;
  e.triangle = t;
  e.material = s.material;
  e.pdf_area = 1.0 / emissive_area_;
  return e;
}

}  // namespace luxel::reference
