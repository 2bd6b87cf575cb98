#include "bake/bake_buffers.h"

#include <algorithm>
#include <type_traits>

#include "bake/resource_estimate.h"
#include "bake/sample_slice.h"
#include "shading/texture_pack.h"

namespace luxel::pipeline {
namespace {

// Allocation and upload that count what they hold; a dry run only counts
// (what the tile plan needs before anything is allocated).
class Allocator {
 public:
  Allocator(device::Context& ctx, size_t& bytes, bool dry = false)
      : ctx_(ctx), bytes_(bytes), dry_(dry) {}

  Status alloc(device::Buffer& b, size_t size, const char* name) {
    if (dry_) return count(size);
    return keep(b, ctx_.alloc(std::max<size_t>(size, 16), name));
  }
  // The vector's contents, or a placeholder when it is empty or unused.
  template <typename T>
  Status upload(device::Buffer& b, const std::vector<T>& v, const char* name, bool used = true) {
    if (dry_) return count(used ? v.size() * sizeof(T) : 0);
    if (!used) return keep(b, ctx_.alloc(16, std::string(name) + " (unused)"));
    if (v.empty()) return keep(b, ctx_.alloc(16, name));
    return keep(b, ctx_.upload(v, name));
  }
  Status zero(const device::Buffer& b) {
    if (dry_) return Status::ok();
    static constexpr uint32_t kZero = 0;
    return device::cl_status(clEnqueueFillBuffer(ctx_.queue(), b.get(), &kZero, sizeof kZero, 0,
                                                 b.bytes(), 0, nullptr, nullptr),
                             "clear buffer");
  }
  // The same in pieces of kClearChunk bytes, waiting for each and polling
  // `cancel` between them: one fill of a 2048^2 basis state took 0.48 s on
  // PoCL (2 cores), longer than a cancel may wait.
  Status zero(const device::Buffer& b, const CancelToken& cancel) {
    if (dry_ || !cancel.flag()) return zero(b);
    static constexpr uint32_t kZero = 0;
    constexpr size_t kClearChunk = size_t{64} << 20;
    for (size_t at = 0; at < b.bytes(); at += kClearChunk) {
      const size_t n = std::min(kClearChunk, b.bytes() - at);
      LUXEL_RETURN_IF_ERROR(
          device::cl_status(clEnqueueFillBuffer(ctx_.queue(), b.get(), &kZero, sizeof kZero, at, n,
                                                0, nullptr, nullptr),
                            "clear buffer"));
      LUXEL_RETURN_IF_ERROR(ctx_.finish());
      LUXEL_RETURN_IF_ERROR(check_cancel(cancel, "the tile's clear"));
    }
    return Status::ok();
  }

