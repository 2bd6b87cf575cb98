// The device decode (Listing 4.2 in kernels/shared/sample_info.h, run by
// kernels/testing/sample_info_probe.cl on the OpenCL device) against the host
// decode, for every valid sample of a packed scene.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "atlas_test_util.h"
#include "device/context.h"
#include "device/program_cache.h"
#include "kernels/shared/sample_info.h"
#include "scene/gltf_import.h"

namespace luxel::atlas::testing {
namespace {

template <typename T>
T expect_ok(Result<T> r, const char* what) {
  EXPECT_TRUE(r.is_ok()) << what << ": " << r.status().to_string();
  if (!r.is_ok()) throw std::runtime_error(what);
  return std::move(r.value());
}

TEST(SampleInfoDevice, ProbeMatchesHostDecode) {
  scene::ImportOptions options;
  options.decode_textures = false;
  auto loaded =
      scene::import_gltf_file(std::string(LUXEL_SCENES_DIR) + "/foliage_instanced.glb", options);
  ASSERT_TRUE(loaded.is_ok()) << loaded.status().to_string();
  const scene::Scene& s = loaded.value();
  AtlasSettings settings;
  settings.resolution = 128;
  const Atlas atlas = expect_atlas(s, settings);
  const SampleInfo info = expect_sample_info(s, atlas);
  ASSERT_GT(info.valid_samples, 0u);

  // Queries: every valid sample of every covered texel.
  std::vector<uint32_t> queries;
  for (uint32_t texel : info.covered_texels) {
    const uint32_t count = cl::lux_sample_info_count(info.words.data(), info.offsets[texel]);
    for (uint32_t rank = 0; rank < count; ++rank) queries.insert(queries.end(), {texel, rank});
  }
  const uint32_t n = static_cast<uint32_t>(queries.size() / 2);
  // Atlas UVs of every world triangle, and each instance's first triangle.
  std::vector<uint32_t> base;
  std::vector<cl::float4> uvs;
  for (uint32_t i = 0; i < s.instances.size(); ++i) {
    base.push_back(static_cast<uint32_t>(uvs.size() / 2));
    const auto& mesh = s.meshes[static_cast<size_t>(s.instances[i].mesh)];
    for (size_t t = 0; t < mesh.triangle_count(); ++t) {
      Vec2 a[3];
      for (int k = 0; k < 3; ++k)
        a[k] = atlas.to_atlas(i, mesh.uv1[mesh.indices[t * 3 + static_cast<size_t>(k)]]);
      uvs.push_back({a[0].x, a[0].y, a[1].x, a[1].y});
      uvs.push_back({a[2].x, a[2].y, 0, 0});
    }
  }

  auto ctx = expect_ok(device::Context::create(), "context");
  auto program = expect_ok(
      ctx->programs().get("testing/sample_info_probe.cl", device::FeatureSet{}), "program");
  auto kernel = expect_ok(program->kernel("sample_info_probe"), "kernel");
  auto offsets_buf = expect_ok(ctx->upload(info.offsets, "sample offsets"), "upload");
  auto words_buf = expect_ok(ctx->upload(info.words, "sample words"), "upload");
  auto queries_buf = expect_ok(ctx->upload(queries, "queries"), "upload");
  auto base_buf = expect_ok(ctx->upload(base, "triangle base"), "upload");
  auto uvs_buf = expect_ok(ctx->upload(uvs, "triangle uvs"), "upload");
  auto decoded_buf = expect_ok(ctx->alloc(n * sizeof(cl::uint4), "decoded"), "alloc");
  auto bary_buf = expect_ok(ctx->alloc(n * sizeof(cl::float4), "barycentrics"), "alloc");
  ASSERT_TRUE(kernel
                  .set_args(offsets_buf, words_buf, queries_buf, base_buf, uvs_buf,
                            static_cast<uint32_t>(atlas.width), static_cast<uint32_t>(atlas.height),
                            n, decoded_buf, bary_buf)
                  .is_ok());
  ASSERT_TRUE(ctx->launch(kernel, n, 0, "sample_info_probe").is_ok());
  std::vector<cl::uint4> decoded(n);
  std::vector<cl::float4> bary(n);
  ASSERT_TRUE(ctx->read(decoded_buf, decoded).is_ok());
  ASSERT_TRUE(ctx->read(bary_buf, bary).is_ok());
  ASSERT_TRUE(ctx->finish().is_ok());

  size_t mismatches = 0;
  double worst_bary = 0;
  for (uint32_t q = 0; q < n; ++q) {
    const uint32_t texel = queries[2 * q], rank = queries[2 * q + 1];
    const SamplePoint p = sample_point(info, texel, rank);
    const cl::uint4 d = decoded[q];
    const bool same = d.x == p.instance && d.y == p.triangle && d.z == p.hammersley_index &&
                      d.w == cl::lux_sample_info_count(info.words.data(), info.offsets[texel]);
    if (!same && ++mismatches <= 5)
      ADD_FAILURE() << "texel " << texel << " rank " << rank << ": device (" << d.x << ", " << d.y
                    << ", " << d.z << ") host (" << p.instance << ", " << p.triangle << ", "
                    << p.hammersley_index << ")";
    // Host run of the same shared barycentric helper.
    const uint32_t world = base[p.instance] + p.triangle;
    const cl::float4 a = uvs[2 * world], b = uvs[2 * world + 1];
    float w[3];
    cl::lux_texel_barycentrics({a.x, a.y}, {a.z, a.w}, {b.x, b.y}, static_cast<float>(atlas.width),
                               static_cast<float>(atlas.height), texel % 128, texel / 128,
                               cl::lux_hammersley64(p.hammersley_index), &w[0], &w[1], &w[2]);
    for (float diff : {bary[q].x - w[0], bary[q].y - w[1], bary[q].z - w[2]})
      worst_bary = std::max(worst_bary, static_cast<double>(std::fabs(diff)));
    EXPECT_NEAR(bary[q].x + bary[q].y + bary[q].z, 1.0f, 1e-5f);
  }
  EXPECT_EQ(mismatches, 0u);
  EXPECT_LT(worst_bary, 1e-5);
  std::printf("%u samples decoded on %s; worst device/host barycentric difference %.3g\n", n,
              ctx->info().device_name.c_str(), worst_bary);
}

}  // namespace
}  // namespace luxel::atlas::testing
