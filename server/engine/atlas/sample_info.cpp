#include "atlas/sample_info.h"

#include <algorithm>
#include <bit>

#include "kernels/shared/sample_info.h"

namespace luxel::atlas {
namespace {

static_assert(LUX_SAMPLES_PER_TEXEL == 64, "the masks are two 32-bit words");
static_assert(LUX_SAMPLE_INFO_HEADER_WORDS == 2 && LUX_SAMPLE_INFO_RECORD_WORDS == 4);
static_assert(sizeof(cl::uint) == sizeof(uint32_t));
static_assert(sizeof(cl::float2) == 8 && alignof(cl::float2) == 8);

// Texels per band: the coverage tuples of one band (16 bytes each) stay in
// the tens of megabytes even where triangles overlap a texel several times.
constexpr size_t kBandTexels = size_t{1} << 18;

struct WorldTriangles {
  std::vector<TexelTriangle> texel;  // texel-space vertices
  std::vector<uint32_t> instance, triangle;
};

// One triangle's coverage of one texel of the current band.
struct Coverage {
  uint64_t mask;
  uint32_t texel;     // index within the band
  uint32_t triangle;  // index into WorldTriangles
};

// Triangles touching each band, in world order (CSR).
struct BandLists {
  std::vector<uint32_t> first;  // band -> first entry in `triangles`
  std::vector<uint32_t> triangles;
};

BandLists bucket_by_band(const WorldTriangles& tris, int height, int band_rows) {
  const size_t bands = static_cast<size_t>((height + band_rows - 1) / band_rows);
  BandLists lists;
  lists.first.assign(bands + 1, 0);
  auto band_range = [&](size_t j, size_t* b0, size_t* b1) {
    int begin, end;
    TriangleCoverage(tris.texel[j]).rows(height, &begin, &end);
    *b0 = static_cast<size_t>(begin / band_rows);
    *b1 = end > begin ? static_cast<size_t>((end - 1) / band_rows) + 1 : *b0;
  };
  for (size_t j = 0; j < tris.texel.size(); ++j) {
    size_t b0, b1;
    band_range(j, &b0, &b1);
    for (size_t b = b0; b < b1; ++b) ++lists.first[b + 1];
  }
  for (size_t b = 0; b < bands; ++b) lists.first[b + 1] += lists.first[b];
  lists.triangles.resize(lists.first[bands]);
  std::vector<uint32_t> cursor(lists.first.begin(), lists.first.end() - 1);
  for (size_t j = 0; j < tris.texel.size(); ++j) {
    size_t b0, b1;
    band_range(j, &b0, &b1);
    for (size_t b = b0; b < b1; ++b) lists.triangles[cursor[b]++] = static_cast<uint32_t>(j);
  }
  return lists;
}

// Appends the words of every covered texel of one band; `coverage` is in
// world-triangle order, so records come out ordered by (instance, triangle).
void emit_band(const std::vector<Coverage>& coverage, const WorldTriangles& tris,
               size_t band_first_texel, size_t band_texels, SampleInfo* out,
               std::vector<uint32_t>* counts, std::vector<Coverage>* sorted) {
  counts->assign(band_texels + 1, 0);
  for (const Coverage& c : coverage) ++(*counts)[c.texel + 1];
  for (size_t t = 0; t < band_texels; ++t) (*counts)[t + 1] += (*counts)[t];
  sorted->resize(coverage.size());
  {
    std::vector<uint32_t> cursor(counts->begin(), counts->end() - 1);
    for (const Coverage& c : coverage) (*sorted)[cursor[c.texel]++] = c;
  }
  for (size_t t = 0; t < band_texels; ++t) {
    const uint32_t begin = (*counts)[t], end = (*counts)[t + 1];
    if (begin == end) continue;
    const size_t texel = band_first_texel + t;
    const size_t header = out->words.size();
    out->offsets[texel] = static_cast<uint32_t>(header);
    out->covered_texels.push_back(static_cast<uint32_t>(texel));
    out->words.resize(header + LUX_SAMPLE_INFO_HEADER_WORDS);
    uint64_t valid = 0, contested = 0;
    for (uint32_t k = begin; k < end; ++k) {
      const Coverage& c = (*sorted)[k];
      contested |= valid & c.mask;
      valid |= c.mask;
      out->words.insert(out->words.end(),
                        {static_cast<uint32_t>(c.mask), static_cast<uint32_t>(c.mask >> 32),
                         tris.instance[c.triangle], tris.triangle[c.triangle]});
    }
    out->words[header] = static_cast<uint32_t>(valid);
    out->words[header + 1] = static_cast<uint32_t>(valid >> 32);
    out->valid_samples += static_cast<uint64_t>(std::popcount(valid));
    out->contested_samples += static_cast<uint64_t>(std::popcount(contested));
    out->records += end - begin;
  }
}

}  // namespace

Result<SampleInfo> build_sample_info(const scene::Scene& scene, const Atlas& atlas,
                                     CancelToken cancel) {
  if (atlas.placements.size() != scene.instances.size())
    return invalid_argument(strprintf("atlas has %zu placements for %zu instances",
                                      atlas.placements.size(), scene.instances.size()));
  if (atlas.width < 1 || atlas.height < 1)
    return invalid_argument(strprintf("atlas size %dx%d is empty", atlas.width, atlas.height));
  const size_t width = static_cast<size_t>(atlas.width), height = static_cast<size_t>(atlas.height);
  if (width * height >= LUX_NO_SAMPLES)
    return resource_exhausted(
        strprintf("atlas %zux%zu has more texels than 32-bit indices address", width, height));
  SampleInfo info;
  info.width = atlas.width;
  info.height = atlas.height;
  info.offsets.assign(width * height, LUX_NO_SAMPLES);

  WorldTriangles tris;
  for (uint32_t i = 0; i < scene.instances.size(); ++i) {
    const scene::Mesh& mesh = scene.meshes[static_cast<size_t>(scene.instances[i].mesh)];
    if (mesh.uv1.size() != mesh.positions.size())
      return invalid_argument(strprintf("mesh '%s' has %zu lightmap UVs for %zu vertices",
                                        mesh.name.c_str(), mesh.uv1.size(), mesh.positions.size()));
    for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
      const TexelTriangle tt = texel_triangle(scene, atlas, i, t);
      if (TriangleCoverage(tt).zero_area()) {
        ++info.zero_uv_area_triangles;
        continue;
      }
      tris.texel.push_back(tt);
      tris.instance.push_back(i);
      tris.triangle.push_back(t);
    }
  }

