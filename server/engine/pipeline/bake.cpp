#include "pipeline/bake.h"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>

#include "accel/bvh_builder.h"
#include "accel/cl_tracer.h"
#include "accel/triangle_soup.h"
#include "atlas/sample_info.h"
#include "pipeline/primitives/offset_buffer.h"
#include "pipeline/primitives/radix_sort.h"
#include "pipeline/primitives/stream_compaction.h"
#include "pipeline/scene_data.h"
#include "pipeline/shading/light_table.h"
#include "pipeline/shading/texture_pack.h"
#include "shared/bake.h"

namespace luxel::pipeline {

const char* termination_name(Termination t) {
  switch (t) {
    case Termination::kSamples: return "samples";
    case Termination::kTime: return "time";
    case Termination::kError: return "error";
    case Termination::kCancelled: return "cancelled";
  }
  return "?";
}

namespace {

using Clock = std::chrono::steady_clock;
constexpr uint32_t kSlotMask = 0x1FFFFFFFu;  // LUX_SLOT_MASK in kernels/bake.cl
constexpr int kTagShift = 29;                // octant bits above the slot (§5.4)
constexpr size_t kStatsGroup = 256;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Everything one bake holds on the device. Buffers a feature does not need
// stay a 16-byte placeholder (kernel signatures are fixed; see bake.cl).
struct DeviceBuffers {
  device::Buffer placeholder;
  // Scene
  device::Buffer surface, materials, atlas_uvs, instance_first, covered;
  device::Buffer sample_offsets, sample_words;
  device::Buffer lights, light_cdf, sky_texels, sky_marginal, sky_conditional;
  device::Buffer textures, texels;
  // Per iteration (sized by the batch)
  device::Buffer keys, offsets, batch_count, path_count, count_a, count_b;
  device::Buffer paths, rays, hits, shadow_rays, shadow_contrib, occluded;
  device::Buffer active_a, active_b, alive, tagged;
  // Accumulation (sized by the lightmap)
  device::Buffer mean, m2, weight, spp, nonfinite, stats;
  // Directional encodings (placeholders without them)
  device::Buffer basis_samples, encodings, basis_dirs, basis_state;
  device::Buffer reference;  // benchmark mode (placeholder without a reference)
};

class Baker {
 public:
  Baker(const scene::Scene& scene, const BakeSettings& settings, device::Context& ctx)
      : scene_(scene), settings_(settings), ctx_(ctx) {}

  Result<BakeResult> run(const BakeHooks& hooks);

 private:
  Status setup();
  Status upload_scene();
  Status allocate_work_buffers();
  Status build_kernels();
  Status run_iteration(uint32_t batch);
  Status compute_stats(BakeProgress& p);
  // The measure target_error applies to.
  double tracked_error(const BakeProgress& p) const {
    switch (settings_.target_metric) {
      case ErrorMetric::kRmse: return p.rmse;
      case ErrorMetric::kRelMse: return p.rel_mse;
      case ErrorMetric::kEstimate: break;
    }
    return p.error;
  }
  Status read_result(BakeResult& r);
  Status read_state(BakeCheckpoint& c);
  Status restore_state(const BakeCheckpoint& c);
  void fill_irradiance(const std::vector<cl::float4>& mean, std::vector<float>& rgba) const;
  void derive_features();

  template <typename T>
  Result<device::Buffer> upload_or_placeholder(const std::vector<T>& v, const char* name) {
    if (v.empty()) return ctx_.alloc(16, name);
    return ctx_.upload(v, name);
  }
  Status alloc(device::Buffer& b, size_t bytes, const char* name) {
    auto r = ctx_.alloc(std::max<size_t>(bytes, 16), name);
    if (!r) return r.status();
    b = std::move(r.value());
    device_bytes_ += b.bytes();
    return Status::ok();
  }
  Status fill_zero(const device::Buffer& b) {
    return device::cl_status(clEnqueueFillBuffer(ctx_.queue(), b.get(), &kZero, sizeof kZero, 0, b.bytes(),
                                         0, nullptr, nullptr),
                     "clear buffer");
  }
  Status write_int(const device::Buffer& b, int value) {
    return ctx_.write(b, &value, sizeof value);
  }
  cl::LuxBakeParams params(uint32_t batch) const {
    cl::LuxBakeParams p = params_;
    p.paths = batch;
    return p;
  }

  static constexpr uint32_t kZero = 0;

  const scene::Scene& scene_;
  const BakeSettings& settings_;
  device::Context& ctx_;

  atlas::Atlas atlas_;
  atlas::SampleInfo info_;
  accel::TriangleSoup soup_;
  std::unique_ptr<accel::ClTracer> tracer_;
  LightTable lights_;
  SceneData data_;
  device::FeatureSet features_;
  EncodingPlan plan_;
  cl::LuxBakeParams params_{};
  size_t capacity_ = 0;
  size_t device_bytes_ = 0;
  uint64_t paths_done_ = 0;

