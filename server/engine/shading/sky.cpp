// The sky: a constant radiance, or an equirectangular HDR image read with
// OpenImageIO plus the 2D distributions that importance-sample it, one per
// cell of receiver normals (shading/sky_distribution.h).
#include <OpenImageIO/imageio.h>

#include <cmath>

#include "shading/color.h"
#include "shading/light_builders.h"
#include "shading/sky_distribution.h"

namespace luxel::pipeline::detail {
namespace {

constexpr double kPi = 3.14159265358979323846;
// 16k x 8k: beyond this the float texels alone pass 1.5 GB.
constexpr uint64_t kMaxSkyTexels = uint64_t{16384} * 8192;

struct Image {
  int width = 0, height = 0;
  std::vector<float> rgb;
};

Result<Image> read_rgb(const std::string& path) {
  const std::string what = "sky image '" + path + "'";
  auto in = OIIO::ImageInput::open(path);
  if (!in) return invalid_argument(what + ": cannot read: " + OIIO::geterror());
  const OIIO::ImageSpec& spec = in->spec();
  const int channels = spec.nchannels;
  if (spec.width <= 0 || spec.height <= 0 || channels <= 0)
    return invalid_argument(strprintf("%s: empty image (%d x %d, %d channels)", what.c_str(),
                                      spec.width, spec.height, channels));
  const uint64_t texels = uint64_t(spec.width) * uint64_t(spec.height);
  if (texels > kMaxSkyTexels)
    return resource_exhausted(strprintf("%s: %d x %d texels is more than the %llu supported",
                                        what.c_str(), spec.width, spec.height,
                                        static_cast<unsigned long long>(kMaxSkyTexels)));
  std::vector<float> pixels(texels * static_cast<uint64_t>(channels));
  if (!in->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, pixels.data()))
    return invalid_argument(what + ": cannot read pixels: " + in->geterror());
  in->close();

  Image img;
  img.width = spec.width;
  img.height = spec.height;
  img.rgb.resize(texels * 3);
  for (uint64_t i = 0; i < texels; ++i) {
    const float* p = &pixels[i * static_cast<uint64_t>(channels)];
    // Grey (+ alpha) images give grey; extra channels beyond RGB are ignored.
    const Vec3 c = channels >= 3 ? Vec3{p[0], p[1], p[2]} : Vec3{p[0], p[0], p[0]};
    if (!is_finite(c) || c.x < 0 || c.y < 0 || c.z < 0)
      return invalid_argument(
          strprintf("%s: texel (%llu, %llu) = (%g, %g, %g) is not finite and non-negative",
                    what.c_str(), static_cast<unsigned long long>(i % uint64_t(spec.width)),
                    static_cast<unsigned long long>(i / uint64_t(spec.width)),
                    static_cast<double>(c.x), static_cast<double>(c.y), static_cast<double>(c.z)));
    img.rgb[i * 3] = c.x;
    img.rgb[i * 3 + 1] = c.y;
    img.rgb[i * 3 + 2] = c.z;
  }
  return img;
}

// Fills the image sky: scaled texels, marginal/conditional CDFs, means.
Status build_image_sky(const SkySettings& s, Vec3 scale, SkyData* sky) {
  auto image = read_rgb(s.equirect_path);
  if (!image) return image.status();
  const int w = image->width, h = image->height;
  sky->sky.kind = LUX_SKY_KIND_IMAGE;
  sky->sky.width = w;
  sky->sky.height = h;
  sky->texels = std::move(image->rgb);

  double lum_integral = 0;  // integral of luminance over the sphere
  Vec3 rgb_integral;
  for (int y = 0; y < h; ++y) {
    const double theta0 = kPi * y / h, theta1 = kPi * (y + 1) / h;
    const double texel_solid_angle = (2 * kPi / w) * (std::cos(theta0) - std::cos(theta1));
    for (int x = 0; x < w; ++x) {
      float* t =
          &sky->texels[(static_cast<size_t>(y) * static_cast<size_t>(w) + static_cast<size_t>(x)) *
                       3];
      const Vec3 c{t[0] * scale.x, t[1] * scale.y, t[2] * scale.z};
      if (!is_finite(c))
        return invalid_argument(
            strprintf("sky image '%s': texel (%d, %d) times color * intensity overflows a float",
                      s.equirect_path.c_str(), x, y));
      t[0] = c.x;
      t[1] = c.y;
      t[2] = c.z;
      lum_integral += luminance(c) * texel_solid_angle;
      rgb_integral = rgb_integral + c * static_cast<float>(texel_solid_angle);
    }
  }
  if (lum_integral > 0) {  // a black sky is dropped by the light table
    SkyDistributions d = build_sky_distributions(sky->texels, w, h);
    sky->sky.blocks_x = d.blocks_x;
    sky->sky.blocks_y = d.blocks_y;
    sky->sky.block_width = d.block_width;
    sky->sky.block_height = d.block_height;
    sky->sky.normal_bins = d.normal_bins;
    sky->block_cdfs = std::move(d.block_cdfs);
    sky->texel_cdfs = std::move(d.texel_cdfs);
  }
  sky->mean_luminance = lum_integral / (4 * kPi);
  sky->mean_radiance = rgb_integral * static_cast<float>(1.0 / (4 * kPi));
  return Status::ok();
}

}  // namespace

Result<SkyData> load_sky(const SkySettings& s) {
  SkyData sky;
  sky.sky.kind = LUX_SKY_KIND_NONE;
  sky.sky.light = -1;
  const double rot = s.rotation_degrees * kPi / 180.0;
  sky.sky.rotation = {static_cast<float>(std::sin(rot)), static_cast<float>(std::cos(rot)), 0, 0};
  if (s.kind == SkySettings::Kind::kNone) return sky;

  LUXEL_RETURN_IF_ERROR(check_color("sky", "color", s.color));
  LUXEL_RETURN_IF_ERROR(check_nonnegative("sky", "intensity", s.intensity));
  if (!std::isfinite(s.rotation_degrees))
    return invalid_argument(
        strprintf("sky: rotation %g degrees is not finite", double(s.rotation_degrees)));
  const Vec3 scale = s.color * s.intensity;
  if (!is_finite(scale)) return invalid_argument("sky: color * intensity overflows a float");
  sky.sky.radiance = {scale.x, scale.y, scale.z, 0};

  if (s.kind == SkySettings::Kind::kConstant) {
    sky.sky.kind = LUX_SKY_KIND_CONSTANT;
    sky.mean_luminance = luminance(scale);
    sky.mean_radiance = scale;
    return sky;
  }
  if (s.equirect_path.empty())
    return invalid_argument("sky: equirect_path is empty for an equirect sky");
  LUXEL_RETURN_IF_ERROR(build_image_sky(s, scale, &sky));
  return sky;
}

}  // namespace luxel::pipeline::detail
