// The resource estimate at submit (bake/resource_estimate.h): closed
// forms for the lightmap size from texel_density, the batch against the
// device's largest allocation and the budget, the per-path bytes against
// BakeBuffers' own allocation (so the estimate and the bake's memory plan
// cannot drift apart), and the estimate against real bakes' peak device
// bytes.
#include "bake/resource_estimate.h"

#include <gtest/gtest.h>

#include <cmath>

#include "bake/bake.h"
#include "bake/bake_buffers.h"
#include "bake/bake_setup.h"
#include "bake/lightmap_layout.h"
#include "bake/primitives/radix_sort.h"
#include "device/context.h"
#include "support/test_scenes.h"

namespace luxel {
namespace {

using pipeline::DeviceLimits;

constexpr uint64_t kGiB = uint64_t{1} << 30;

pipeline::BakeSettings plane_settings() {
  pipeline::BakeSettings s;
  s.atlas.resolution = 32;
  s.samples_per_texel = 16;
  s.max_bounces = 1;
  return s;
}

bool mentions(const Status& st, const std::string& text) {
  return st.message().find(text) != std::string::npos;
}

// open_plane is 2 x 2: 4 square units. At density d the lightmap has at least
// 4 d^2 texels; --max-resolution R with the file's UVs allows R^2, and past
// it the layout lowers the density (atlas.h), so the estimate is capped there
// instead of refusing.
TEST(ResourceEstimate, TexelDensityAgainstMaxResolutionIsAClosedForm) {
  const scene::Scene scene = testing::open_plane();
  pipeline::BakeSettings s = plane_settings();
  s.uv = pipeline::UvMode::kExisting;
  s.atlas.resolution = 0;
  s.atlas.max_resolution = 512;
  const DeviceLimits device{16 * kGiB, 4 * kGiB};

  s.atlas.texel_density = 1e30f;
  auto huge = pipeline::estimate_bake_resources(scene, s, device);
  ASSERT_TRUE(huge) << huge.status().to_string();
  EXPECT_EQ(huge->min_texels, 512u * 512u);
  EXPECT_EQ(huge->max_texels, 512u * 512u);

  // Just past and just within 512^2 = 4 d^2, i.e. d = 256.
  s.atlas.texel_density = 256 * 1.01f;
  auto past = pipeline::estimate_bake_resources(scene, s, device);
  ASSERT_TRUE(past) << past.status().to_string();
  EXPECT_EQ(past->min_texels, 512u * 512u);
  s.atlas.texel_density = 256 * 0.99f;
  auto fits = pipeline::estimate_bake_resources(scene, s, device);
  ASSERT_TRUE(fits) << fits.status().to_string();
  EXPECT_NEAR(fits->surface_area, 4.0, 1e-9);
  EXPECT_EQ(fits->min_texels, static_cast<uint64_t>(4.0 * std::pow(256 * 0.99f, 2)));
  // A lower bound: the layout the bake makes holds at least as many texels.
  auto layout = pipeline::lay_out_lightmap(scene, s);
  ASSERT_TRUE(layout) << layout.status().to_string();
  EXPECT_GE(uint64_t(layout->atlas.width) * uint64_t(layout->atlas.height), fits->min_texels);
  EXPECT_TRUE(layout->atlas.warnings.empty());
  // Past the page the layout holds the page, at a lower density, and says so.
  s.atlas.texel_density = 256 * 1.01f;
  auto lowered = pipeline::lay_out_lightmap(scene, s);
  ASSERT_TRUE(lowered) << lowered.status().to_string();
  EXPECT_EQ(lowered->atlas.width, 512);
  EXPECT_LT(lowered->atlas.texels_per_unit, 256 * 1.01);
  ASSERT_EQ(lowered->atlas.warnings.size(), 1u);
  EXPECT_TRUE(lowered->atlas.warnings[0].find("texel density lowered from 258.56") !=
              std::string::npos)
      << lowered->atlas.warnings[0];

  // Generated UVs may use 64 pages of 512^2.
  s.uv = pipeline::UvMode::kGenerate;
  s.atlas.texel_density = 256 * 1.01f;
  auto paged = pipeline::estimate_bake_resources(scene, s, device);
  ASSERT_TRUE(paged) << paged.status().to_string();
  EXPECT_EQ(paged->max_texels, 64u * 512u * 512u);
}

// 2^26 paths: the paths buffer alone is 2^26 x 112 = 7516192768 bytes.
TEST(ResourceEstimate, BatchPastTheLargestAllocationNamesTheBytes) {
  const scene::Scene scene = testing::open_plane();
  pipeline::BakeSettings s = plane_settings();
  s.samples_per_texel = 0;
  s.time_budget_s = 10;
  s.paths_per_iteration = 1u << 26;
  auto st = pipeline::estimate_bake_resources(scene, s, DeviceLimits{64 * kGiB, 1 * kGiB});
  ASSERT_FALSE(st);
  EXPECT_EQ(st.status().code(), StatusCode::kResourceExhausted);
  EXPECT_TRUE(mentions(st.status(), "settings.paths_per_iteration")) << st.status().message();
  EXPECT_TRUE(mentions(st.status(), "7516192768 bytes")) << st.status().message();
  EXPECT_TRUE(mentions(st.status(), "1073741824 bytes")) << st.status().message();
  EXPECT_TRUE(mentions(st.status(), "at most 9586980 paths")) << st.status().message();

  // Within the allocation but past the default budget (4 GiB): 2^26 x 240.
  auto budget = pipeline::estimate_bake_resources(scene, s, DeviceLimits{64 * kGiB, 16 * kGiB});
  ASSERT_FALSE(budget);
  EXPECT_TRUE(mentions(budget.status(), "16106127360 bytes")) << budget.status().message();
  EXPECT_TRUE(mentions(budget.status(), "4294967296")) << budget.status().message();

  // The device's iteration cap (iteration_stops.h): 2 compute units trace
  // 2^18 paths an iteration, 512 trace 2^26.
  auto capped = pipeline::estimate_bake_resources(scene, s, DeviceLimits{64 * kGiB, 1 * kGiB, 2});
  ASSERT_TRUE(capped) << capped.status().to_string();
  EXPECT_EQ(capped->batch_paths, 1u << 18);
  EXPECT_EQ(capped->path_bytes, (1u << 18) * 240u);
  EXPECT_FALSE(pipeline::estimate_bake_resources(scene, s, DeviceLimits{64 * kGiB, 1 * kGiB, 512}));

  // The samples rule trims the batch: 16 spp x 32^2 texels = 16384 paths.
  s.samples_per_texel = 16;
  auto trimmed = pipeline::estimate_bake_resources(scene, s, DeviceLimits{64 * kGiB, 1 * kGiB});
  ASSERT_TRUE(trimmed) << trimmed.status().to_string();
  EXPECT_EQ(trimmed->batch_paths, 16384u);
}

// paths_per_iteration 0 (auto): 2^18 paths on CPUs; on GPUs 2^22, halved
// while the path state would take more than half the budget or one buffer
// would pass the largest allocation, never below 2^18; a given value wins.
TEST(ResourceEstimate, AutomaticBatchFollowsTheDevice) {
  pipeline::BakeSettings s;
  ASSERT_EQ(s.paths_per_iteration, 0u);
  const pipeline::PathStateBytes bytes = pipeline::path_state_bytes(false);
  ASSERT_EQ(bytes.per_path, 240u);
  const DeviceLimits cpu{64 * kGiB, 16 * kGiB, 2, false};
  EXPECT_EQ(pipeline::batch_paths_request(s, cpu, bytes, 4 * kGiB), 1u << 18);
  DeviceLimits gpu{140 * kGiB, 35 * kGiB, 132, true};
  // 2^22 x 240 B = 960 MiB, within half of 4 GiB.
  EXPECT_EQ(pipeline::batch_paths_request(s, gpu, bytes, 4 * kGiB), 1u << 22);
  // Half of 1 GiB holds 2^21 x 240 B = 480 MiB, not 960 MiB.
  EXPECT_EQ(pipeline::batch_paths_request(s, gpu, bytes, 1 * kGiB), 1u << 21);
  // The largest buffer of 2^20 paths is exactly the largest allocation.
  gpu.max_alloc_bytes = (uint64_t{1} << 20) * bytes.largest;
  EXPECT_EQ(pipeline::batch_paths_request(s, gpu, bytes, 4 * kGiB), 1u << 20);
  // Never below the CPU batch, however small the budget (the memory plan
  // then refuses or tiles as for any batch).
  EXPECT_EQ(pipeline::batch_paths_request(s, gpu, bytes, 1 << 20), 1u << 18);
  s.paths_per_iteration = 4096;
  EXPECT_EQ(pipeline::batch_paths_request(s, gpu, bytes, 4 * kGiB), 4096u);

  // The estimate uses it: a time-bounded bake on the GPU gets 2^22 paths.
  const scene::Scene scene = testing::open_plane();
  pipeline::BakeSettings t = plane_settings();
  t.samples_per_texel = 0;
  t.time_budget_s = 10;
  auto e =
      pipeline::estimate_bake_resources(scene, t, DeviceLimits{140 * kGiB, 35 * kGiB, 132, true});
  ASSERT_TRUE(e) << e.status().to_string();
  EXPECT_EQ(e->batch_paths, 1u << 22);
  auto c =
      pipeline::estimate_bake_resources(scene, t, DeviceLimits{64 * kGiB, 16 * kGiB, 2, false});
  ASSERT_TRUE(c) << c.status().to_string();
  EXPECT_EQ(c->batch_paths, 1u << 18);
}

// The Gaussian filter cannot tile its per-texel state: at density 2048 the
// plane has 4 x 2048^2 = 16.8 M texels, at least half of them covered, x 57
// bytes = 478 MB against a 256 MiB budget. The box filter tiles it; with a
// resolution the covered texels are not known before the layout, so the
// bake's memory plan decides.
TEST(ResourceEstimate, GaussianFilterStateThatCannotBeTiledIsRefused) {
  const scene::Scene scene = testing::open_plane();
  pipeline::BakeSettings s = plane_settings();
  s.atlas.resolution = 0;
  s.atlas.texel_density = 2048;
  s.atlas.max_resolution = 8192;
  s.device_memory_budget_mib = 256;
  s.filter = pipeline::Filter::kGaussian;
  const DeviceLimits device{16 * kGiB, 4 * kGiB, 2};
  auto gaussian = pipeline::estimate_bake_resources(scene, s, device);
  ASSERT_FALSE(gaussian);
  EXPECT_EQ(gaussian.status().code(), StatusCode::kResourceExhausted);
  EXPECT_TRUE(mentions(gaussian.status(), "settings.filter")) << gaussian.status().message();
  // 57 bytes of texel state, 5 more with adaptive sampling's weight and 16
  // more with the radiance cache's mean.
  const std::string bytes =
      strprintf("x %d bytes", 57 + (s.adaptive ? 5 : 0) + (s.radiance_cache ? 16 : 0));
  EXPECT_TRUE(mentions(gaussian.status(), "least 8388608 covered texels " + bytes))
      << gaussian.status().message();
  s.filter = pipeline::Filter::kBox;
  EXPECT_TRUE(pipeline::estimate_bake_resources(scene, s, device));
  s.filter = pipeline::Filter::kGaussian;
  s.atlas.texel_density = 0;
  s.atlas.resolution = 4096;
  EXPECT_TRUE(pipeline::estimate_bake_resources(scene, s, device));
}

// The per-path bytes are what BakeBuffers and the radix sort allocate per
// path slot (a buffer added to one and not the other fails here).
TEST(ResourceEstimate, PerPathBytesMatchTheBakeBuffers) {
  auto ctx = device::Context::create();
  ASSERT_TRUE(ctx) << ctx.status().to_string();
  const scene::Scene scene = testing::furnace_box(0.5f, 0.25f);
  for (bool encodings : {false, true}) {
    pipeline::BakeSettings s = plane_settings();
    if (encodings) s.encodings.names = {"sh2"};
    auto layout = pipeline::lay_out_lightmap(scene, s);
    ASSERT_TRUE(layout);
    auto setup = pipeline::prepare_bake(*layout->scene, layout->atlas, s, *ctx.value());
    ASSERT_TRUE(setup) << setup.status().to_string();
    pipeline::BakeSetup& b = setup.value();
    const size_t c1 = 1 << 12, c2 = 1 << 16;
    b.capacity = c1;
    auto f1 = pipeline::BakeBuffers::fixed_bytes(*ctx.value(), *layout->scene, b, s);
    b.capacity = c2;
    auto f2 = pipeline::BakeBuffers::fixed_bytes(*ctx.value(), *layout->scene, b, s);
    ASSERT_TRUE(f1 && f2);
    auto sort1 = pipeline::RadixSort::create(*ctx.value(), c1);
    auto sort2 = pipeline::RadixSort::create(*ctx.value(), c2);
    ASSERT_TRUE(sort1 && sort2);
    const pipeline::PathStateBytes per = pipeline::path_state_bytes(encodings);
    const size_t scratch = 8;  // the sort's keys and values per path
    EXPECT_EQ(f2.value() - f1.value(), (c2 - c1) * (per.per_path - scratch)) << encodings;
    const size_t sort_delta = sort2.value()->device_bytes() - sort1.value()->device_bytes();
    EXPECT_GE(sort_delta, (c2 - c1) * scratch);
    EXPECT_LT(sort_delta, (c2 - c1) * (scratch + 1));  // + the histogram, small
    EXPECT_EQ(pipeline::texel_state_bytes(b.plan.bytes_per_texel(),
                                          b.features.has(device::Feature::ADAPTIVE),
                                          b.features.has(device::Feature::RADIANCE_CACHE),
                                          b.features.has(device::Feature::GUIDING)),
              pipeline::BakeBuffers::per_slot_bytes(b));
  }
}

// Estimate against the bakes' measured peak_device_bytes, on scenes with the
// whole atlas (plane), six walls (furnace) and directional encodings.
// Tolerance: within 25 % of the peak, the figure the scene estimate (BVH and
// soup per triangle, textures) is good for; the Embree intersector keeps
// its BVH in host memory, which makes the estimate the larger one.
TEST(ResourceEstimate, EstimateIsWithinAQuarterOfTheBakesPeak) {
  auto ctx = device::Context::create();
  ASSERT_TRUE(ctx) << ctx.status().to_string();
  const DeviceLimits device = DeviceLimits::of(ctx.value()->info());
  struct Case {
    const char* name;
    scene::Scene scene;
    std::vector<std::string> encodings;
  };
  std::vector<Case> cases;
  cases.push_back({"plane", testing::open_plane(), {}});
  cases.push_back({"furnace", testing::furnace_box(0.5f, 0.25f), {}});
  cases.push_back({"furnace sh2", testing::furnace_box(0.5f, 0.25f), {"sh2", "sg6"}});
  for (const Case& c : cases) {
    pipeline::BakeSettings s = plane_settings();
    s.atlas.resolution = 64;
    s.samples_per_texel = 4;
    s.paths_per_iteration = 1 << 16;
    s.encodings.names = c.encodings;
    auto e = pipeline::estimate_bake_resources(c.scene, s, device);
    ASSERT_TRUE(e) << e.status().to_string();
    auto r = pipeline::bake(c.scene, s, *ctx.value());
    ASSERT_TRUE(r) << r.status().to_string();
    const double estimate = static_cast<double>(e->device_bytes(r->covered_texels));
    const double peak = static_cast<double>(r->peak_device_bytes);
    std::printf("%-12s estimate %.0f bytes, peak %.0f bytes (%+.1f %%)\n", c.name, estimate, peak,
                100 * (estimate / peak - 1));
    EXPECT_NEAR(estimate / peak, 1.0, 0.25) << c.name;
  }
}

// The bake's own memory plan refuses a batch past the budget with the same
// check and wording as the estimate.
TEST(ResourceEstimate, BakeAndEstimateRefuseTheSameBatch) {
  auto ctx = device::Context::create();
  ASSERT_TRUE(ctx) << ctx.status().to_string();
  const scene::Scene scene = testing::open_plane();
  pipeline::BakeSettings s = plane_settings();
  s.samples_per_texel = 0;
  s.time_budget_s = 10;
  s.paths_per_iteration = 1 << 16;  // 15.7 MB of path state
  s.device_memory_budget_mib = 8;   // 8 MiB
  auto e = pipeline::estimate_bake_resources(scene, s, DeviceLimits::of(ctx.value()->info()));
  auto r = pipeline::bake(scene, s, *ctx.value());
  ASSERT_FALSE(e);
  ASSERT_FALSE(r);
  EXPECT_EQ(e.status().code(), StatusCode::kResourceExhausted);
  EXPECT_EQ(r.status().code(), StatusCode::kResourceExhausted);
  const std::string head = "a batch of 65536 paths needs 15728640 bytes";
  EXPECT_TRUE(mentions(e.status(), head)) << e.status().message();
  EXPECT_TRUE(mentions(r.status(), head)) << r.status().message();

  // A budget that holds it: both accept.
  s.device_memory_budget_mib = 64;
  EXPECT_TRUE(pipeline::estimate_bake_resources(scene, s, DeviceLimits::of(ctx.value()->info())));
}

}  // namespace
}  // namespace luxel
