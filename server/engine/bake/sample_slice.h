// The sample-info buffer (§4.2) cut to a range of covered slots, the form
// the bake kernels read: per-texel state and paths are indexed by covered
// slot, not by texel, so the device holds records only for covered texels
// (and, when the atlas is baked in tiles, only for the tile's texels).
#pragma once

#include <cstdint>
#include <vector>

#include "atlas/sample_info.h"

namespace luxel::pipeline {

struct SampleSlice {
  std::vector<uint32_t> covered;  // texel of each slot of the range, ascending
  std::vector<uint32_t> offsets;  // first word of slot's record in `words`
  std::vector<uint32_t> words;    // the records of the range's texels, in slot order
};

// Slots [begin, end) of info.covered_texels. Records of consecutive covered
// texels are consecutive in info.words, so the slice is one copy, rebased.
SampleSlice slice_sample_info(const atlas::SampleInfo& info, size_t begin, size_t end);

}  // namespace luxel::pipeline
