// OpenEXR files of lightmap data, written and read through OpenImageIO.
//
// Files are linear (no transfer curve), 32-bit float per channel, ZIP
// compressed, scanline, one part. Channel order in the file follows OpenEXR
// (channels sorted by name); OpenImageIO hands RGBA back as R,G,B,A and the
// reader reports the names, so look channels up by name for non-RGBA files.
#pragma once

#include <map>
#include <string>
#include <utility>
#include <vector>

#include "output/image.h"

namespace luxel::output {

// Channel names for the usual layouts.
inline const std::vector<std::string> kRgbaChannels = {"R", "G", "B", "A"};
inline const std::vector<std::string> kLuminanceChannel = {"Y"};

// Writes `image` to `path` atomically (see common/atomic_file.h; nothing is left
// half-written). `channel_names` names every channel (non-empty, unique).
// `metadata` becomes string header attributes, e.g. {"luxel/encoding",
// "irradiance"}; keys "compression" and "oiio:*" are reserved. The header
// carries no time stamp unless metadata sets "DateTime", so the same pixels
// and metadata always give the same bytes.
// INVALID_ARGUMENT (naming the path) for a malformed or zero-size image, a
// channel-name count that differs from image.channels, a bad name or key, or
// an unwritable destination; INTERNAL when OpenImageIO fails to encode.
Status write_exr(const std::string& path, const Image& image,
                 const std::vector<std::string>& channel_names,
                 const std::map<std::string, std::string>& metadata = {});

// What read_exr found besides the pixels.
struct ExrInfo {
  std::vector<std::string> channel_names;  // in the order of Image::pixels
  // Every string header attribute except OpenImageIO's own "oiio:*" hints:
  // the metadata given to write_exr plus standard ones such as "compression".
  std::map<std::string, std::string> metadata;
};

// Reads the first part of an OpenEXR file, every channel converted to float.
// NOT_FOUND for a missing file, INVALID_ARGUMENT for a file that is not
// OpenEXR or is a volume, DATA_LOSS for a truncated or corrupt one.
Result<Image> read_exr(const std::string& path, ExrInfo* info = nullptr);

// The width and height in the header of an OpenEXR file, without decoding
// its pixels (a reference lightmap's size, checked at submit); the codes of
// read_exr.
Result<std::pair<int, int>> read_exr_size(const std::string& path);

// The samples-per-texel map: a single-channel image written as channel "Y"
// with "luxel/encoding" = "samples_per_texel" (plus `metadata`). Counts are
// stored as float: exact up to 2^24 samples per texel.
Status write_samples_exr(const std::string& path, const Image& samples,
                         std::map<std::string, std::string> metadata = {});

}  // namespace luxel::output
