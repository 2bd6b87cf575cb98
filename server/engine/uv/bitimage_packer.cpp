// The BitImage packer (bitimage_packer.h). Over 500 lines: the masks, padding,
// first-fit search over 64-bit rows and resume are one algorithm (thesis §4.1)
// over one row representation.
#include "uv/bitimage_packer.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>

namespace luxel::uv {
namespace {

constexpr int kWordBits = 64;

int words_for(int bits) {
  return (bits + kWordBits - 1) / kWordBits;
}

// A bit per texel, rows padded to whole 64-bit words so every row starts at a
// word boundary (thesis §4.1.1, Table 4.1: the aligned layout tests fastest).
struct BitImage {
  int width = 0, height = 0, stride = 0;  // stride: words per row
  std::vector<uint64_t> bits;

  BitImage() = default;
  BitImage(int w, int h, int extra_words = 0)
      : width(w),
        height(h),
        stride(words_for(w) + extra_words),
        bits(static_cast<size_t>(stride) * static_cast<size_t>(h), 0) {}
  uint64_t* row(int y) { return bits.data() + static_cast<size_t>(y) * stride; }
  const uint64_t* row(int y) const { return bits.data() + static_cast<size_t>(y) * stride; }
  bool get(int x, int y) const { return (row(y)[x >> 6] >> (x & 63)) & 1; }
  bool operator==(const BitImage& o) const {
    return width == o.width && height == o.height && bits == o.bits;
  }
};

// Sets bits [begin, end) of a row.
void set_span(uint64_t* row, int begin, int end) {
  for (int x = begin; x < end;) {
    const int word = x >> 6, bit = x & 63;
    const int n = std::min(end - x, kWordBits - bit);
    const uint64_t m = n == kWordBits ? ~0ull : ((1ull << n) - 1) << bit;
    row[word] |= m;
    x += n;
  }
}

// dst |= src << shift (towards higher x), dst having room for the result.
void or_shifted(uint64_t* dst, int dst_words, const uint64_t* src, int src_words, int shift) {
  const int q = shift >> 6, s = shift & 63;
  for (int i = 0; i < src_words; ++i) {
    if (i + q < dst_words) dst[i + q] |= src[i] << s;
    if (s != 0 && i + q + 1 < dst_words) dst[i + q + 1] |= src[i] >> (kWordBits - s);
  }
}

// First set bit at or after x (the row must hold a set bit at or after x).
int next_one(const uint64_t* row, int x) {
  int q = x >> 6;
  uint64_t w = row[q] & (~0ull << (x & 63));
  while (w == 0) w = row[++q];
  return q * kWordBits + std::countr_zero(w);
}

// First set bit in [x, limit), or a value >= limit when there is none.
int next_one_before(const uint64_t* row, int x, int limit) {
  int q = x >> 6;
  uint64_t w = row[q] & (~0ull << (x & 63));
  const int last = (limit - 1) >> 6;
  while (w == 0) {
    if (++q > last) return limit;
    w = row[q];
  }
  return q * kWordBits + std::countr_zero(w);
}

// First clear bit at or after x, or `limit` when none is below it.
int next_zero(const uint64_t* row, int x, int limit) {
  if (x >= limit) return limit;
  int q = x >> 6;
  uint64_t w = ~row[q] & (~0ull << (x & 63));
  const int last = (limit - 1) >> 6;
  while (w == 0) {
    if (++q > last) return limit;
    w = ~row[q];
  }
  return std::min(limit, q * kWordBits + std::countr_zero(w));
}

// The 64 texels of an atlas row starting at bit x (an unaligned load from two
// words, thesis §4.1.3; the atlas keeps a spare word at the end of each row).
uint64_t load_bits(const uint64_t* row, int x) {
  const int q = x >> 6, s = x & 63;
  return s == 0 ? row[q] : (row[q] >> s) | (row[q + 1] << (kWordBits - s));
}

// --- Conservative rasterisation -------------------------------------------

struct DVec2 {
  double x, y;
};

// Marks every texel of `mask` whose square, widened by kMaskSlopTexels, meets
// the closed triangle. Per row the triangle is clipped to the widened strip;
// a convex set inside the strip meets a box of the strip exactly when its x
// range meets the box's, so the row's texels are one exact span.
void rasterise_triangle(const DVec2 t[3], BitImage* mask) {
  const double e = kMaskSlopTexels;
  const double ymin = std::min({t[0].y, t[1].y, t[2].y});
  const double ymax = std::max({t[0].y, t[1].y, t[2].y});
  const int j0 = std::max(0, static_cast<int>(std::ceil(ymin - 1 - e)));
  const int j1 = std::min(mask->height - 1, static_cast<int>(std::floor(ymax + e)));
  for (int j = j0; j <= j1; ++j) {
    const double lo = j - e, hi = j + 1 + e;
    double xmin = std::numeric_limits<double>::infinity(), xmax = -xmin;
    for (int k = 0; k < 3; ++k) {
      const DVec2 a = t[k], b = t[(k + 1) % 3];
      if (a.y >= lo && a.y <= hi) xmin = std::min(xmin, a.x), xmax = std::max(xmax, a.x);
      for (const double c : {lo, hi}) {
        if ((a.y < c && b.y > c) || (a.y > c && b.y < c)) {
          const double x = a.x + (c - a.y) / (b.y - a.y) * (b.x - a.x);
          xmin = std::min(xmin, x), xmax = std::max(xmax, x);
        }
      }
    }
    if (!(xmin <= xmax)) continue;
    const int i0 = std::max(0, static_cast<int>(std::ceil(xmin - 1 - e)));
    const int i1 = std::min(mask->width - 1, static_cast<int>(std::floor(xmax + e)));
    if (i0 <= i1) set_span(mask->row(j), i0, i1 + 1);
  }
}

// The image turned by rotate(., 1): texel (i, j) of a w x h mask goes to
// (h - 1 - j, i) of the h x w result (the centring fraction makes the turn of
// the mask the mask of the turned shape; see ShapeGeometry).
BitImage rotate_quarter(const BitImage& m) {
  BitImage r(m.height, m.width);
  for (int j = 0; j < m.height; ++j) {
    for (int i = 0; i < m.width; ++i) {
      if (m.get(i, j)) r.row(i)[(m.height - 1 - j) >> 6] |= 1ull << ((m.height - 1 - j) & 63);
    }
  }
  return r;
}

// The mask dilated by p texels in Chebyshev distance: (w + 2p) x (h + 2p),
// the original at (p, p). With one_sided, the dilation reaches only towards
// +x and +y: (w + p) x (h + p), the original at (0, 0).
BitImage dilate(const BitImage& m, int p, bool one_sided) {
  const int grow = one_sided ? p : 2 * p;
  BitImage horizontal(m.width + grow, m.height);
  for (int j = 0; j < m.height; ++j) {
    for (int s = 0; s <= grow; ++s) {
      or_shifted(horizontal.row(j), horizontal.stride, m.row(j), m.stride, s);
    }
  }
  BitImage out(m.width + grow, m.height + grow);
  for (int j = 0; j < m.height; ++j) {
    for (int s = 0; s <= grow; ++s) {
      uint64_t* dst = out.row(j + s);
      const uint64_t* src = horizontal.row(j);
      for (int k = 0; k < out.stride; ++k) dst[k] |= src[k];
    }
  }
  return out;
}

long long popcount(const BitImage& m) {
  long long n = 0;
  for (const uint64_t w : m.bits) n += std::popcount(w);
  return n;
}

// --- Shapes -----------------------------------------------------------------

// One distinct rotation of a shape, ready to be placed.
struct Variant {
  int rotation = 0;
  double shift[2] = {0, 0};  // rotate(p) + shift = position within the mask
  BitImage mask;             // undilated conservative mask
  BitImage dilated;          // mask dilated by the padding
  // Per row of `dilated`: its longest run of set texels (start, length). A
  // position is possible only where every such run lands on free texels,
  // which is cheap to search for (next_fit) before the full test.
  std::vector<int> run_start, run_length;
  int min_run = 0;
};

struct ShapeInfo {
  std::vector<Variant> variants;
  long long covered = 0;    // mask texels
  long long footprint = 0;  // one-sided dilated mask texels
  // Size bucket (thesis §4.1, step 5): 4 per octave of the mask perimeter
  // rather than the thesis's perimeter / 16, so small charts, the many, get
  // fine buckets and large ones, which restart the search, coarse ones.
  int bucket = 0;
};

DVec2 rotate(DVec2 p, int k) {
  switch (k & 3) {
    case 1:
      return {-p.y, p.x};
    case 2:
      return {-p.x, -p.y};
    case 3:
      return {p.y, -p.x};
    default:
      return p;
  }
}

void longest_runs(Variant* v) {
  const BitImage& d = v->dilated;
  v->run_start.assign(d.height, 0);
  v->run_length.assign(d.height, 0);
  v->min_run = std::numeric_limits<int>::max();
  for (int j = 0; j < d.height; ++j) {
    int best_start = 0, best_len = 0;
    for (int i = 0; i < d.width;) {
      if (!d.get(i, j)) {
        ++i;
        continue;
      }
      int k = i;
      while (k < d.width && d.get(k, j)) ++k;
      if (k - i > best_len) best_start = i, best_len = k - i;
      i = k;
    }
    v->run_start[j] = best_start;
    v->run_length[j] = best_len;
    v->min_run = std::min(v->min_run, best_len);
  }
}

// Rasterises shape `index` at rotation 0 in a frame that centres it in its
// mask: local = p - bbox_min + f, f = (n - extent) / 2 per axis, with
// n = floor(extent + 2e) + 1 texels, so every corner is more than e inside
// the mask's outer texels. Turning p by a quarter turn swaps and mirrors the
// axes of that frame exactly (local'.x = n_y - local.y), hence the turned
// masks are the turned image, not a second rasterisation.
Result<ShapeInfo> build_shape(const PackShape& shape, size_t index, int padding, int max_side) {
  const size_t n_corners = shape.corners.size();
  if (n_corners == 0 || n_corners % 3 != 0) {
    return invalid_argument(
        strprintf("shape %zu: %zu corners (want 3 per triangle, at least 3)", index, n_corners));
  }
  std::vector<DVec2> p(n_corners);
  for (size_t c = 0; c < n_corners; ++c) {
    p[c] = {shape.corners[c].x, shape.corners[c].y};
    if (!std::isfinite(p[c].x) || !std::isfinite(p[c].y)) {
      return invalid_argument(strprintf("shape %zu corner %zu is not finite", index, c));
    }
  }
  ShapeInfo info;
  const int rotations = shape.allow_rotation ? 4 : 1;
  for (int k = 0; k < rotations; ++k) {
    double lo[2] = {std::numeric_limits<double>::infinity(),
                    std::numeric_limits<double>::infinity()};
    double hi[2] = {-lo[0], -lo[1]};
    for (const DVec2& c : p) {
      const DVec2 r = rotate(c, k);
      lo[0] = std::min(lo[0], r.x), hi[0] = std::max(hi[0], r.x);
      lo[1] = std::min(lo[1], r.y), hi[1] = std::max(hi[1], r.y);
    }
    Variant v;
    v.rotation = k;
    int n[2];
    for (int a = 0; a < 2; ++a) {
      const double extent = hi[a] - lo[a];
      const double cells = std::floor(extent + 2 * kMaskSlopTexels) + 1;
      if (!(cells + 2.0 * padding <= max_side)) {
        return resource_exhausted(
            strprintf("shape %zu spans %.1f texels, more than fits an atlas of %d with padding %d",
                      index, extent, max_side, padding));
      }
      n[a] = static_cast<int>(cells);
      v.shift[a] = -lo[a] + (n[a] - extent) / 2;
    }
    if (k == 0) {
      v.mask = BitImage(n[0], n[1]);
      for (size_t t = 0; t < n_corners; t += 3) {
        DVec2 tri[3];
        for (int c = 0; c < 3; ++c) tri[c] = {p[t + c].x + v.shift[0], p[t + c].y + v.shift[1]};
        rasterise_triangle(tri, &v.mask);
      }
      info.covered = popcount(v.mask);
      info.footprint = popcount(dilate(v.mask, padding, /*one_sided=*/true));
      info.bucket = static_cast<int>(std::floor(4 * std::log2(2.0 * (n[0] + n[1]))));
    } else {
      v.mask = rotate_quarter(info.variants.back().mask);
      LUXEL_CHECK(v.mask.width == n[0] && v.mask.height == n[1]);
    }
    v.dilated = dilate(v.mask, padding, /*one_sided=*/false);
    info.variants.push_back(std::move(v));
  }
  // Symmetric shapes (a square, a rectangle turned by a half turn) repeat a
  // mask; searching it twice would only cost time.
  std::vector<Variant> distinct;
  for (Variant& v : info.variants) {
    const bool seen = std::any_of(distinct.begin(), distinct.end(),
                                  [&](const Variant& d) { return d.mask == v.mask; });
    if (!seen) distinct.push_back(std::move(v));
  }
  info.variants = std::move(distinct);
  for (Variant& v : info.variants) longest_runs(&v);
  return info;
}

// --- The atlas --------------------------------------------------------------

class Atlas {
 public:
  // Texels beyond the width are marked occupied, so run searches stop at the
  // border without a bounds test; one spare word per row serves load_bits.
  Atlas(int width, int height) : image_(width, height, 1), max_free_(height, width) {
    for (int y = 0; y < height; ++y) set_span(image_.row(y), width, image_.stride * kWordBits);
  }

