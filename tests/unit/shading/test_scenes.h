// Small hand-made scenes, random numbers and image files for the shading
// tests (no glTF import involved).
#pragma once

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "accel/triangle_soup.h"
#include "common/math.h"
#include "kernels/shared/compat.h"
#include "scene/scene.h"

namespace luxel::pipeline::test {

// A scene with one mesh + instance per add_triangles call.
struct SceneBuilder {
  scene::Scene s;
  SceneBuilder() { s.materials.push_back(scene::Material{}); }  // material 0: not emissive

  // Returns the material index.
  int add_emitter(Vec3 radiance, bool double_sided = false, const std::string& name = "emitter");
  // Triangles from 3 vertices each, all with `material`, under `xf`.
  void add_triangles(const std::vector<Vec3>& vertices, int material, const Mat4& xf = {});
  void add_point(Vec3 position, Vec3 color, float intensity, const std::string& name = "point");
  void add_spot(Vec3 position, Vec3 direction, Vec3 color, float intensity, float inner,
                float outer, const std::string& name = "spot");
  void add_directional(Vec3 direction, Vec3 color, float lux,
                       const std::string& name = "directional");

  accel::TriangleSoup soup() const;  // aborts the test binary on failure (a test bug)
};

// Deterministic uniform numbers in [0, 1) (24-bit, so never 1.0f).
class Rng {
 public:
  explicit Rng(uint64_t seed) : gen_(seed) {}
  float uniform() { return static_cast<float>(gen_() >> 40) * 0x1p-24f; }
  cl::float4 uniform4() { return {uniform(), uniform(), uniform(), uniform()}; }

 private:
  std::mt19937_64 gen_;
};

cl::float4 f4(Vec3 v, float w = 0);
Vec3 xyz(const cl::float4& v);

// A fresh folder under the temp directory, removed on destruction.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string file(const std::string& name) const { return path_ + "/" + name; }

 private:
  std::string path_;
};

// Writes float RGB (width * height * 3) with OpenImageIO (format by
// extension: .hdr, .exr). Returns false on failure.
bool write_rgb_image(const std::string& path, int width, int height, const std::vector<float>& rgb);

}  // namespace luxel::pipeline::test
