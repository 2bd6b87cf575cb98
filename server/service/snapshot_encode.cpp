#include "service/snapshot_encode.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "output/exr.h"
#include "output/preview.h"
#include "service/files.h"

namespace luxel::service {

Result<v1::Snapshot> SnapshotFrame::encoded() const {
  std::lock_guard<std::mutex> lock(mu_);
  if (cache_) return *cache_;
  v1::Snapshot snap;
  snap.set_format(format_);
  if (pages_ > 1) snap.set_pages(static_cast<uint32_t>(pages_));
  snap.set_denoised(denoised_);
  *snap.mutable_progress() = progress_;
  if (format_ == v1::SNAPSHOT_FORMAT_EXR) {
    const std::string path = scratch_dir_ + "/snapshot-" + random_hex_id() + ".exr";
    Status st =
        output::write_exr(path, image_, output::kRgbaChannels,
                          {{"luxel/encoding", "irradiance"}, {"luxel/snapshot", "progressive"}});
    auto bytes = st.is_ok() ? read_whole_file(path) : Result<std::string>(st);
    std::remove(path.c_str());
    if (!bytes) {
      cache_ = bytes.status();
      return *cache_;
    }
    snap.set_width(static_cast<uint32_t>(image_.width));
    snap.set_height(static_cast<uint32_t>(image_.height));
    snap.set_data(std::move(bytes.value()));
  } else {
    auto png = output::encode_png_preview(image_, max_side_);
    if (!png) {
      cache_ = png.status();
      return *cache_;
    }
    // Same arithmetic as output::downscale_box: aspect kept, never enlarged.
    const int longest = std::max(image_.width, image_.height);
    const int side = std::min(longest, max_side_);
    auto scaled = [&](int n) {
      return static_cast<uint32_t>(std::max(1L, std::lround(double(n) * side / longest)));
    };
    snap.set_width(scaled(image_.width));
    snap.set_height(scaled(image_.height));
    snap.set_data(png->data(), png->size());
  }
  cache_ = snap;
  return snap;
}

}  // namespace luxel::service