  // First position (x, y) of v's dilated mask, in row-major order, from
  // (start_y, start_x) on and before (bound_y, bound_x), where the dilated
  // mask misses every occupied texel. False when there is none.
  bool find(const Variant& v, int start_y, int start_x, int bound_y, int bound_x, int* out_x,
            int* out_y) const {
    const BitImage& d = v.dilated;
    const int x_last = image_.width - d.width, y_last = std::min(image_.height - d.height, bound_y);
    for (int y = start_y; y <= y_last; ++y) {
      // Rows whose longest free run is too short for the run they would meet
      // rule out this y; one shorter than every run rules out every y that
      // covers it.
      int blocked = -1;
      for (int r = d.height - 1; r >= 0; --r) {
        const int free = max_free_[y + r];
        if (free < v.run_length[r]) {
          blocked = free < v.min_run ? y + r : y;
          break;
        }
      }
      if (blocked >= 0) {
        y = blocked;
        continue;
      }
      const int x_end = y == bound_y ? std::min(x_last, bound_x - 1) : x_last;
      if (find_in_row(v, y, y == start_y ? start_x : 0, x_end, out_x)) {
        *out_y = y;
        return true;
      }
    }
    return false;
  }

  void insert(const BitImage& mask, int x, int y) {
    for (int j = 0; j < mask.height; ++j) {
      uint64_t* row = image_.row(y + j);
      or_shifted(row + (x >> 6), image_.stride - (x >> 6), mask.row(j), mask.stride, x & 63);
      max_free_[y + j] = longest_free_run(row);
    }
  }