  DeviceBuffers b_;
  std::unique_ptr<RadixSort> sort_;
  std::unique_ptr<StreamCompaction> compaction_;
  std::unique_ptr<OffsetBuffer> offset_buffer_;
  device::Kernel k_domain_, k_raygen_, k_shade_, k_resolve_, k_resolve_texel_, k_accumulate_,
      k_stats_;
};

Status Baker::setup() {
  auto atlas = atlas::build_atlas(scene_, settings_.atlas);
  if (!atlas) return atlas.status();
  atlas_ = std::move(atlas.value());
  auto info = atlas::build_sample_info(scene_, atlas_);
  if (!info) return info.status();
  info_ = std::move(info.value());
  if (info_.covered_texels.empty())
    return invalid_argument(strprintf(
        "no texel of the %dx%d lightmap contains a sample of any triangle (lightmap UVs too "
        "small for this resolution?)",
        atlas_.width, atlas_.height));
  if (info_.covered_texels.size() >= kSlotMask)
    return resource_exhausted("lightmap has too many covered texels for 32-bit path keys");

  auto soup = accel::build_triangle_soup(scene_);
  if (!soup) return soup.status();
  soup_ = std::move(soup.value());
  auto bvh = accel::build_bvh(soup_);
  if (!bvh) return bvh.status();
  auto tracer = accel::ClTracer::create(ctx_, bvh.value());
  if (!tracer) return tracer.status();
  tracer_ = std::move(tracer.value());
  device_bytes_ += tracer_->device_bytes();

  auto lights = build_light_table(scene_, soup_, settings_.lights, soup_.bounds);
  if (!lights) return lights.status();
  lights_ = std::move(lights.value());
  auto data = prepare_scene_data(scene_, soup_, atlas_, lights_.triangle_light);
  if (!data) return data.status();
  data_ = std::move(data.value());

  auto plan = plan_encodings(settings_.encodings);
  if (!plan) return plan.status();
  plan_ = std::move(plan.value());

  derive_features();
  LUXEL_RETURN_IF_ERROR(upload_scene());

  // Batch size: the paths-per-iteration budget, never more than the samples
  // the whole bake needs, and at most 2^29 (slot ids share a word with the
  // octant tag).
  uint64_t cap = settings_.paths_per_iteration;
  if (settings_.samples_per_texel > 0)
    cap = std::min<uint64_t>(cap, uint64_t{settings_.samples_per_texel} * info_.covered_texels.size());
  capacity_ = static_cast<size_t>(std::clamp<uint64_t>(cap, 1, kSlotMask));

  params_.width = static_cast<uint32_t>(atlas_.width);
  params_.height = static_cast<uint32_t>(atlas_.height);
  params_.texel_count = params_.width * params_.height;
  params_.covered_count = static_cast<uint32_t>(info_.covered_texels.size());
  params_.bake_seed = settings_.seed;
  params_.max_bounces = static_cast<uint32_t>(settings_.max_bounces);
  params_.rr_depth = static_cast<uint32_t>(settings_.rr_depth);
  params_.light_count = static_cast<uint32_t>(lights_.lights.size());
  params_.sky_light = lights_.sky.light;
  params_.clamp_luminance = settings_.clamp_luminance;
  const Vec3 extent = soup_.bounds.empty() ? Vec3{1, 1, 1} : soup_.bounds.extent();
  const float largest = std::max({extent.x, extent.y, extent.z});
  params_.offset_scale = std::clamp(largest, 1e-6f, 1.0f);

  LUXEL_RETURN_IF_ERROR(allocate_work_buffers());
  return build_kernels();
}

void Baker::derive_features() {
  auto& f = features_;
  if (lights_.has_point) f.set("LIGHT_POINT");
  if (lights_.has_spot) f.set("LIGHT_SPOT");
  if (lights_.has_directional) f.set("LIGHT_DIRECTIONAL");
  if (lights_.has_emissive) f.set("LIGHT_EMISSIVE");
  if (lights_.has_sky && !lights_.sky_is_image) f.set("SKY");
  if (lights_.has_sky && lights_.sky_is_image) f.set("SKY_IMAGE");
  if (!lights_.lights.empty()) f.set("NEE");
  if (data_.uses_textures) f.set("TEXTURES");
  if (data_.uses_emissive_texture && lights_.has_emissive) f.set("EMISSIVE_TEXTURE");
  if (data_.needs_specular) f.set("SPECULAR");
  if (settings_.sort_directions) f.set("SORT_DIRECTIONS");
  if (settings_.compaction) f.set("COMPACTION");
  if (settings_.filter == Filter::kGaussian) f.set("FILTER_GAUSSIAN");
  if (settings_.random_sequence) f.set("SEQUENCE_RANDOM");
  if (!plan_.empty()) f.set("BASIS");
}

Status Baker::upload_scene() {
  auto up = [&](device::Buffer& dst, auto&& r) -> Status {
    if (!r) return r.status();
    dst = std::move(r.value());
    device_bytes_ += dst.bytes();
    return Status::ok();
  };
  LUXEL_RETURN_IF_ERROR(up(b_.placeholder, ctx_.alloc(16, "placeholder")));
  LUXEL_RETURN_IF_ERROR(up(b_.surface, upload_or_placeholder(data_.surface, "surface triangles")));
  LUXEL_RETURN_IF_ERROR(up(b_.materials, upload_or_placeholder(data_.materials, "materials")));
  LUXEL_RETURN_IF_ERROR(up(b_.atlas_uvs, upload_or_placeholder(data_.atlas_uvs, "atlas uvs")));
  LUXEL_RETURN_IF_ERROR(
      up(b_.instance_first, upload_or_placeholder(data_.instance_first, "instance table")));
  LUXEL_RETURN_IF_ERROR(up(b_.covered, upload_or_placeholder(info_.covered_texels, "covered texels")));
  // The sample-info buffer (§4.2): per-texel offsets plus the packed words.
  LUXEL_RETURN_IF_ERROR(up(b_.sample_offsets, upload_or_placeholder(info_.offsets, "sample-info offsets")));
  LUXEL_RETURN_IF_ERROR(up(b_.sample_words, upload_or_placeholder(info_.words, "sample-info words")));
  // Lights, sky and textures only when the features use them.
  const bool nee = features_.has("NEE");
  LUXEL_RETURN_IF_ERROR(up(b_.lights, nee ? upload_or_placeholder(lights_.lights, "lights")
                                          : ctx_.alloc(16, "lights (unused)")));
  LUXEL_RETURN_IF_ERROR(up(b_.light_cdf, nee ? upload_or_placeholder(lights_.select_cdf, "light cdf")
                                             : ctx_.alloc(16, "light cdf (unused)")));
  const bool image_sky = features_.has("SKY_IMAGE");
  LUXEL_RETURN_IF_ERROR(up(b_.sky_texels, image_sky ? upload_or_placeholder(lights_.sky_texels, "sky texels")
                                                    : ctx_.alloc(16, "sky texels (unused)")));
  LUXEL_RETURN_IF_ERROR(up(b_.sky_marginal, image_sky ? upload_or_placeholder(lights_.sky_marginal_cdf, "sky marginal cdf")
                                                      : ctx_.alloc(16, "sky marginal (unused)")));
  LUXEL_RETURN_IF_ERROR(up(b_.sky_conditional, image_sky ? upload_or_placeholder(lights_.sky_conditional_cdf, "sky conditional cdf")
                                                         : ctx_.alloc(16, "sky conditional (unused)")));
  if (features_.has("TEXTURES") || features_.has("EMISSIVE_TEXTURE")) {
    auto pack = pack_textures(scene_);
    if (!pack) return pack.status();
    LUXEL_RETURN_IF_ERROR(up(b_.textures, upload_or_placeholder(pack.value().textures, "textures")));
    LUXEL_RETURN_IF_ERROR(up(b_.texels, upload_or_placeholder(pack.value().texels, "texture texels")));
  } else {
    LUXEL_RETURN_IF_ERROR(up(b_.textures, ctx_.alloc(16, "textures (unused)")));
    LUXEL_RETURN_IF_ERROR(up(b_.texels, ctx_.alloc(16, "texels (unused)")));
  }
  return Status::ok();
}

Status Baker::allocate_work_buffers() {
  const size_t p = capacity_;
  const size_t t = size_t{params_.texel_count};
  LUXEL_RETURN_IF_ERROR(alloc(b_.keys, p * 4, "path texel keys"));
  LUXEL_RETURN_IF_ERROR(alloc(b_.offsets, (t + 1) * 4, "offset buffer"));
  LUXEL_RETURN_IF_ERROR(alloc(b_.batch_count, 4, "batch count"));
  LUXEL_RETURN_IF_ERROR(alloc(b_.path_count, 4, "path count"));
  LUXEL_RETURN_IF_ERROR(alloc(b_.count_a, 4, "live count a"));
  LUXEL_RETURN_IF_ERROR(alloc(b_.count_b, 4, "live count b"));
  LUXEL_RETURN_IF_ERROR(alloc(b_.paths, p * sizeof(cl::LuxPath), "paths"));
  LUXEL_RETURN_IF_ERROR(alloc(b_.rays, p * sizeof(cl::LuxRay), "rays"));
  LUXEL_RETURN_IF_ERROR(alloc(b_.hits, p * sizeof(cl::LuxHit), "hits"));
  LUXEL_RETURN_IF_ERROR(alloc(b_.shadow_rays, p * sizeof(cl::LuxRay), "shadow rays"));
  LUXEL_RETURN_IF_ERROR(alloc(b_.shadow_contrib, p * 16, "shadow contributions"));
  LUXEL_RETURN_IF_ERROR(alloc(b_.occluded, p * 4, "occlusion flags"));
  LUXEL_RETURN_IF_ERROR(alloc(b_.active_a, p * 4, "active paths a"));
  LUXEL_RETURN_IF_ERROR(alloc(b_.active_b, p * 4, "active paths b"));
  LUXEL_RETURN_IF_ERROR(alloc(b_.alive, p * 4, "alive flags"));
  LUXEL_RETURN_IF_ERROR(alloc(b_.tagged, p * 4, "tagged slots"));
  LUXEL_RETURN_IF_ERROR(alloc(b_.mean, t * 16, "accumulated mean"));
  LUXEL_RETURN_IF_ERROR(alloc(b_.m2, t * 16, "accumulated M2"));
  LUXEL_RETURN_IF_ERROR(alloc(b_.weight, t * 8, "accumulated weight"));
  LUXEL_RETURN_IF_ERROR(alloc(b_.spp, t * 4, "samples per texel"));
  LUXEL_RETURN_IF_ERROR(alloc(b_.nonfinite, 4, "non-finite counter"));
  const size_t groups = (params_.covered_count + kStatsGroup - 1) / kStatsGroup;
  LUXEL_RETURN_IF_ERROR(alloc(b_.stats, groups * sizeof(cl::LuxAccumStats), "stats partials"));
  // Directional encodings: one sample record per path, the state per texel.
  const bool basis = !plan_.empty();
  LUXEL_RETURN_IF_ERROR(alloc(b_.basis_samples, basis ? p * sizeof(cl::LuxBasisSample) : 16, "basis samples"));
  LUXEL_RETURN_IF_ERROR(alloc(b_.basis_state, t * plan_.bytes_per_texel(), "basis state"));
  auto table = upload_or_placeholder(plan_.table, "encodings");
  if (!table) return table.status();
  b_.encodings = std::move(table.value());
  auto dirs = upload_or_placeholder(plan_.directions, "basis directions");
  if (!dirs) return dirs.status();
  b_.basis_dirs = std::move(dirs.value());
  if (settings_.reference) {
    if (settings_.reference->size() != t * 4)
      return invalid_argument(strprintf(
          "settings.reference: %zu values do not match the %ux%u lightmap (expected RGBA, %zu)",
          settings_.reference->size(), params_.width, params_.height, t * 4));
    auto ref = ctx_.upload(*settings_.reference, "reference lightmap");
    if (!ref) return ref.status();
    b_.reference = std::move(ref.value());
    device_bytes_ += b_.reference.bytes();
  } else {
    LUXEL_RETURN_IF_ERROR(alloc(b_.reference, 16, "reference (unused)"));
  }
  for (const device::Buffer* z : {&b_.mean, &b_.m2, &b_.weight, &b_.spp, &b_.nonfinite, &b_.basis_state})
    LUXEL_RETURN_IF_ERROR(fill_zero(*z));

  auto sort = RadixSort::create(ctx_, p);
  if (!sort) return sort.status();
  sort_ = std::move(sort.value());
  device_bytes_ += sort_->device_bytes();
  if (settings_.compaction) {
    auto compaction = StreamCompaction::create(ctx_, p);
    if (!compaction) return compaction.status();
    compaction_ = std::move(compaction.value());
    device_bytes_ += compaction_->device_bytes();
  }
  auto offsets = OffsetBuffer::create(ctx_, p, params_.texel_count);
  if (!offsets) return offsets.status();
  offset_buffer_ = std::move(offsets.value());
  return Status::ok();
}

Status Baker::build_kernels() {
  auto program = ctx_.programs().get("bake.cl", features_);
  if (!program) return program.status();
  auto get = [&](device::Kernel& k, const char* name) -> Status {
    auto r = program.value()->kernel(name);
    if (!r) return r.status();
    k = std::move(r.value());
    return Status::ok();
  };
  LUXEL_RETURN_IF_ERROR(get(k_domain_, "texel_domain"));
  LUXEL_RETURN_IF_ERROR(get(k_raygen_, "raygen"));
  LUXEL_RETURN_IF_ERROR(get(k_shade_, "shade"));
  LUXEL_RETURN_IF_ERROR(get(k_resolve_, "resolve_shadows"));
  LUXEL_RETURN_IF_ERROR(get(k_resolve_texel_, "resolve_texel_shadows"));
  LUXEL_RETURN_IF_ERROR(get(k_accumulate_, "accumulate"));
  return get(k_stats_, "accum_stats");
}

// One iteration of the wavefront pipeline (module comment of kernels/bake.cl).
Status Baker::run_iteration(uint32_t batch) {
  const cl::LuxBakeParams p = params(batch);
  const size_t cap = capacity_;
  const cl_ulong first_path = paths_done_;
  const bool nee = features_.has("NEE");

  // 1. Texel domain, 2. radix sort by texel (only the bits the texel range
  // needs), 3. offset buffer (Listing 3.1).
  LUXEL_RETURN_IF_ERROR(k_domain_.set_args(p, b_.covered, first_path, b_.keys,
                                           static_cast<cl_uint>(cap)));
  LUXEL_RETURN_IF_ERROR(ctx_.launch(k_domain_, cap, 64));
  LUXEL_RETURN_IF_ERROR(write_int(b_.batch_count, static_cast<int>(batch)));
  LUXEL_RETURN_IF_ERROR(sort_->enqueue(b_.keys, device::Buffer(), b_.batch_count, cap, 0,
                                       RadixSort::bits_for(params_.texel_count - 1)));
  LUXEL_RETURN_IF_ERROR(offset_buffer_->enqueue(b_.keys, b_.batch_count, b_.offsets, b_.path_count));

  // 4. Primary rays + NEE at the texel point.
  LUXEL_RETURN_IF_ERROR(k_raygen_.set_args(
      p, b_.keys, b_.offsets, b_.path_count, b_.sample_offsets, b_.sample_words, b_.atlas_uvs,
      b_.instance_first, b_.surface, b_.materials, b_.textures, b_.texels, b_.lights, b_.light_cdf,
      lights_.sky, b_.sky_texels, b_.sky_marginal, b_.sky_conditional, b_.spp, b_.paths, b_.rays,
      b_.shadow_rays, b_.shadow_contrib, b_.active_a, b_.basis_samples));
  LUXEL_RETURN_IF_ERROR(ctx_.launch(k_raygen_, cap, 64));

  const device::Buffer* active = &b_.active_a;
  const device::Buffer* spare = &b_.active_b;
  const device::Buffer* count = &b_.path_count;
  auto sort_directions = [&]() -> Status {
    return sort_->enqueue(*active, device::Buffer(), *count, cap, kTagShift, 32);
  };
  auto shadows = [&]() -> Status {
    LUXEL_RETURN_IF_ERROR(
        tracer_->enqueue_any_indexed(b_.shadow_rays, *active, *count, kSlotMask, b_.occluded, cap));
    LUXEL_RETURN_IF_ERROR(k_resolve_.set_args(*active, *count, b_.occluded, b_.shadow_contrib, b_.paths));
    return ctx_.launch(k_resolve_, cap, 64);
  };
  if (nee && !plan_.empty()) {
    // The texel point's light sample stays apart from the path's radiance
    // for the basis accumulator: only its visibility is recorded.
    LUXEL_RETURN_IF_ERROR(
        tracer_->enqueue_any_indexed(b_.shadow_rays, *active, *count, kSlotMask, b_.occluded, cap));
    LUXEL_RETURN_IF_ERROR(k_resolve_texel_.set_args(*active, *count, b_.occluded, b_.basis_samples));
    LUXEL_RETURN_IF_ERROR(ctx_.launch(k_resolve_texel_, cap, 64));
  } else if (nee) {
    LUXEL_RETURN_IF_ERROR(shadows());
  }
  if (settings_.sort_directions) LUXEL_RETURN_IF_ERROR(sort_directions());

  // 5. Bounce loop: closest hit -> shade -> shadow rays -> compaction.
  for (int bounce = 0; bounce <= settings_.max_bounces; ++bounce) {
    LUXEL_RETURN_IF_ERROR(
        tracer_->enqueue_closest_indexed(b_.rays, *active, *count, kSlotMask, b_.hits, cap));
    LUXEL_RETURN_IF_ERROR(k_shade_.set_args(
        p, *active, *count, b_.hits, b_.rays, b_.surface, b_.materials, b_.textures, b_.texels,
        b_.lights, b_.light_cdf, lights_.sky, b_.sky_texels, b_.sky_marginal, b_.sky_conditional,
        b_.paths, b_.rays, b_.shadow_rays, b_.shadow_contrib, b_.alive, b_.tagged));
    LUXEL_RETURN_IF_ERROR(ctx_.launch(k_shade_, cap, 64));
    const bool last = bounce == settings_.max_bounces;
    if (last) break;  // vertices past the limit only add emission: no NEE
    if (nee) LUXEL_RETURN_IF_ERROR(shadows());
    if (compaction_) {
      // §5.1: keep only live paths; the new count stays on the device.
      const device::Buffer* next_count = count == &b_.count_a ? &b_.count_b : &b_.count_a;
      LUXEL_RETURN_IF_ERROR(compaction_->enqueue(b_.tagged, b_.alive, *count, *spare, *next_count, cap));
      std::swap(active, spare);
      count = next_count;
      if (settings_.sort_directions) LUXEL_RETURN_IF_ERROR(sort_directions());
    } else if (settings_.sort_directions) {
      LUXEL_RETURN_IF_ERROR(device::cl_status(clEnqueueCopyBuffer(ctx_.queue(), b_.tagged.get(), active->get(), 0,
                                                          0, cap * 4, 0, nullptr, nullptr),
                                      "copy tagged slots"));
      LUXEL_RETURN_IF_ERROR(sort_directions());
    }
  }

  // 6. Gather accumulation per covered texel (Listing 3.2).
  LUXEL_RETURN_IF_ERROR(k_accumulate_.set_args(
      p, b_.covered, b_.offsets, b_.paths, b_.surface, b_.mean, b_.m2, b_.weight, b_.spp,
      b_.nonfinite, b_.basis_samples, b_.encodings, static_cast<cl_uint>(plan_.table.size()),
      plan_.stride, b_.basis_dirs, b_.basis_state, settings_.encodings.acceleration));
  LUXEL_RETURN_IF_ERROR(ctx_.launch(k_accumulate_, params_.covered_count, 64));
  paths_done_ += batch;
  return Status::ok();
}

Status Baker::compute_stats(BakeProgress& progress) {
  const cl::LuxBakeParams p = params(0);
  const size_t groups = (params_.covered_count + kStatsGroup - 1) / kStatsGroup;
  LUXEL_RETURN_IF_ERROR(k_stats_.set_args(p, b_.covered, b_.mean, b_.m2, b_.weight, b_.spp, b_.stats));
  LUXEL_RETURN_IF_ERROR(device::cl_status(clSetKernelArg(k_stats_.get(), 7, kStatsGroup * sizeof(float), nullptr),
                                  "accum_stats local error"));
  LUXEL_RETURN_IF_ERROR(device::cl_status(clSetKernelArg(k_stats_.get(), 8, kStatsGroup * sizeof(cl_uint), nullptr),
                                  "accum_stats local min"));
  const cl_mem ref = b_.reference.get();
  const cl_uint has_reference = settings_.reference ? 1u : 0u;
  LUXEL_RETURN_IF_ERROR(device::cl_status(clSetKernelArg(k_stats_.get(), 9, sizeof ref, &ref),
                                  "accum_stats reference"));
  LUXEL_RETURN_IF_ERROR(device::cl_status(clSetKernelArg(k_stats_.get(), 10, sizeof has_reference, &has_reference),
                                  "accum_stats reference flag"));
  LUXEL_RETURN_IF_ERROR(device::cl_status(clSetKernelArg(k_stats_.get(), 11, kStatsGroup * sizeof(cl::float2), nullptr),
                                  "accum_stats local reference"));
  LUXEL_RETURN_IF_ERROR(ctx_.launch(k_stats_, groups * kStatsGroup, kStatsGroup));
  std::vector<cl::LuxAccumStats> partials(groups);
  LUXEL_RETURN_IF_ERROR(ctx_.read(b_.stats, partials));
  LUXEL_RETURN_IF_ERROR(ctx_.finish());
  double err = 0, sq = 0, rel = 0;
  uint32_t min_spp = 0xFFFFFFFFu;
  for (const auto& s : partials) {
    err += s.rel_error_sum;
    sq += s.reference.x;
    rel += s.reference.y;
    min_spp = std::min(min_spp, s.min_spp);
  }
  progress.error = err / static_cast<double>(params_.covered_count);
  if (settings_.reference) {
    progress.rmse = std::sqrt(sq / params_.covered_count);
    progress.rel_mse = rel / params_.covered_count;
  }
  progress.min_spp = min_spp;
  progress.paths = paths_done_;
  progress.mean_spp = static_cast<double>(paths_done_) / params_.covered_count;
  return Status::ok();
}

// Irradiance RGBA from the running means; alpha = fraction of the texel's
// 64 sample positions that lie on geometry.
void Baker::fill_irradiance(const std::vector<cl::float4>& mean, std::vector<float>& rgba) const {
  rgba.assign(size_t{params_.texel_count} * 4, 0.0f);
  for (uint32_t texel : info_.covered_texels) {
    const uint32_t off = info_.offsets[texel];
    const int valid = std::popcount(info_.words[off]) + std::popcount(info_.words[off + 1]);
    float* px = &rgba[size_t{texel} * 4];
    px[0] = mean[texel].x;
    px[1] = mean[texel].y;
    px[2] = mean[texel].z;
    px[3] = static_cast<float>(valid) / 64.0f;
  }
}

Status Baker::read_state(BakeCheckpoint& c) {
  const size_t t = params_.texel_count;
  c.width = params_.width;
  c.height = params_.height;
  c.mean.resize(t);
  c.m2.resize(t);
  c.weight.resize(t);
  c.spp.resize(t);
  uint32_t nonfinite = 0;
  LUXEL_RETURN_IF_ERROR(ctx_.read(b_.mean, c.mean));
  LUXEL_RETURN_IF_ERROR(ctx_.read(b_.m2, c.m2));
  LUXEL_RETURN_IF_ERROR(ctx_.read(b_.weight, c.weight));
  LUXEL_RETURN_IF_ERROR(ctx_.read(b_.spp, c.spp));
  c.basis.resize(plan_.empty() ? 0 : t * plan_.stride);
  if (!c.basis.empty()) LUXEL_RETURN_IF_ERROR(ctx_.read(b_.basis_state, c.basis));
  LUXEL_RETURN_IF_ERROR(ctx_.read(b_.nonfinite, &nonfinite, sizeof nonfinite));
  LUXEL_RETURN_IF_ERROR(ctx_.finish());
  c.nonfinite = nonfinite;
  c.paths_done = paths_done_;
  return Status::ok();
}

Status Baker::restore_state(const BakeCheckpoint& c) {
  if (c.width != params_.width || c.height != params_.height)
    return invalid_argument(strprintf("checkpoint is for a %ux%u lightmap, this bake is %ux%u",
                                      c.width, c.height, params_.width, params_.height));
  const uint32_t nonfinite = static_cast<uint32_t>(c.nonfinite);
  LUXEL_RETURN_IF_ERROR(ctx_.write(b_.mean, c.mean.data(), c.mean.size() * sizeof(cl::float4)));
  LUXEL_RETURN_IF_ERROR(ctx_.write(b_.m2, c.m2.data(), c.m2.size() * sizeof(cl::float4)));
  LUXEL_RETURN_IF_ERROR(ctx_.write(b_.weight, c.weight.data(), c.weight.size() * sizeof(cl::float2)));
  LUXEL_RETURN_IF_ERROR(ctx_.write(b_.spp, c.spp.data(), c.spp.size() * sizeof(uint32_t)));
  const size_t basis_size = plan_.empty() ? 0 : size_t{params_.texel_count} * plan_.stride;
  if (c.basis.size() != basis_size)
    return invalid_argument(strprintf("checkpoint holds %zu basis values, this bake needs %zu",
                                      c.basis.size(), basis_size));
  if (basis_size > 0)
    LUXEL_RETURN_IF_ERROR(ctx_.write(b_.basis_state, c.basis.data(), basis_size * sizeof(cl::float4)));
  LUXEL_RETURN_IF_ERROR(ctx_.write(b_.nonfinite, &nonfinite, sizeof nonfinite));
  paths_done_ = c.paths_done;
  return ctx_.finish();
}

Status Baker::read_result(BakeResult& r) {
  BakeCheckpoint state;
  LUXEL_RETURN_IF_ERROR(read_state(state));
  const size_t t = params_.texel_count;
  r.width = atlas_.width;
  r.height = atlas_.height;
  fill_irradiance(state.mean, r.irradiance);
  r.samples.assign(t, 0.0f);
  r.rel_error.assign(t, 0.0f);
  for (uint32_t texel : info_.covered_texels) {
    r.samples[texel] = static_cast<float>(state.spp[texel]);
    const double w = state.weight[texel].x, w2 = state.weight[texel].y;
    if (state.spp[texel] >= 2 && w > 0 && state.mean[texel].w > 0) {
      const double var = std::max(0.0, double{state.m2[texel].w} / w);
      const double n_eff = w * w / std::max(w2, 1e-30);
      r.rel_error[texel] = static_cast<float>(std::sqrt(var / n_eff) / state.mean[texel].w);
    }
  }
  r.nonfinite_dropped = state.nonfinite;
  r.basis_bytes_per_texel = plan_.bytes_per_texel();
  for (size_t k = 0; k < plan_.encodings.size(); ++k) {
    EncodedLightmap e;
    e.name = plan_.encodings[k].name();
    e.count = plan_.table[k].count;
    e.coefficients = extract_coefficients(plan_, k, state.basis, t);
    double residual = 0;
    for (uint32_t texel : info_.covered_texels)
      residual += std::sqrt(std::max(0.0f, state.basis[size_t{texel} * plan_.stride + plan_.table[k].state_offset].y));
    const bool progressive = plan_.table[k].solver != LUX_SOLVER_PROJECTION;
    e.residual_rms = progressive ? residual / std::max<size_t>(1, info_.covered_texels.size()) : -1.0;
    e.manifest_json = plan_.encodings[k].describe_json(e.name + ".exr", settings_.encodings.acceleration,
                                                       progressive ? e.residual_rms : -1.0);
    r.encodings.push_back(std::move(e));
  }
  return Status::ok();
}

Result<BakeResult> Baker::run(const BakeHooks& hooks) {
  LUXEL_RETURN_IF_ERROR(validate_settings(settings_));
  const auto t_setup = Clock::now();
  ctx_.timer().reset();
  LUXEL_RETURN_IF_ERROR(setup());
  BakeResult result;
  BakeProgress progress;
  double resumed_elapsed = 0;
  if (hooks.resume) {
    if (hooks.resume->fingerprint != hooks.fingerprint)
      return invalid_argument("checkpoint belongs to another scene or other settings");
    LUXEL_RETURN_IF_ERROR(restore_state(*hooks.resume));
    resumed_elapsed = hooks.resume->elapsed_s;
    progress.iteration = hooks.resume->iteration;
    const auto& s = hooks.resume->series;
    const size_t stride = hooks.resume->series_stride;
    for (size_t i = 0; i + stride <= s.size(); i += stride)
      result.series.push_back({s[i], static_cast<uint64_t>(s[i + 1]), s[i + 2],
                               static_cast<uint32_t>(s[i + 3]), s[i + 4],
                               stride >= 7 ? s[i + 5] : -1.0, stride >= 7 ? s[i + 6] : -1.0});
  }
  LUXEL_RETURN_IF_ERROR(ctx_.finish());
  result.setup_s = seconds_since(t_setup);

  const auto t_start = Clock::now();
  // Tracing time, continued across a resume.
  auto elapsed = [&] { return resumed_elapsed + seconds_since(t_start); };
  const auto& on_progress = hooks.on_progress;
  const uint64_t covered = params_.covered_count;
  const uint64_t target_paths =
      settings_.samples_per_texel > 0 ? uint64_t{settings_.samples_per_texel} * covered : 0;
  auto last_report = Clock::now();
  auto last_snapshot = Clock::now();
  auto last_checkpoint = Clock::now();
  Termination why = Termination::kSamples;
  auto report = [&](bool final_report) -> Result<bool> {
    LUXEL_RETURN_IF_ERROR(compute_stats(progress));
    progress.elapsed_s = elapsed();
    // Progress towards the nearest rule, and its ETA.
    double fraction = 0, eta = -1;
    const double rate = progress.elapsed_s > 0 ? paths_done_ / progress.elapsed_s : 0;
    auto consider = [&](double f, double e) {
      if (f > fraction) fraction = f;
      if (e >= 0 && (eta < 0 || e < eta)) eta = e;
    };
    if (target_paths > 0)
      consider(double(paths_done_) / target_paths,
               rate > 0 ? (double(target_paths) - paths_done_) / rate : -1);
    if (settings_.time_budget_s > 0)
      consider(progress.elapsed_s / settings_.time_budget_s,
               std::max(0.0, settings_.time_budget_s - progress.elapsed_s));
    const double tracked = tracked_error(progress);
    if (settings_.target_error > 0 && tracked > 0 && paths_done_ > 0) {
      // The estimate and RMSE fall as 1/sqrt(samples), relMSE as 1/samples:
      // samples needed = now * (err/target)^p.
      const double power = settings_.target_metric == ErrorMetric::kRelMse ? 1.0 : 2.0;
      const double needed = double(paths_done_) * std::pow(tracked / settings_.target_error, power);
      consider(std::min(1.0, double(paths_done_) / needed),
               rate > 0 ? std::max(0.0, needed - paths_done_) / rate : -1);
    }
    progress.fraction = std::min(1.0, final_report ? 1.0 : fraction);
    progress.eta_s = final_report ? 0 : eta;
    // The final report after a stopping rule repeats the last point: replace it.
    if (!result.series.empty() && result.series.back().paths == progress.paths) result.series.pop_back();
    result.series.push_back({progress.elapsed_s, progress.paths, progress.mean_spp,
                             progress.min_spp, progress.error, progress.rmse, progress.rel_mse});
    last_report = Clock::now();
    if (on_progress && !on_progress(progress)) return false;
    return true;
  };

  for (;;) {
    uint64_t batch = capacity_;
    if (target_paths > 0) batch = std::min<uint64_t>(batch, target_paths - paths_done_);
    {
      std::unique_lock<std::mutex> turn;
      if (hooks.device_turn) turn = std::unique_lock<std::mutex>(*hooks.device_turn);
      LUXEL_RETURN_IF_ERROR(run_iteration(static_cast<uint32_t>(batch)));
      LUXEL_RETURN_IF_ERROR(ctx_.finish());
    }
    ++progress.iteration;
    if (target_paths > 0 && paths_done_ >= target_paths) { why = Termination::kSamples; break; }
    if (hooks.cancel && hooks.cancel->load()) { why = Termination::kCancelled; break; }
    if (settings_.time_budget_s > 0 && elapsed() >= settings_.time_budget_s) {
      why = Termination::kTime;
      break;
    }
    const bool due = seconds_since(last_report) >= settings_.progress_interval_s;
    if (due || settings_.target_error > 0) {
      // The error rule needs the statistics; they cost one small kernel.
      auto keep_going = report(false);
      if (!keep_going) return keep_going.status();
      if (settings_.target_error > 0 && tracked_error(progress) <= settings_.target_error) {
        why = Termination::kError;
        break;
      }
      if (!keep_going.value()) { why = Termination::kCancelled; break; }
    }
    if (hooks.on_snapshot && hooks.snapshot_interval_s > 0 &&
        seconds_since(last_snapshot) >= hooks.snapshot_interval_s) {
      BakeCheckpoint state;
      LUXEL_RETURN_IF_ERROR(read_state(state));
      BakeSnapshot snap;
      snap.width = atlas_.width;
      snap.height = atlas_.height;
      fill_irradiance(state.mean, snap.irradiance);
      // The image's own statistics (error, min spp), not those of the last
      // progress report.
      LUXEL_RETURN_IF_ERROR(compute_stats(progress));
      snap.progress = progress;
      snap.progress.elapsed_s = elapsed();
      hooks.on_snapshot(snap);
      last_snapshot = Clock::now();
    }
    const bool checkpoint_due =
        (hooks.checkpoint_interval_s > 0 &&
         seconds_since(last_checkpoint) >= hooks.checkpoint_interval_s) ||
        (hooks.checkpoint_now && hooks.checkpoint_now->load());
    if (hooks.on_checkpoint && checkpoint_due) {
      BakeCheckpoint state;
      LUXEL_RETURN_IF_ERROR(read_state(state));
      state.fingerprint = hooks.fingerprint;
      state.iteration = progress.iteration;
      state.elapsed_s = elapsed();
      for (const auto& e : result.series)
        state.series.insert(state.series.end(), {e.elapsed_s, double(e.paths), e.mean_spp,
                                                 double(e.min_spp), e.error, e.rmse, e.rel_mse});
      hooks.on_checkpoint(state);
      last_checkpoint = Clock::now();
      // A host that checkpoints to stop (daemon shutdown) cancels in the
      // hook: stop here rather than trace an iteration the checkpoint lacks.
      if (hooks.cancel && hooks.cancel->load()) { why = Termination::kCancelled; break; }
    }
  }
  result.seconds = elapsed();
  auto final_report = report(true);
  if (!final_report) return final_report.status();

  LUXEL_RETURN_IF_ERROR(read_result(result));
  result.atlas = atlas_;
  result.covered_texels = info_.covered_texels.size();
  result.termination = why;
  result.paths = paths_done_;
  result.mean_spp = progress.mean_spp;
  result.min_spp = progress.min_spp;
  result.error = progress.error;
  result.rmse = progress.rmse;
  result.rel_mse = progress.rel_mse;
  device::FeatureSet reported = features_;
  for (const auto& [name, value] : tracer_->features().values()) reported.set(name, value);
  result.features = reported.describe();
  result.device = ctx_.info().describe();
  result.sample_info_bytes = info_.bytes();
  result.peak_device_bytes = device_bytes_;
  result.kernel_table = ctx_.timer().table();
  for (const auto& [name, stats] : ctx_.timer().stats()) result.kernel_ms.push_back({name, stats.total_ms});
  return result;
}

}  // namespace

Result<BakeResult> bake(const scene::Scene& scene, const BakeSettings& settings,
                        device::Context& ctx, const BakeHooks& hooks) {
  Baker baker(scene, settings, ctx);
  return baker.run(hooks);
}

Result<BakeResult> bake(const scene::Scene& scene, const BakeSettings& settings,
                        device::Context& ctx, const ProgressFn& on_progress) {
  BakeHooks hooks;
  hooks.on_progress = on_progress;
  return bake(scene, settings, ctx, hooks);
}

}  // namespace luxel::pipeline
