#include "output/oiio_codec.h"

#include <OpenImageIO/filesystem.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

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

Status encode_with_oiio_to_fd(const std::string& format, const OIIO::ImageSpec& spec,
                              OIIO::TypeDesc pixel_type, const void* pixels,
                              const std::string& what, int fd) {
  // A stream of its own on a duplicate of fd: closing it leaves fd open.
  const int own = ::dup(fd);
  FILE* file = own >= 0 ? ::fdopen(own, "w+b") : nullptr;
  if (!file) {
    if (own >= 0) ::close(own);
    return internal_error(
        strprintf("%s: cannot open a stream to write: %s", what.c_str(), std::strerror(errno)));
  }
  bool ok = false;
  std::string error;
  {
    OIIO::Filesystem::IOFile sink(file, OIIO::Filesystem::IOProxy::Write);
    auto out = OIIO::ImageOutput::create(format);
    if (!out) {
      std::fclose(file);
      return internal_error(strprintf("%s: OpenImageIO has no '%s' writer: %s", what.c_str(),
                                      format.c_str(), OIIO::geterror().c_str()));
    }
    if (!out->supports("ioproxy")) {
      std::fclose(file);
      return internal_error(strprintf("%s: OpenImageIO's '%s' writer cannot write to a stream",
                                      what.c_str(), format.c_str()));
    }
    out->set_ioproxy(&sink);
    ok = out->open(what, spec) && out->write_image(pixel_type, pixels) && out->close();
    if (!ok) error = out->geterror();
  }
  const bool flushed = std::fflush(file) == 0 && !std::ferror(file);
  const int err = errno;
  std::fclose(file);
  if (!ok)
    return internal_error(
        strprintf("%s: encoding %s failed: %s", what.c_str(), format.c_str(), error.c_str()));
  if (!flushed)
    return err == ENOSPC || err == EDQUOT
               ? resource_exhausted(
                     strprintf("cannot write '%s': %s", what.c_str(), std::strerror(err)))
               : internal_error(
                     strprintf("cannot write '%s': %s", what.c_str(), std::strerror(err)));
  return Status::ok();
}

}  // namespace luxel::output