 private:
  bool find_in_row(const Variant& v, int y, int x_begin, int x_end, int* out_x) const {
    const BitImage& d = v.dilated;
    int x = x_begin, agreed = 0, r = 0;
    while (x <= x_end) {
      // Move x until every row's longest run lands on free texels.
      const int fit =
          next_fit(image_.row(y + r), x + v.run_start[r], v.run_length[r]) - v.run_start[r];
      if (fit != x) {
        x = fit;
        agreed = 1;
      } else if (++agreed >= d.height) {
        if (fits(d, x, y)) {
          *out_x = x;
          return true;
        }
        ++x;
        agreed = 0;
      }
      r = r + 1 == d.height ? 0 : r + 1;
    }
    return false;
  }

  bool fits(const BitImage& d, int x, int y) const {
    for (int j = 0; j < d.height; ++j) {
      const uint64_t* a = image_.row(y + j);
      const uint64_t* m = d.row(j);
      for (int k = 0; k < d.stride; ++k) {
        if (m[k] != 0 && (load_bits(a, x + k * kWordBits) & m[k]) != 0) return false;
      }
    }
    return true;
  }

  // First x >= start with texels [x, x + len) free; beyond the width when
  // there is none (the occupied texels past the border end every run).
  int next_fit(const uint64_t* row, int start, int len) const {
    if (len == 0) return start;  // an empty row (a shape in separate pieces)
    for (int x = start;;) {
      const int zero = next_zero(row, x, image_.width);
      if (zero >= image_.width) return image_.width;
      // Only the first `len` texels matter: free space runs on for long.
      const int one = next_one_before(row, zero, zero + len);
      if (one - zero >= len) return zero;
      x = one;
    }
  }