 private:
  Status count(size_t size) {
    bytes_ += std::max<size_t>(size, 16);
    return Status::ok();
  }
  Status keep(device::Buffer& b, Result<device::Buffer> r) {
    if (!r) return r.status();
    b = std::move(r.value());
    bytes_ += b.bytes();
    return Status::ok();
  }
  device::Context& ctx_;
  size_t& bytes_;
  bool dry_;
};

// slots/words: what the tile buffers hold (covered texels, sample-info
// words); load_tile fills them.
Status upload_scene(Allocator& a, const scene::Scene& scene, const BakeSetup& s,
                    const TileCapacity& cap, BakeKernelArgs& args) {
  SceneArgs& g = args.scene;
  LUXEL_RETURN_IF_ERROR(a.upload(g.tris, s.data.surface, "surface triangles"));
  LUXEL_RETURN_IF_ERROR(a.upload(g.materials, s.data.materials, "materials"));
  LUXEL_RETURN_IF_ERROR(a.upload(g.atlas_uvs, s.data.atlas_uvs, "atlas uvs"));
  LUXEL_RETURN_IF_ERROR(a.upload(g.instance_first, s.data.instance_first, "instance table"));
  // The tile's covered texels and their sample-info records (§4.2), per
  // covered slot: offsets[slot] is the first word of covered[slot]'s record.
  LUXEL_RETURN_IF_ERROR(a.alloc(g.covered, cap.slots * 4, "covered texels"));
  LUXEL_RETURN_IF_ERROR(a.alloc(g.sample_offsets, cap.slots * 4, "sample-info offsets"));
  LUXEL_RETURN_IF_ERROR(a.alloc(g.sample_words, cap.words * 4, "sample-info words"));
  // Probe domain: the probes' positions and visibility caps (shared/probe.h).
  LUXEL_RETURN_IF_ERROR(a.upload(g.probes, s.probes, "probe positions", !s.probes.empty()));

  // Lights, sky and textures only when the features use them.
  LightArgs& l = args.lights;
  const bool nee = s.features.has(device::Feature::NEE);
  const bool image_sky = s.features.has(device::Feature::SKY_IMAGE);
  l.sky = s.lights.sky;
  LUXEL_RETURN_IF_ERROR(a.upload(l.lights, s.lights.lights, "lights", nee));
  LUXEL_RETURN_IF_ERROR(a.upload(l.light_select, s.lights.select, "light selection", nee));
  LUXEL_RETURN_IF_ERROR(a.upload(l.sky_texels, s.lights.sky_texels, "sky texels", image_sky));
  LUXEL_RETURN_IF_ERROR(
      a.upload(l.sky_block_cdfs, s.lights.sky_block_cdfs, "sky block cdfs", image_sky));
  LUXEL_RETURN_IF_ERROR(
      a.upload(l.sky_texel_cdfs, s.lights.sky_texel_cdfs, "sky texel cdfs", image_sky));

  TextureArgs& t = args.textures;
  const bool normal_map = s.features.has(device::Feature::NORMAL_MAP);
  LUXEL_RETURN_IF_ERROR(a.upload(t.tangents, s.data.tangents, "normal-map tangents", normal_map));
  if (!s.features.has(device::Feature::TEXTURES) &&
      !s.features.has(device::Feature::EMISSIVE_TEXTURE) && !normal_map) {
    LUXEL_RETURN_IF_ERROR(a.upload(t.textures, std::vector<cl::LuxTexture>{}, "textures", false));
    LUXEL_RETURN_IF_ERROR(a.upload(t.texels, std::vector<uint32_t>{}, "texels", false));
    return a.upload(t.material_uv1, std::vector<cl::LuxTriangleUV>{}, "material uv1", false);
  }
  auto pack = pack_textures(scene);
  if (!pack) return pack.status();
  LUXEL_RETURN_IF_ERROR(a.upload(t.textures, pack.value().textures, "textures"));
  LUXEL_RETURN_IF_ERROR(a.upload(t.texels, pack.value().texels, "texture texels"));
  return a.upload(t.material_uv1, s.data.material_uv1, "material uv1",
                  s.features.has(device::Feature::TEXCOORD1));
}

// slots: covered texels (the offset buffer is indexed by covered slot).
Status allocate_paths(Allocator& a, size_t p, size_t slots, PathArgs& g) {
  LUXEL_RETURN_IF_ERROR(a.alloc(g.keys, p * 4, "path texel keys"));
  LUXEL_RETURN_IF_ERROR(a.alloc(g.offsets, (slots + 1) * 4, "offset buffer"));
  LUXEL_RETURN_IF_ERROR(a.alloc(g.paths, p * sizeof(cl::LuxPath), "paths"));
  LUXEL_RETURN_IF_ERROR(a.alloc(g.rays, p * sizeof(cl::LuxRay), "rays"));
  LUXEL_RETURN_IF_ERROR(a.alloc(g.hits, p * sizeof(cl::LuxHit), "hits"));
  LUXEL_RETURN_IF_ERROR(a.alloc(g.shadow_rays, p * sizeof(cl::LuxRay), "shadow rays"));
  LUXEL_RETURN_IF_ERROR(a.alloc(g.shadow_contrib, p * 16, "shadow contributions"));
  LUXEL_RETURN_IF_ERROR(a.alloc(g.occluded, p * 4, "occlusion flags"));
  LUXEL_RETURN_IF_ERROR(a.alloc(g.alive, p * 4, "alive flags"));
  return a.alloc(g.tagged, p * 4, "tagged slots");
}

// Per-texel state exists only for the tile's covered texels, indexed by
// covered slot.
Status allocate_accum(Allocator& a, const BakeSetup& s, const BakeSettings& settings, size_t c,
                      AccumArgs& g) {
  const size_t t = s.params.texel_count;
  LUXEL_RETURN_IF_ERROR(a.alloc(g.mean, c * 16, "accumulated mean"));
  LUXEL_RETURN_IF_ERROR(a.alloc(g.m2, c * 16, "accumulated M2"));
  LUXEL_RETURN_IF_ERROR(a.alloc(g.weight, c * 8, "accumulated weight"));
  LUXEL_RETURN_IF_ERROR(a.alloc(g.spp, c * 4, "samples per texel"));
  LUXEL_RETURN_IF_ERROR(a.alloc(g.nonfinite, 4, "non-finite counter"));
  LUXEL_RETURN_IF_ERROR(a.alloc(g.radiance_cache,
                                s.features.has(device::Feature::RADIANCE_CACHE) ? c * 16 : 16,
                                "radiance cache"));
  LUXEL_RETURN_IF_ERROR(
      a.alloc(g.guide, s.features.has(device::Feature::GUIDING) ? c * 16 * kGuideStride : 16,
              "first-bounce guide"));
  const size_t groups = (c + LUX_STATS_GROUP - 1) / LUX_STATS_GROUP;
  LUXEL_RETURN_IF_ERROR(a.alloc(g.stats, groups * sizeof(cl::LuxAccumStats), "stats partials"));
  if (!settings.reference) return a.alloc(g.reference, 16, "reference (unused)");
  if (settings.reference->size() != t * 4)
    return invalid_argument(strprintf(
        "settings.reference: %zu values do not match the %ux%u lightmap (expected RGBA, %zu)",
        settings.reference->size(), s.params.width, s.params.height, t * 4));
  return a.upload(g.reference, *settings.reference, "reference lightmap");
}

// Directional encodings: one sample record per path, the state per covered
// texel.
Status allocate_encodings(Allocator& a, const BakeSetup& s, size_t t, EncodingArgs& g) {
  const size_t p = s.capacity;
  const bool basis = !s.plan.empty();
  LUXEL_RETURN_IF_ERROR(
      a.alloc(g.basis_samples, basis ? p * sizeof(cl::LuxBasisSample) : 16, "basis samples"));
  LUXEL_RETURN_IF_ERROR(a.alloc(g.basis_state, t * s.plan.bytes_per_texel(), "basis state"));
  LUXEL_RETURN_IF_ERROR(a.upload(g.encodings, s.plan.table, "encodings"));
  return a.upload(g.basis_dirs, s.plan.directions, "basis directions");
}

// Adaptive sampling's weights per covered slot and block sums (one per
// LUX_ALLOC_GROUP slots, plus the total); placeholders without it.
Status allocate_alloc(Allocator& a, const BakeSetup& s, size_t c, AllocArgs& g) {
  const bool on = s.features.has(device::Feature::ADAPTIVE);
  const size_t blocks = (c + LUX_ALLOC_GROUP - 1) / LUX_ALLOC_GROUP + 1;
  LUXEL_RETURN_IF_ERROR(a.alloc(g.alloc_weights, on ? c * 4 : 16, "adaptive weights"));
  return a.alloc(g.alloc_blocks, on ? blocks * 8 : 16, "adaptive block sums");
}

}  // namespace

Status BakeBuffers::allocate(device::Context& ctx, const scene::Scene& scene,
                             const BakeSetup& setup, const BakeSettings& settings,
                             const TileCapacity& cap, bool dry) {
  Allocator a(ctx, device_bytes_, dry);
  args_.params = setup.params;
  radiance_cache_ = setup.features.has(device::Feature::RADIANCE_CACHE);
  guiding_ = setup.features.has(device::Feature::GUIDING);
  LUXEL_RETURN_IF_ERROR(upload_scene(a, scene, setup, cap, args_));
  const size_t p = setup.capacity;
  LUXEL_RETURN_IF_ERROR(a.alloc(batch_count, 4, "batch count"));
  LUXEL_RETURN_IF_ERROR(a.alloc(path_count, 4, "path count"));
  LUXEL_RETURN_IF_ERROR(a.alloc(count_a, 4, "live count a"));
  LUXEL_RETURN_IF_ERROR(a.alloc(count_b, 4, "live count b"));
  LUXEL_RETURN_IF_ERROR(a.alloc(active_a, p * 4, "active paths a"));
  LUXEL_RETURN_IF_ERROR(a.alloc(active_b, p * 4, "active paths b"));
  LUXEL_RETURN_IF_ERROR(allocate_paths(a, p, cap.slots, args_.paths));
  LUXEL_RETURN_IF_ERROR(allocate_accum(a, setup, settings, cap.slots, args_.accum));
  LUXEL_RETURN_IF_ERROR(allocate_alloc(a, setup, cap.slots, args_.alloc));
  return allocate_encodings(a, setup, cap.slots, args_.encodings);
}

Result<BakeBuffers> BakeBuffers::create(device::Context& ctx, const scene::Scene& scene,
                                        const BakeSetup& setup, const BakeSettings& settings,
                                        const TileCapacity& cap) {
  BakeBuffers b;
  LUXEL_RETURN_IF_ERROR(b.allocate(ctx, scene, setup, settings, cap, /*dry=*/false));
  return b;
}

Result<size_t> BakeBuffers::fixed_bytes(device::Context& ctx, const scene::Scene& scene,
                                        const BakeSetup& setup, const BakeSettings& settings) {
  BakeBuffers b;
  LUXEL_RETURN_IF_ERROR(b.allocate(ctx, scene, setup, settings, TileCapacity{}, /*dry=*/true));
  return b.device_bytes_;
}

size_t BakeBuffers::per_slot_bytes(const BakeSetup& s) {
  return texel_state_bytes(s.plan.bytes_per_texel(), s.features.has(device::Feature::ADAPTIVE),
                           s.features.has(device::Feature::RADIANCE_CACHE),
                           s.features.has(device::Feature::GUIDING));  // resource_estimate.h
}

size_t BakeBuffers::largest_per_slot_bytes(const BakeSetup& s) {
  return std::max<size_t>(16, s.plan.bytes_per_texel());
}

Status BakeBuffers::load_tile(device::Context& ctx, const BakeSetup& setup, size_t begin,
                              size_t end, CancelToken cancel) {
  const SampleSlice slice = slice_sample_info(setup.info, begin, end);
  SceneArgs& g = args_.scene;
  LUXEL_RETURN_IF_ERROR(ctx.write(g.covered, slice.covered.data(), slice.covered.size() * 4));
  LUXEL_RETURN_IF_ERROR(
      ctx.write(g.sample_offsets, slice.offsets.data(), slice.offsets.size() * 4));
  LUXEL_RETURN_IF_ERROR(ctx.write(g.sample_words, slice.words.data(), slice.words.size() * 4));
  args_.params.covered_count = static_cast<uint32_t>(end - begin);
  size_t unused = 0;
  Allocator a(ctx, unused);
  const AccumArgs& acc = args_.accum;
  for (const device::Buffer* z :
       {&acc.mean, &acc.m2, &acc.weight, &acc.spp, &acc.nonfinite, &acc.radiance_cache, &acc.guide,
        static_cast<const device::Buffer*>(&args_.encodings.basis_state)}) {
    LUXEL_RETURN_IF_ERROR(a.zero(*z, cancel));
  }
  return ctx.finish();  // the slice's host memory goes when this returns
}

Status BakeBuffers::read_state(device::Context& ctx, BakeCheckpoint& c, CancelToken cancel) const {
  return read_state(ctx, c, 0, args_.params.covered_count, cancel);
}

Status BakeBuffers::read_state(device::Context& ctx, BakeCheckpoint& c, size_t first, size_t n,
                               CancelToken cancel) const {
  const cl::LuxBakeParams& p = args_.params;
  const AccumArgs& acc = args_.accum;
  c.width = p.width;
  c.height = p.height;
  c.per_texel = false;
  c.mean.resize(n);
  c.m2.resize(n);
  c.weight.resize(n);
  c.spp.resize(n);
  uint32_t nonfinite = 0;
  auto read = [&](const device::Buffer& b, auto& v, size_t per_slot) {
    using T = typename std::decay_t<decltype(v)>::value_type;
    return ctx.read(b, v.data(), v.size() * sizeof(T), first * per_slot * sizeof(T));
  };
  LUXEL_RETURN_IF_ERROR(read(acc.mean, c.mean, 1));
  LUXEL_RETURN_IF_ERROR(read(acc.m2, c.m2, 1));
  LUXEL_RETURN_IF_ERROR(read(acc.weight, c.weight, 1));
  LUXEL_RETURN_IF_ERROR(read(acc.spp, c.spp, 1));
  c.radiance_cache.resize(radiance_cache_ ? n : 0);
  if (radiance_cache_) LUXEL_RETURN_IF_ERROR(read(acc.radiance_cache, c.radiance_cache, 1));
  c.guide.resize(guiding_ ? n * kGuideStride : 0);
  if (guiding_) LUXEL_RETURN_IF_ERROR(read(acc.guide, c.guide, kGuideStride));
  const size_t stride = p.encoding_count == 0 ? 0 : p.basis_stride;
  c.basis.resize(n * stride);
  constexpr size_t kReadChunk = size_t{64} << 20;
  const size_t basis_bytes = c.basis.size() * sizeof(c.basis[0]);
  const size_t basis_offset = first * stride * sizeof(c.basis[0]);
  for (size_t at = 0; at < basis_bytes; at += kReadChunk) {
    LUXEL_RETURN_IF_ERROR(check_cancel(cancel, "the state's read-back"));
    LUXEL_RETURN_IF_ERROR(ctx.read(args_.encodings.basis_state,
                                   reinterpret_cast<char*>(c.basis.data()) + at,
                                   std::min(kReadChunk, basis_bytes - at), basis_offset + at));
  }
  LUXEL_RETURN_IF_ERROR(ctx.read(acc.nonfinite, &nonfinite, sizeof nonfinite));
  LUXEL_RETURN_IF_ERROR(ctx.finish());
  c.nonfinite = nonfinite;
  return Status::ok();
}

Status BakeBuffers::restore_state(device::Context& ctx, const BakeCheckpoint& c,
                                  const std::vector<uint32_t>& covered) {
  const cl::LuxBakeParams& p = args_.params;
  if (c.width != p.width || c.height != p.height)
    return invalid_argument(strprintf("checkpoint is for a %ux%u lightmap, this bake is %ux%u",
                                      c.width, c.height, p.width, p.height));
  // Version-1/2 checkpoints hold whole images: keep the covered texels.
  const BakeCheckpoint compact = c.per_texel ? compact_checkpoint(c, covered) : BakeCheckpoint{};
  const BakeCheckpoint& k = c.per_texel ? compact : c;
  const size_t n = p.covered_count;
  if (k.mean.size() != n || k.m2.size() != n || k.weight.size() != n || k.spp.size() != n)
    return invalid_argument(
        strprintf("checkpoint holds %zu covered texels, this bake has %zu", k.mean.size(), n));
  const AccumArgs& acc = args_.accum;
  const uint32_t nonfinite = static_cast<uint32_t>(c.nonfinite);
  LUXEL_RETURN_IF_ERROR(ctx.write(acc.mean, k.mean.data(), n * sizeof(cl::float4)));
  LUXEL_RETURN_IF_ERROR(ctx.write(acc.m2, k.m2.data(), n * sizeof(cl::float4)));
  LUXEL_RETURN_IF_ERROR(ctx.write(acc.weight, k.weight.data(), n * sizeof(cl::float2)));
  LUXEL_RETURN_IF_ERROR(ctx.write(acc.spp, k.spp.data(), n * sizeof(uint32_t)));
  // A checkpoint without the cache (written before it, or by a bake without
  // it) leaves the cache empty: the bake refills it.
  if (radiance_cache_ && k.radiance_cache.size() == n)
    LUXEL_RETURN_IF_ERROR(
        ctx.write(acc.radiance_cache, k.radiance_cache.data(), n * sizeof(cl::float4)));
  if (guiding_ && k.guide.size() == n * kGuideStride)
    LUXEL_RETURN_IF_ERROR(
        ctx.write(acc.guide, k.guide.data(), k.guide.size() * sizeof(cl::float4)));
  const size_t basis_size = p.encoding_count == 0 ? 0 : n * p.basis_stride;
  if (k.basis.size() != basis_size)
    return invalid_argument(strprintf("checkpoint holds %zu basis values, this bake needs %zu",
                                      k.basis.size(), basis_size));
  if (basis_size > 0)
    LUXEL_RETURN_IF_ERROR(
        ctx.write(args_.encodings.basis_state, k.basis.data(), basis_size * sizeof(cl::float4)));
  LUXEL_RETURN_IF_ERROR(ctx.write(acc.nonfinite, &nonfinite, sizeof nonfinite));
  return ctx.finish();
}

}  // namespace luxel::pipeline