  const int band_rows = static_cast<int>(std::max<size_t>(1, kBandTexels / width));
  const BandLists lists = bucket_by_band(tris, atlas.height, band_rows);
  std::vector<Coverage> coverage, sorted;
  std::vector<uint32_t> counts;
  for (size_t band = 0; band + 1 < lists.first.size(); ++band) {
    LUXEL_RETURN_IF_ERROR(check_cancel(cancel, "the sample info"));
    const int row0 = static_cast<int>(band) * band_rows;
    const int row1 = std::min(atlas.height, row0 + band_rows);
    coverage.clear();
    for (uint32_t k = lists.first[band]; k < lists.first[band + 1]; ++k) {
      const uint32_t j = lists.triangles[k];
      const TriangleCoverage cov(tris.texel[j]);
      int y0, y1;
      cov.rows(atlas.height, &y0, &y1);
      for (int y = std::max(y0, row0); y < std::min(y1, row1); ++y) {
        int x0, x1;
        cov.row_span(y, atlas.width, &x0, &x1);
        for (int x = x0; x < x1; ++x)
          if (const uint64_t mask = cov.texel_mask(x, y))
            coverage.push_back({mask, static_cast<uint32_t>((y - row0) * atlas.width + x), j});
      }
    }
    emit_band(coverage, tris, static_cast<size_t>(row0) * width,
              static_cast<size_t>(row1 - row0) * width, &info, &counts, &sorted);
    if (info.words.size() >= LUX_NO_SAMPLES)
      return resource_exhausted(
          strprintf("sample-info buffer for a %zux%zu atlas exceeds 2^32 words", width, height));
  }
  return info;
}

double coverage_sum(const SampleInfo& info, size_t begin, size_t end) {
  uint64_t valid = 0;
  for (size_t k = begin; k < end; ++k)
    valid += cl::lux_sample_info_count(info.words.data(), info.offsets[info.covered_texels[k]]);
  return double(valid) / double(LUX_SAMPLES_PER_TEXEL);
}

SamplePoint sample_point(const SampleInfo& info, uint32_t texel, uint32_t rank) {
  LUXEL_CHECK(texel < info.offsets.size());
  const uint32_t offset = info.offsets[texel];
  LUXEL_CHECK(offset != LUX_NO_SAMPLES);
  LUXEL_CHECK(rank < cl::lux_sample_info_count(info.words.data(), offset));
  SamplePoint p;
  cl::lux_sample_info_lookup(info.words.data(), offset, rank, &p.instance, &p.triangle,
                             &p.hammersley_index);
  const uint32_t w = static_cast<uint32_t>(info.width);
  p.x = (texel % w) + hammersley_x(p.hammersley_index);
  p.y = (texel / w) + hammersley_y(p.hammersley_index);
  return p;
}

Vec3 atlas_barycentrics(const TexelTriangle& t, double x, double y) {
  // Sub-triangle areas relative to the point: (p, v1, v2), (p, v2, v0), (p, v0, v1).
  double e[3];
  for (int k = 0; k < 3; ++k) {
    const int a = (k + 1) % 3, b = (k + 2) % 3;
    e[k] = (t.x[a] - x) * (t.y[b] - y) - (t.y[a] - y) * (t.x[b] - x);
  }
  if (e[0] + e[1] + e[2] < 0)
    for (double& v : e) v = -v;
  for (double& v : e) v = v > 0 ? v : 0;
  const double sum = e[0] + e[1] + e[2];
  if (!(sum > 0)) return {1.0f / 3, 1.0f / 3, 1.0f / 3};
  return {static_cast<float>(e[0] / sum), static_cast<float>(e[1] / sum),
          static_cast<float>(e[2] / sum)};
}

}  // namespace luxel::atlas