  int longest_free_run(const uint64_t* row) const {
    int best = 0;
    for (int x = 0; x < image_.width;) {
      const int zero = next_zero(row, x, image_.width);
      if (zero >= image_.width) break;
      const int one = next_one(row, zero);
      best = std::max(best, one - zero);
      x = one;
    }
    return best;
  }

  BitImage image_;
  std::vector<int> max_free_;  // per row: longest run of free texels
};

// Places every shape in a width x height atlas; false at the first shape
// that does not fit.
bool place_all(const std::vector<ShapeInfo>& shapes, const std::vector<size_t>& order, int width,
               int height, int padding, std::vector<ShapePlacement>* placements) {
  Atlas atlas(width, height);
  placements->assign(shapes.size(), {});
  // Thesis §4.1, steps 5-6: a chart in the same size bucket as the one before
  // resumes the search where that one was placed (it would rarely fit the
  // holes that one passed over); a smaller bucket starts again at the top to
  // fill the holes left between larger charts. Without this, every chart
  // would scan the whole filled part of the atlas.
  int resume_x = 0, resume_y = 0, bucket = std::numeric_limits<int>::max();
  for (const size_t s : order) {
    const ShapeInfo& shape = shapes[s];
    if (shape.bucket < bucket) resume_x = resume_y = 0;
    bucket = shape.bucket;
    // Each turn at its first fit; the one whose bottom edge is highest wins
    // (then the leftmost, then the first), so a later turn need only be
    // searched above the best bottom so far.
    int best_x = 0, best_y = height, best_bottom = height + 1, best_v = -1;
    for (size_t vi = 0; vi < shape.variants.size(); ++vi) {
      const int dh = shape.variants[vi].dilated.height;
      int x = 0, y = 0;
      if (atlas.find(shape.variants[vi], resume_y, resume_x, best_bottom - dh,
                     best_v < 0 ? width : best_x, &x, &y)) {
        best_x = x, best_y = y, best_bottom = y + dh, best_v = static_cast<int>(vi);
      }
    }
    if (best_v < 0) return false;
    resume_x = best_x, resume_y = best_y;
    const Variant& v = shape.variants[best_v];
    atlas.insert(v.mask, best_x + padding, best_y + padding);
    ShapePlacement& out = (*placements)[s];
    out.rotation = v.rotation;
    out.mask_origin[0] = best_x + padding;
    out.mask_origin[1] = best_y + padding;
    out.mask_size[0] = v.mask.width;
    out.mask_size[1] = v.mask.height;
    out.offset[0] = out.mask_origin[0] + v.shift[0];
    out.offset[1] = out.mask_origin[1] + v.shift[1];
  }
  return true;
}

// The automatic size starts where the footprints would cover kStartDensity
// of the atlas and grows by kGrowth per failed attempt. First fit reaches
// 85-88 % footprint density on mixed synthetic charts (bench_uv_pack), so
// most packs fit at the first or second size.
constexpr double kStartDensity = 0.88;
constexpr double kGrowth = 1.025;

int round_up_to_4(double v) {
  return static_cast<int>(std::ceil(v / 4.0)) * 4;
}

}  // namespace

Result<PackResult> pack_shapes(const std::vector<PackShape>& shapes, const PackOptions& options) {
  const int padding = options.padding_texels;
  if (padding < 0) return invalid_argument(strprintf("padding_texels %d is negative", padding));
  if (options.max_resolution < 1) {
    return invalid_argument(strprintf("max_resolution %d is not positive", options.max_resolution));
  }
  const bool fixed = options.width != 0 || options.height != 0;
  if (fixed &&
      (options.width <= 0 || options.height <= 0 || options.width > options.max_resolution ||
       options.height > options.max_resolution)) {
    return invalid_argument(
        strprintf("atlas size %d x %d: want both in [1, max_resolution %d] or both 0",
                  options.width, options.height, options.max_resolution));
  }
  const int max_side = fixed ? std::max(options.width, options.height) : options.max_resolution;

  std::vector<ShapeInfo> infos;
  infos.reserve(shapes.size());
  long long covered = 0, footprint = 0;
  int smallest_side = 1;  // no atlas below the largest shape's smallest dilated extent
  for (size_t i = 0; i < shapes.size(); ++i) {
    Result<ShapeInfo> info = build_shape(shapes[i], i, padding, max_side);
    if (!info) return info.status();
    covered += info->covered;
    footprint += info->footprint;
    int side = std::numeric_limits<int>::max();
    for (const Variant& v : info->variants)
      side = std::min(side, std::max(v.dilated.width, v.dilated.height));
    smallest_side = std::max(smallest_side, side);
    infos.push_back(std::move(info.value()));
  }

  // Largest first (thesis §4.1, step 4): by perimeter bucket, within one by
  // mask area, ties by input order so the result depends on nothing else.
  std::vector<size_t> order(shapes.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    if (infos[a].bucket != infos[b].bucket) return infos[a].bucket > infos[b].bucket;
    return infos[a].covered > infos[b].covered;
  });

