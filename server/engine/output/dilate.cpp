#include "output/dilate.h"

#include <array>
#include <cstdint>

namespace luxel::output {
namespace {

enum TexelState : uint8_t { kEmpty = 0, kFilled = 1, kQueued = 2 };

// Calls fn(neighbour index) for the up to 8 neighbours of texel (x, y), in a
// fixed order.
template <typename Fn>
void for_each_neighbour(int x, int y, int width, int height, Fn&& fn) {
  for (int dy = -1; dy <= 1; ++dy) {
    const int ny = y + dy;
    if (ny < 0 || ny >= height) continue;
    for (int dx = -1; dx <= 1; ++dx) {
      const int nx = x + dx;
      if ((dx == 0 && dy == 0) || nx < 0 || nx >= width) continue;
      fn(static_cast<size_t>(ny) * static_cast<size_t>(width) + static_cast<size_t>(nx));
    }
  }
}

// Fills the first `fill_channels` channels (of `stride`) of empty texels.
// Works on a frontier: only texels next to the previous ring are visited,
// so the cost is one scan plus the dilated texels, not radius full scans.
class Dilator {
 public:
  Dilator(float* pixels, int width, int height, int stride, int fill_channels,
          std::vector<uint8_t> state)
      : px_(pixels),
        w_(width),
        h_(height),
        stride_(stride),
        fill_(fill_channels),
        state_(std::move(state)) {}

  void run(int radius) {
    std::vector<size_t> ring;
    for (size_t i = 0; i < state_.size(); ++i) {
      if (state_[i] != kEmpty) continue;
      bool touches = false;
      for_each_neighbour(x_of(i), y_of(i), w_, h_,
                         [&](size_t n) { touches = touches || state_[n] == kFilled; });
      if (touches) queue(i, ring);
    }
    std::vector<float> staged;
    for (int pass = 0; pass < radius && !ring.empty(); ++pass) {
      staged.assign(ring.size() * static_cast<size_t>(fill_), 0.0f);
      for (size_t k = 0; k < ring.size(); ++k) average_neighbours(ring[k], &staged[k * fill_]);
      for (size_t k = 0; k < ring.size(); ++k) {
        for (int c = 0; c < fill_; ++c) px_[ring[k] * stride_ + c] = staged[k * fill_ + c];
        state_[ring[k]] = kFilled;
      }
      std::vector<size_t> next;
      for (size_t i : ring)
        for_each_neighbour(x_of(i), y_of(i), w_, h_, [&](size_t n) {
          if (state_[n] == kEmpty) queue(n, next);
        });
      ring.swap(next);
    }
  }

 private:
  int x_of(size_t i) const { return static_cast<int>(i % static_cast<size_t>(w_)); }
  int y_of(size_t i) const { return static_cast<int>(i / static_cast<size_t>(w_)); }
  void queue(size_t i, std::vector<size_t>& ring) {
    state_[i] = kQueued;
    ring.push_back(i);
  }

  // Only kFilled neighbours count: kQueued ones belong to the ring being
  // computed and are still empty at the start of the pass.
  void average_neighbours(size_t i, float* out) const {
    std::array<double, 64> sum{};
    int count = 0;
    for_each_neighbour(x_of(i), y_of(i), w_, h_, [&](size_t n) {
      if (state_[n] != kFilled) return;
      ++count;
      for (int c = 0; c < fill_; ++c) sum[c] += px_[n * stride_ + c];
    });
    for (int c = 0; c < fill_; ++c) out[c] = static_cast<float>(sum[c] / count);
  }

  float* px_;
  int w_, h_;
  size_t stride_;
  int fill_;
  std::vector<uint8_t> state_;
};

}  // namespace

Status dilate(Image& rgba, int radius) {
  LUXEL_RETURN_IF_ERROR(check_image(rgba, "dilate"));
  if (rgba.channels != 4)
    return invalid_argument(strprintf(
        "dilate: expected an RGBA image (coverage in channel 3), got %d channels", rgba.channels));
  if (radius < 0) return invalid_argument(strprintf("dilate: radius %d is negative", radius));
  std::vector<uint8_t> state(rgba.texel_count());
  for (size_t i = 0; i < state.size(); ++i)
    state[i] = rgba.pixels[i * 4 + 3] > 0.0f ? kFilled : kEmpty;
  Dilator(rgba.pixels.data(), rgba.width, rgba.height, 4, 3, std::move(state)).run(radius);
  return Status::ok();
}

Status dilate(Image& image, const Image& coverage, int radius) {
  LUXEL_RETURN_IF_ERROR(check_image(image, "dilate"));
  LUXEL_RETURN_IF_ERROR(check_image(coverage, "dilate coverage"));
  if (coverage.channels != 1 || coverage.width != image.width || coverage.height != image.height)
    return invalid_argument(
        strprintf("dilate: coverage image is %d x %d x %d, expected %d x %d x 1", coverage.width,
                  coverage.height, coverage.channels, image.width, image.height));
  if (radius < 0) return invalid_argument(strprintf("dilate: radius %d is negative", radius));
  std::vector<uint8_t> state(image.texel_count());
  for (size_t i = 0; i < state.size(); ++i) state[i] = coverage.pixels[i] > 0.0f ? kFilled : kEmpty;
  Dilator(image.pixels.data(), image.width, image.height, image.channels, image.channels,
          std::move(state))
      .run(radius);
  return Status::ok();
}

}  // namespace luxel::output
