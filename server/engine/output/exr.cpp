#include "output/exr.h"

#include <OpenImageIO/imageio.h>

#include <filesystem>
#include <set>

#include "common/atomic_file.h"
#include "output/oiio_codec.h"

namespace luxel::output {
namespace {

Status check_channel_names(const std::string& path, const Image& image,
                           const std::vector<std::string>& names) {
  if (names.size() != static_cast<size_t>(image.channels))
    return invalid_argument(strprintf("%s: %zu channel names given for an image with %d channels",
                                      path.c_str(), names.size(), image.channels));
  std::set<std::string> seen;
  for (const std::string& name : names) {
    if (name.empty()) return invalid_argument(strprintf("%s: empty channel name", path.c_str()));
    if (!seen.insert(name).second)
      return invalid_argument(
          strprintf("%s: channel name '%s' appears twice", path.c_str(), name.c_str()));
  }
  return Status::ok();
}

Status check_metadata_key(const std::string& path, const std::string& key) {
  if (key.empty()) return invalid_argument(strprintf("%s: empty metadata key", path.c_str()));
  if (key == "compression" || key.rfind("oiio:", 0) == 0)
    return invalid_argument(
        strprintf("%s: metadata key '%s' is reserved", path.c_str(), key.c_str()));
  return Status::ok();
}

}  // namespace

Status write_exr(const std::string& path, const Image& image,
                 const std::vector<std::string>& channel_names,
                 const std::map<std::string, std::string>& metadata) {
  if (path.empty()) return invalid_argument("write_exr: empty output path");
  LUXEL_RETURN_IF_ERROR(check_image(image, path));
  LUXEL_RETURN_IF_ERROR(check_channel_names(path, image, channel_names));

  OIIO::ImageSpec spec(image.width, image.height, image.channels, OIIO::TypeDesc::FLOAT);
  spec.channelnames = channel_names;
  // Without alpha_channel = -1 OpenImageIO would guess one from the names.
  spec.alpha_channel = -1;
  for (int c = 0; c < image.channels; ++c)
    if (channel_names[static_cast<size_t>(c)] == "A") spec.alpha_channel = c;
  // OpenImageIO stamps the current time when DateTime is unset; an empty one
  // is left out of the header, keeping files reproducible.
  spec.attribute("DateTime", "");
  for (const auto& [key, value] : metadata) {
    LUXEL_RETURN_IF_ERROR(check_metadata_key(path, key));
    spec.attribute(key, value);
  }
  spec.attribute("compression", "zip");
  // Encoded straight into the temporary file: the encoded bytes of a
  // lightmap of several GiB are not held in memory beside its pixels.
  return write_file_atomic_with(path, [&](int fd, const std::string&) {
    return encode_with_oiio_to_fd("openexr", spec, OIIO::TypeDesc::FLOAT, image.pixels.data(), path,
                                  fd);
  });
}

namespace {

// An OpenEXR file opened for reading (its header read), or why not.
Result<std::unique_ptr<OIIO::ImageInput>> open_exr(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    return not_found(strprintf("%s: no such file", path.c_str()));
  auto in = OIIO::ImageInput::open(path);
  if (!in)
    return data_loss(strprintf("%s: cannot read: %s", path.c_str(), OIIO::geterror().c_str()));
  if (std::string(in->format_name()) != "openexr")
    return invalid_argument(
        strprintf("%s: is a %s file, not OpenEXR", path.c_str(), in->format_name()));
  return in;
}

}  // namespace

Result<Image> read_exr(const std::string& path, ExrInfo* info) {
  auto opened = open_exr(path);
  if (!opened) return opened.status();
  auto& in = opened.value();
  const OIIO::ImageSpec& spec = in->spec();
  if (spec.depth > 1)
    return invalid_argument(strprintf("%s: is a volume (depth %d)", path.c_str(), spec.depth));
  LUXEL_RETURN_IF_ERROR(check_shape(spec.width, spec.height, spec.nchannels, path));
  Image image = make_image(spec.width, spec.height, spec.nchannels);
  if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, image.pixels.data()))
    return data_loss(strprintf("%s: cannot decode: %s", path.c_str(), in->geterror().c_str()));
  if (info) {
    info->channel_names = spec.channelnames;
    info->metadata.clear();
    for (const OIIO::ParamValue& p : spec.extra_attribs) {
      const std::string name = p.name().string();
      if (p.type() != OIIO::TypeDesc::STRING || name.rfind("oiio:", 0) == 0) continue;
      info->metadata[name] = p.get_string();
    }
  }
  return image;
}

Result<std::pair<int, int>> read_exr_size(const std::string& path) {
  auto in = open_exr(path);
  if (!in) return in.status();
  return std::make_pair(in.value()->spec().width, in.value()->spec().height);
}

Status write_samples_exr(const std::string& path, const Image& samples,
                         std::map<std::string, std::string> metadata) {
  LUXEL_RETURN_IF_ERROR(check_image(samples, path));
  if (samples.channels != 1)
    return invalid_argument(
        strprintf("%s: a samples map has 1 channel, got %d", path.c_str(), samples.channels));
  metadata["luxel/encoding"] = "samples_per_texel";
  return write_exr(path, samples, kLuminanceChannel, metadata);
}

}  // namespace luxel::output