  PackResult result;
  LUXEL_RETURN_IF_ERROR(check_cancel(options.cancel, "UV packing"));
  if (fixed) {
    result.width = options.width, result.height = options.height, result.attempts = 1;
    if (!place_all(infos, order, result.width, result.height, padding, &result.placements)) {
      return resource_exhausted(strprintf("%zu shapes with padding %d do not fit %d x %d texels",
                                          shapes.size(), padding, result.width, result.height));
    }
  } else {
    const int limit = options.max_resolution / 4 * 4;
    int side = std::max({4, round_up_to_4(std::sqrt(footprint / kStartDensity) + padding),
                         round_up_to_4(smallest_side)});
    for (;;) {
      if (side > limit) {
        return resource_exhausted(strprintf(
            "%zu shapes with padding %d need an atlas of at least %d x %d texels, more than "
            "max_resolution %d",
            shapes.size(), padding, side, side, options.max_resolution));
      }
      ++result.attempts;
      LUXEL_RETURN_IF_ERROR(check_cancel(options.cancel, "UV packing"));
      if (place_all(infos, order, side, side, padding, &result.placements)) break;
      const int next = std::max(side + 4, round_up_to_4(side * kGrowth));
      // The last size tried below the limit is the limit itself.
      side = side < limit && next > limit ? limit : next;
    }
    result.width = result.height = side;
  }
  result.covered_texels = covered;
  result.footprint_texels = footprint;
  result.efficiency =
      static_cast<double>(covered) / (static_cast<double>(result.width) * result.height);
  return result;
}

}  // namespace luxel::uv
