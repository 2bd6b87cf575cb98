// A progressive snapshot as the bake produced it, encoded on demand.
//
// The bake thread only stores the newest frame (floats, no encoding) and
// notifies; the first watcher that wants it encodes it (PNG preview or EXR
// bytes) and the result is cached in the frame for every other watcher. So
// snapshot cost grows with watchers reading, never on the bake's thread, and
// nothing is encoded for a bake nobody watches.
#pragma once

#include <mutex>
#include <optional>
#include <string>

#include "common/status.h"
#include "luxel/v1/luxel.pb.h"
#include "output/image.h"

namespace luxel::service {

class SnapshotFrame {
 public:
  // `scratch_dir` is where EXR bytes are assembled (OpenImageIO writes files).
  // `pages`: lightmap pages stacked from the top in `image` (Snapshot.pages);
  // `denoised`: the image went through the denoiser (Snapshot.denoised).
  SnapshotFrame(output::Image image, v1::BakeProgress progress, v1::SnapshotFormat format,
                int max_side, std::string scratch_dir, int pages = 1, bool denoised = false)
      : image_(std::move(image)),
        pages_(pages),
        denoised_(denoised),
        progress_(std::move(progress)),
        format_(format),
        max_side_(max_side),
        scratch_dir_(std::move(scratch_dir)) {}

  // The encoded snapshot; computed once, thread-safe.
  Result<v1::Snapshot> encoded() const;
  const v1::BakeProgress& progress() const { return progress_; }

 private:
  output::Image image_;
  int pages_;
  bool denoised_;  // Snapshot.denoised
  v1::BakeProgress progress_;
  v1::SnapshotFormat format_;
  int max_side_;
  std::string scratch_dir_;
  mutable std::mutex mu_;
  mutable std::optional<Result<v1::Snapshot>> cache_;
};

}  // namespace luxel::service
