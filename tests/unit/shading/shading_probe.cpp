#include "shading_probe.h"

#include "support/device_context.h"

namespace luxel::pipeline::test {
namespace {

// One context for the whole test binary (PoCL start-up is not free).
using ::luxel::testing::shared_context;

constexpr const char* kProbe = "testing/lights_probe.cl";

// Uploads v, or allocates a placeholder for an absent (empty) buffer.
template <typename T>
Result<device::Buffer> upload(const std::vector<T>& v, const char* name) {
  return shared_context().upload(v, name);
}

template <typename T>
Status read_back(const device::Buffer& b, std::vector<T>* out, size_t n) {
  out->resize(n);
  return shared_context().read(b, *out);
}

}  // namespace

device::FeatureSet all_light_features() {
  device::FeatureSet f;
  using device::Feature;
  for (Feature name : {Feature::LIGHT_POINT, Feature::LIGHT_SPOT, Feature::LIGHT_DIRECTIONAL,
                       Feature::LIGHT_EMISSIVE, Feature::SKY, Feature::SKY_IMAGE})
    f.set(name);
  return f;
}

Result<std::unique_ptr<LightProbe>> LightProbe::create(const LightTable& table,
                                                       const device::FeatureSet& features) {
  std::unique_ptr<LightProbe> p(new LightProbe);
  p->table_ = &table;
  auto program = shared_context().programs().get(kProbe, features);
  if (!program) return program.status();
  p->program_ = program.value();
  auto lights = upload(table.lights, "lights");
  if (!lights) return lights.status();
  p->lights_ = std::move(lights.value());
  auto cdf = upload(table.select, "light selection");
  if (!cdf) return cdf.status();
  p->cdf_ = std::move(cdf.value());
  auto texels = upload(table.sky_texels, "sky texels");
  if (!texels) return texels.status();
  p->sky_texels_ = std::move(texels.value());
  auto marginal = upload(table.sky_block_cdfs, "sky marginal");
  if (!marginal) return marginal.status();
  p->sky_block_cdfs_ = std::move(marginal.value());
  auto conditional = upload(table.sky_texel_cdfs, "sky conditional");
  if (!conditional) return conditional.status();
  p->sky_texel_cdfs_ = std::move(conditional.value());
  return p;
}

Result<LightSamples> LightProbe::sample(const std::vector<cl::float4>& points,
                                        const std::vector<cl::float4>& randoms,
                                        std::vector<cl::float4> normals) {
  LUXEL_CHECK(points.size() == randoms.size());
  if (normals.empty()) normals.assign(points.size(), cl::float4{0, 1, 0, 0});
  LUXEL_CHECK(normals.size() == points.size());
  device::Context& ctx = shared_context();
  const size_t n = points.size();
  auto kernel = program_->kernel("probe_sample_lights");
  if (!kernel) return kernel.status();
  auto pts = upload(points, "points");
  if (!pts) return pts.status();
  auto rnd = upload(randoms, "randoms");
  if (!rnd) return rnd.status();
  auto nrm = upload(normals, "normals");
  if (!nrm) return nrm.status();
  auto wi_pdf = ctx.alloc(n * sizeof(cl::float4), "wi pdf");
  auto rad = ctx.alloc(n * sizeof(cl::float4), "radiance dist");
  auto info = ctx.alloc(n * sizeof(cl::int4), "info");
  auto bary = ctx.alloc(n * sizeof(cl::float2), "bary");
  if (!wi_pdf || !rad || !info || !bary) return internal_error("allocating probe outputs");
  const cl_uint count = static_cast<cl_uint>(table_->lights.size());
  LUXEL_RETURN_IF_ERROR(kernel->set_args(lights_, cdf_, count, table_->sky, sky_texels_,
                                         sky_block_cdfs_, sky_texel_cdfs_, pts.value(), nrm.value(),
                                         rnd.value(), static_cast<int>(n), wi_pdf.value(),
                                         rad.value(), info.value(), bary.value()));
  LUXEL_RETURN_IF_ERROR(ctx.launch(kernel.value(), n));
  LightSamples s;
  LUXEL_RETURN_IF_ERROR(read_back(wi_pdf.value(), &s.wi_pdf, n));
  LUXEL_RETURN_IF_ERROR(read_back(rad.value(), &s.radiance_dist, n));
  LUXEL_RETURN_IF_ERROR(read_back(info.value(), &s.info, n));
  LUXEL_RETURN_IF_ERROR(read_back(bary.value(), &s.bary, n));
  return s;
}

Result<LightSamples> LightProbe::sample_at(Vec3 p, const std::vector<cl::float4>& randoms, Vec3 n) {
  return sample(std::vector<cl::float4>(randoms.size(), cl::float4{p.x, p.y, p.z, 0}), randoms,
                std::vector<cl::float4>(randoms.size(), cl::float4{n.x, n.y, n.z, 0}));
}

Result<std::vector<float>> LightProbe::triangle_pdf(const std::vector<int>& light,
                                                    const std::vector<cl::float4>& p,
                                                    const std::vector<cl::float4>& hit,
                                                    const std::vector<cl::float4>& normal) {
  const size_t n = light.size();
  LUXEL_CHECK(p.size() == n && hit.size() == n && normal.size() == n);
  auto kernel = program_->kernel("probe_triangle_pdf");
  if (!kernel) return kernel.status();
  auto lb = upload(light, "light"), pb = upload(p, "p"), hb = upload(hit, "hit"),
       nb = upload(normal, "normal");
  if (!lb || !pb || !hb || !nb) return internal_error("uploading pdf queries");
  auto out = shared_context().alloc(n * sizeof(float), "pdf");
  if (!out) return out.status();
  LUXEL_RETURN_IF_ERROR(kernel->set_args(lights_, cdf_, lb.value(), pb.value(), hb.value(),
                                         nb.value(), static_cast<int>(n), out.value()));
  LUXEL_RETURN_IF_ERROR(shared_context().launch(kernel.value(), n));
  std::vector<float> pdf;
  LUXEL_RETURN_IF_ERROR(read_back(out.value(), &pdf, n));
  return pdf;
}

Result<std::vector<cl::float4>> LightProbe::sky(const std::vector<cl::float4>& dirs, Vec3 nrm) {
  const size_t n = dirs.size();
  auto kernel = program_->kernel("probe_sky");
  if (!kernel) return kernel.status();
  auto db = upload(dirs, "dirs");
  if (!db) return db.status();
  auto out = shared_context().alloc(n * sizeof(cl::float4), "sky out");
  if (!out) return out.status();
  LUXEL_RETURN_IF_ERROR(kernel->set_args(
      table_->sky, sky_texels_, cdf_, table_->sky.light, sky_block_cdfs_, sky_texel_cdfs_,
      db.value(), static_cast<int>(n), cl::float4{nrm.x, nrm.y, nrm.z, 0}, out.value()));
  LUXEL_RETURN_IF_ERROR(shared_context().launch(kernel.value(), n));
  std::vector<cl::float4> r;
  LUXEL_RETURN_IF_ERROR(read_back(out.value(), &r, n));
  return r;
}

namespace {

// One probe kernel over a table: (table, n, u, count, index, pmf).
template <typename T>
Status probe_table_sampler(const char* kernel_name, const std::vector<T>& table, cl_uint n,
                           const std::vector<float>& u, std::vector<int>* index,
                           std::vector<float>* pmf) {
  auto program = shared_context().programs().get(kProbe, all_light_features());
  if (!program) return program.status();
  auto kernel = program.value()->kernel(kernel_name);
  if (!kernel) return kernel.status();
  auto cb = upload(table, "table"), ub = upload(u, "u");
  if (!cb || !ub) return internal_error("uploading table queries");
  auto ib = shared_context().alloc(u.size() * sizeof(int), "index");
  auto pb = shared_context().alloc(u.size() * sizeof(float), "pmf");
  if (!ib || !pb) return internal_error("allocating table outputs");
  LUXEL_RETURN_IF_ERROR(kernel->set_args(cb.value(), n, ub.value(), static_cast<int>(u.size()),
                                         ib.value(), pb.value()));
  LUXEL_RETURN_IF_ERROR(shared_context().launch(kernel.value(), u.size()));
  LUXEL_RETURN_IF_ERROR(read_back(ib.value(), index, u.size()));
  return read_back(pb.value(), pmf, u.size());
}

}  // namespace

Status probe_sample_cdf(const std::vector<float>& cdf, const std::vector<float>& u,
                        std::vector<int>* index, std::vector<float>* pmf) {
  return probe_table_sampler("probe_sample_cdf", cdf, static_cast<cl_uint>(cdf.size() - 1), u,
                             index, pmf);
}

Status probe_sample_alias(const std::vector<cl::LuxAliasEntry>& table, const std::vector<float>& u,
                          std::vector<int>* index, std::vector<float>* pmf) {
  return probe_table_sampler("probe_sample_alias", table, static_cast<cl_uint>(table.size()), u,
                             index, pmf);
}

Result<std::vector<cl::float4>> probe_texture(const TexturePack& pack, int texture,
                                              const std::vector<cl::float2>& uv) {
  cl::LuxTextureSlot slot{};
  slot.m00 = slot.m11 = 1.0f;
  slot.texture = texture;
  return probe_texture_slot(pack, slot, uv, uv);
}

Result<std::vector<cl::float4>> probe_texture_slot(const TexturePack& pack,
                                                   const cl::LuxTextureSlot& slot,
                                                   const std::vector<cl::float2>& uv0,
                                                   const std::vector<cl::float2>& uv1) {
  if (uv0.size() != uv1.size()) return invalid_argument("uv0 and uv1 differ in length");
  auto program = shared_context().programs().get(kProbe, all_light_features());
  if (!program) return program.status();
  auto kernel = program.value()->kernel("probe_texture");
  if (!kernel) return kernel.status();
  auto texels = upload(pack.texels, "texels"), textures = upload(pack.textures, "textures"),
       a = upload(uv0, "uv0"), b = upload(uv1, "uv1");
  if (!texels || !textures || !a || !b) return internal_error("uploading texture queries");
  auto out = shared_context().alloc(uv0.size() * sizeof(cl::float4), "texture out");
  if (!out) return out.status();
  LUXEL_RETURN_IF_ERROR(kernel->set_args(texels.value(), textures.value(), slot, a.value(),
                                         b.value(), static_cast<int>(uv0.size()), out.value()));
  LUXEL_RETURN_IF_ERROR(shared_context().launch(kernel.value(), uv0.size()));
  std::vector<cl::float4> r;
  LUXEL_RETURN_IF_ERROR(read_back(out.value(), &r, uv0.size()));
  return r;
}

}  // namespace luxel::pipeline::test
