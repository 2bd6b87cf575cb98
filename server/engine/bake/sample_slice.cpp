#include "bake/sample_slice.h"

namespace luxel::pipeline {

SampleSlice slice_sample_info(const atlas::SampleInfo& info, size_t begin, size_t end) {
  SampleSlice s;
  const auto& cov = info.covered_texels;
  if (begin >= end) return s;
  s.covered.assign(cov.begin() + begin, cov.begin() + end);
  const uint32_t first = info.offsets[cov[begin]];
  const size_t last = end < cov.size() ? info.offsets[cov[end]] : info.words.size();
  s.words.assign(info.words.begin() + first, info.words.begin() + last);
  s.offsets.reserve(end - begin);
  for (size_t k = begin; k < end; ++k) s.offsets.push_back(info.offsets[cov[k]] - first);
  return s;
}

}  // namespace luxel::pipeline
