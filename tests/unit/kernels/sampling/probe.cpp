#include "probe.h"

#include <random>

#include "device/feature_set.h"
#include "device/program_cache.h"

namespace luxel::sampling_test {
namespace {

device::FeatureSet features(Build build) {
  device::FeatureSet f;
  if (build == Build::kSobolSpecular) f.set(device::Feature::SPECULAR);
  if (build == Build::kRandomDiffuseOnly) f.set(device::Feature::SEQUENCE_RANDOM);
  return f;
}

}  // namespace

Result<Probe*> Probe::instance() {
  static std::unique_ptr<Probe> probe;
  static Status init_status;
  if (!probe && init_status.is_ok()) {
    std::unique_ptr<Probe> p(new Probe());
    init_status = p->init();
    if (init_status.is_ok()) probe = std::move(p);
  }
  if (!probe) return init_status;
  return probe.get();
}

Status Probe::init() {
  auto ctx = device::Context::create();
  if (!ctx) return ctx.status();
  ctx_ = std::move(ctx.value());
  std::mt19937_64 rng(0x5eed5a3b1e5ull);
  auto unit = [&rng] { return float(rng() >> 40) * 0x1p-24f; };
  uniforms_.resize(kMaxSamples);
  for (float4& u : uniforms_) u = {unit(), unit(), unit(), unit()};
  auto buffer = ctx_->upload(uniforms_, "sampling probe uniforms");
  if (!buffer) return buffer.status();
  uniforms_device_ = std::move(buffer.value());
  return Status::ok();
}

Result<device::Kernel> Probe::kernel(Build build, const char* name) {
  auto program = ctx_->programs().get("testing/sampling_probe.cl", features(build));
  if (!program) return program.status();
  return program.value()->kernel(name);
}

template <typename T>
Result<std::vector<T>> Probe::read_back(const device::Buffer& buffer, size_t count) {
  std::vector<T> out(count);
  LUXEL_RETURN_IF_ERROR(ctx_->read(buffer, out));
  return out;
}

Result<std::vector<float2>> Probe::sequence(Build build, const std::vector<uint4>& queries) {
  auto k = kernel(build, "probe_sequence");
  if (!k) return k.status();
  auto in = ctx_->upload(queries, "sequence queries");
  auto out = ctx_->alloc(queries.size() * sizeof(float2), "sequence output");
  if (!in) return in.status();
  if (!out) return out.status();
  LUXEL_RETURN_IF_ERROR(k->set_args(in.value(), uint32_t(queries.size()), out.value()));
  LUXEL_RETURN_IF_ERROR(ctx_->launch(k.value(), queries.size(), 64));
  return read_back<float2>(out.value(), queries.size());
}

Result<std::vector<uint32_t>> Probe::hash(const std::vector<uint32_t>& values) {
  return u32_function("probe_hash", values);
}

Result<std::vector<uint32_t>> Probe::sobol_dim1(const std::vector<uint32_t>& values) {
  return u32_function("probe_sobol_dim1", values);
}

Result<std::vector<uint32_t>> Probe::u32_function(const char* name,
                                                  const std::vector<uint32_t>& values) {
  auto k = kernel(Build::kSobolSpecular, name);
  if (!k) return k.status();
  auto in = ctx_->upload(values, std::string(name) + " input");
  auto out = ctx_->alloc(values.size() * sizeof(uint32_t), std::string(name) + " output");
  if (!in) return in.status();
  if (!out) return out.status();
  LUXEL_RETURN_IF_ERROR(k->set_args(in.value(), uint32_t(values.size()), out.value()));
  LUXEL_RETURN_IF_ERROR(ctx_->launch(k.value(), values.size(), 64));
  return read_back<uint32_t>(out.value(), values.size());
}

Result<std::vector<float4>> Probe::warp(Warp warp, float param, size_t count) {
  if (count > kMaxSamples) return invalid_argument("warp probe: more samples than uniforms");
  auto k = kernel(Build::kSobolSpecular, "probe_warp");
  if (!k) return k.status();
  auto out = ctx_->alloc(count * sizeof(float4), "warp output");
  if (!out) return out.status();
  LUXEL_RETURN_IF_ERROR(
      k->set_args(uniforms_device_, uint32_t(count), int(warp), param, out.value()));
  LUXEL_RETURN_IF_ERROR(ctx_->launch(k.value(), count, 64));
  return read_back<float4>(out.value(), count);
}

Result<std::vector<float>> Probe::cosine_hemisphere_pdf(const std::vector<float4>& dirs) {
  auto k = kernel(Build::kSobolSpecular, "probe_cosine_hemisphere_pdf");
  if (!k) return k.status();
  auto in = ctx_->upload(dirs, "cosine pdf directions");
  auto out = ctx_->alloc(dirs.size() * sizeof(float), "cosine pdf output");
  if (!in) return in.status();
  if (!out) return out.status();
  LUXEL_RETURN_IF_ERROR(k->set_args(in.value(), uint32_t(dirs.size()), out.value()));
  LUXEL_RETURN_IF_ERROR(ctx_->launch(k.value(), dirs.size(), 64));
  return read_back<float>(out.value(), dirs.size());
}

Result<std::vector<float4>> Probe::onb(const std::vector<float4>& normals,
                                       const std::vector<float4>& vectors) {
  auto k = kernel(Build::kSobolSpecular, "probe_onb");
  if (!k) return k.status();
  auto n = ctx_->upload(normals, "onb normals");
  auto v = ctx_->upload(vectors, "onb vectors");
  auto out = ctx_->alloc(normals.size() * 4 * sizeof(float4), "onb output");
  if (!n) return n.status();
  if (!v) return v.status();
  if (!out) return out.status();
  LUXEL_RETURN_IF_ERROR(k->set_args(n.value(), v.value(), uint32_t(normals.size()), out.value()));
  LUXEL_RETURN_IF_ERROR(ctx_->launch(k.value(), normals.size(), 64));
  return read_back<float4>(out.value(), normals.size() * 4);
}

Result<std::vector<float4>> Probe::make_bsdf(Build build, const std::vector<float4>& base_metallic,
                                             const std::vector<float4>& roughness) {
  auto k = kernel(build, "probe_make_bsdf");
  if (!k) return k.status();
  auto m = ctx_->upload(base_metallic, "bsdf materials");
  auto r = ctx_->upload(roughness, "bsdf roughness");
  auto out = ctx_->alloc(base_metallic.size() * 3 * sizeof(float4), "bsdf parameters");
  if (!m) return m.status();
  if (!r) return r.status();
  if (!out) return out.status();
  LUXEL_RETURN_IF_ERROR(
      k->set_args(m.value(), r.value(), uint32_t(base_metallic.size()), out.value()));
  LUXEL_RETURN_IF_ERROR(ctx_->launch(k.value(), base_metallic.size(), 64));
  return read_back<float4>(out.value(), base_metallic.size() * 3);
}

Result<BsdfSamples> Probe::bsdf_sample(Build build, const Material& m, float4 wo,
                                       float u_layer_override, size_t count) {
  if (count > kMaxSamples) return invalid_argument("bsdf sample probe: more samples than uniforms");
  auto k = kernel(build, "probe_bsdf_sample");
  if (!k) return k.status();
  auto sample = ctx_->alloc(count * sizeof(float4), "bsdf samples");
  auto weight = ctx_->alloc(count * sizeof(float4), "bsdf weights");
  auto check = ctx_->alloc(count * sizeof(float4), "bsdf checks");
  if (!sample) return sample.status();
  if (!weight) return weight.status();
  if (!check) return check.status();
  wo.w = m.dielectric_f0;
  LUXEL_RETURN_IF_ERROR(k->set_args(m.base_metallic, m.roughness, wo, m.specular, u_layer_override,
                                    uniforms_device_, uint32_t(count), sample.value(),
                                    weight.value(), check.value()));
  LUXEL_RETURN_IF_ERROR(ctx_->launch(k.value(), count, 64));
  BsdfSamples out;
  for (auto [buffer, vec] :
       {std::pair{&sample.value(), &out.sample}, std::pair{&weight.value(), &out.weight},
        std::pair{&check.value(), &out.check}}) {
    auto data = read_back<float4>(*buffer, count);
    if (!data) return data.status();
    *vec = std::move(data.value());
  }
  return out;
}

Result<std::vector<float4>> Probe::bsdf_eval(Build build, const Material& m, float4 wo,
                                             const std::vector<float4>& dirs) {
  auto k = kernel(build, "probe_bsdf_eval");
  if (!k) return k.status();
  auto in = ctx_->upload(dirs, "bsdf eval directions");
  auto out = ctx_->alloc(dirs.size() * 2 * sizeof(float4), "bsdf eval output");
  if (!in) return in.status();
  if (!out) return out.status();
  wo.w = m.dielectric_f0;
  LUXEL_RETURN_IF_ERROR(k->set_args(m.base_metallic, m.roughness, wo, m.specular, in.value(),
                                    uint32_t(dirs.size()), out.value()));
  LUXEL_RETURN_IF_ERROR(ctx_->launch(k.value(), dirs.size(), 64));
  return read_back<float4>(out.value(), dirs.size() * 2);
}

}  // namespace luxel::sampling_test
