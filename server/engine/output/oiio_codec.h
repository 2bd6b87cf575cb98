// Internal: encode an image into a file format in memory with OpenImageIO.
// The writers then hand the bytes to write_file_atomic, so OpenImageIO never
// writes to the destination directly (it would leave torn files on a crash).
#pragma once

#include <OpenImageIO/imageio.h>

#include <cstdint>
#include <string>
#include <vector>

#include "common/status.h"

namespace luxel::output {

// `format` is an OpenImageIO format name ("openexr", "png"); `pixels` is laid
// out as `pixel_type` x spec.nchannels, row-major, row 0 at the top. `what`
// names the output in errors.
Result<std::vector<uint8_t>> encode_with_oiio(const std::string& format,
                                              const OIIO::ImageSpec& spec,
                                              OIIO::TypeDesc pixel_type, const void* pixels,
                                              const std::string& what);

// The same encoding written into the open file `fd` from its start
// (write_file_atomic_with's temporary) instead of memory: the bytes are
// those encode_with_oiio returns.
Status encode_with_oiio_to_fd(const std::string& format, const OIIO::ImageSpec& spec,
                              OIIO::TypeDesc pixel_type, const void* pixels,
                              const std::string& what, int fd);

}  // namespace luxel::output
