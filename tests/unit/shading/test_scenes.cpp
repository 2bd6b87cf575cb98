#include "test_scenes.h"

#include <OpenImageIO/imageio.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>

#include "common/status.h"

namespace luxel::pipeline::test {

int SceneBuilder::add_emitter(Vec3 radiance, bool double_sided, const std::string& name) {
  scene::Material m;
  m.name = name;
  m.emissive_factor = radiance;
  m.double_sided = double_sided;
  s.materials.push_back(m);
  return static_cast<int>(s.materials.size()) - 1;
}

void SceneBuilder::add_triangles(const std::vector<Vec3>& vertices, int material, const Mat4& xf) {
  scene::Mesh m;
  m.name = "mesh" + std::to_string(s.meshes.size());
  m.positions = vertices;
  m.normals.assign(vertices.size(), Vec3{0, 1, 0});
  m.uv0.assign(vertices.size(), Vec2{});
  m.uv1 = m.uv0;
  for (uint32_t i = 0; i < vertices.size(); ++i) m.indices.push_back(i);
  m.triangle_material.assign(vertices.size() / 3, material);
  s.meshes.push_back(std::move(m));
  scene::Instance inst;
  inst.name = "instance" + std::to_string(s.instances.size());
  inst.mesh = static_cast<int>(s.meshes.size()) - 1;
  inst.object_to_world = xf;
  s.instances.push_back(inst);
}

void SceneBuilder::add_point(Vec3 position, Vec3 color, float intensity, const std::string& name) {
  scene::Light l;
  l.name = name;
  l.type = scene::LightType::kPoint;
  l.position = position;
  l.color = color;
  l.intensity = intensity;
  s.lights.push_back(l);
}

void SceneBuilder::add_spot(Vec3 position, Vec3 direction, Vec3 color, float intensity, float inner,
                            float outer, const std::string& name) {
  add_point(position, color, intensity, name);
  scene::Light& l = s.lights.back();
  l.type = scene::LightType::kSpot;
  l.direction = normalize(direction);
  l.inner_cone_angle = inner;
  l.outer_cone_angle = outer;
}

void SceneBuilder::add_directional(Vec3 direction, Vec3 color, float lux, const std::string& name) {
  add_point({}, color, lux, name);
  scene::Light& l = s.lights.back();
  l.type = scene::LightType::kDirectional;
  l.direction = normalize(direction);
}

accel::TriangleSoup SceneBuilder::soup() const {
  auto soup = accel::build_triangle_soup(s);
  LUXEL_CHECK_MSG(soup.is_ok(), soup.status().to_string().c_str());
  return std::move(soup.value());
}

cl::float4 f4(Vec3 v, float w) {
  return {v.x, v.y, v.z, w};
}
Vec3 xyz(const cl::float4& v) {
  return {v.x, v.y, v.z};
}

TempDir::TempDir() {
  static std::atomic<int> counter{0};
  path_ = (std::filesystem::temp_directory_path() /
           ("luxel-shading-" + std::to_string(getpid()) + "-" + std::to_string(counter++)))
              .string();
  std::filesystem::remove_all(path_);
  std::filesystem::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

bool write_rgb_image(const std::string& path, int width, int height,
                     const std::vector<float>& rgb) {
  auto out = OIIO::ImageOutput::create(path);
  if (!out) return false;
  const OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::FLOAT);
  if (!out->open(path, spec)) return false;
  const bool ok = out->write_image(OIIO::TypeDesc::FLOAT, rgb.data());
  return out->close() && ok;
}

}  // namespace luxel::pipeline::test
