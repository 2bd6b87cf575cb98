#include "output/oiio_codec.h"

#include <OpenImageIO/filesystem.h>

namespace luxel::output {

Result<std::vector<uint8_t>> encode_with_oiio(const std::string& format,
                                              const OIIO::ImageSpec& spec,
                                              OIIO::TypeDesc pixel_type, const void* pixels,
                                              const std::string& what) {
  std::vector<unsigned char> bytes;
  OIIO::Filesystem::IOVecOutput sink(bytes);
  auto out = OIIO::ImageOutput::create(format);
  if (!out)
    return internal_error(strprintf("%s: OpenImageIO has no '%s' writer: %s", what.c_str(),
                                    format.c_str(), OIIO::geterror().c_str()));
  if (!out->supports("ioproxy"))
    return internal_error(strprintf("%s: OpenImageIO's '%s' writer cannot write to memory",
                                    what.c_str(), format.c_str()));
  out->set_ioproxy(&sink);
  // The name only matters to OpenImageIO for messages; the bytes go to `sink`.
  const bool ok = out->open(what, spec) && out->write_image(pixel_type, pixels) && out->close();
  if (!ok)
    return internal_error(strprintf("%s: encoding %s failed: %s", what.c_str(), format.c_str(),
                                    out->geterror().c_str()));
  out.reset();  // done with `sink` before its buffer moves out
  return bytes;
}

}  // namespace luxel::output
