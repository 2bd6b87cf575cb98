#include "shards/checkpoint.h"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>

#include "common/atomic_file.h"
#include "common/hash.h"

namespace luxel::pipeline {
namespace {

constexpr char kMagic[8] = {'L', 'U', 'X', 'C', 'K', 'P', 'T', '5'};
constexpr char kMagicV4[8] = {'L', 'U', 'X', 'C', 'K', 'P', 'T', '4'};
constexpr char kMagicV3[8] = {'L', 'U', 'X', 'C', 'K', 'P', 'T', '3'};
constexpr char kMagicV2[8] = {'L', 'U', 'X', 'C', 'K', 'P', 'T', '2'};
constexpr char kMagicV1[8] = {'L', 'U', 'X', 'C', 'K', 'P', 'T', '1'};

// The file's fields in order: counted (fd < 0: the size the checksum is
// prefixed with), or written to fd through a small buffer and hashed as
// they go, so a checkpoint of several GiB is never held twice in memory.
class Writer {
 public:
  explicit Writer(int fd = -1, uint64_t total = 0) : fd_(fd) {
    if (fd_ >= 0) hasher_.add_length(total);
  }
  template <typename T>
  void pod(const T& v) {
    raw(&v, sizeof v);
  }
  template <typename T>
  void vec(const std::vector<T>& v) {
    pod<uint64_t>(v.size());
    raw(v.data(), v.size() * sizeof(T));
  }
  void raw(const void* p, size_t n) {
    if (n == 0) return;
    size_ += n;
    if (fd_ < 0) return;
    hasher_.add_piece(p, n);
    put(p, n);
  }
  // The checksum of everything before it, unhashed itself; then the rest
  // of the buffer goes out.
  Status finish() {
    const std::string sum = hasher_.hex();
    put(sum.data(), sum.size());
    flush();
    return status_;
  }
  uint64_t size() const { return size_; }

 private:
  void put(const void* p, size_t n) {
    const auto* c = static_cast<const char*>(p);
    while (n > 0 && status_.is_ok()) {
      const size_t k = std::min(n, kBuffer - buffer_.size());
      buffer_.insert(buffer_.end(), c, c + k);
      c += k;
      n -= k;
      if (buffer_.size() == kBuffer) flush();
    }
  }
  void flush() {
    size_t done = 0;
    while (done < buffer_.size() && status_.is_ok()) {
      const ssize_t w = ::write(fd_, buffer_.data() + done, buffer_.size() - done);
      if (w < 0 && errno == EINTR) continue;
      if (w < 0)
        status_ = errno == ENOSPC || errno == EDQUOT
                      ? resource_exhausted(strprintf("checkpoint: %s", std::strerror(errno)))
                      : internal_error(strprintf("checkpoint: %s", std::strerror(errno)));
      else
        done += static_cast<size_t>(w);
    }
    buffer_.clear();
  }
  static constexpr size_t kBuffer = size_t{1} << 20;
  int fd_;
  uint64_t size_ = 0;
  Hasher hasher_;
  std::string buffer_;
  Status status_ = Status::ok();
};

class Reader {
 public:
  Reader(const std::string& b, size_t end) : b_(b), end_(end) {}
  template <typename T>
  bool pod(T& v) {
    return raw(&v, sizeof v);
  }
  template <typename T>
  bool vec(std::vector<T>& v, uint64_t max_elements) {
    uint64_t n = 0;
    if (!pod(n) || n > max_elements || n * sizeof(T) > end_ - pos_) return false;
    v.resize(n);
    return raw(v.data(), n * sizeof(T));
  }
  bool raw(void* p, size_t n) {
    if (n > end_ - pos_) return false;
    if (n == 0) return true;  // an empty vector's data() may be null
    std::memcpy(p, b_.data() + pos_, n);
    pos_ += n;
    return true;
  }
  size_t pos() const { return pos_; }

 private:
  const std::string& b_;
  size_t end_;
  size_t pos_ = 0;
};

}  // namespace

Status write_checkpoint(const std::string& path, const BakeCheckpoint& c) {
  if (c.per_texel) return internal_error("checkpoint: whole-image state is read, never written");
  const std::vector<char> fingerprint(c.fingerprint.begin(), c.fingerprint.end());
  auto fields = [&](Writer& w) {
    w.raw(kMagic, sizeof kMagic);
    w.vec(fingerprint);
    w.pod(c.width);
    w.pod(c.height);
    w.pod(c.paths_done);
    w.pod(c.iteration);
    w.pod(c.elapsed_s);
    w.pod(c.nonfinite);
    w.vec(c.series);
    w.vec(c.mean);
    w.vec(c.m2);
    w.vec(c.weight);
    w.vec(c.spp);
    w.vec(c.basis);
    w.vec(c.tile);
    w.pod(c.shard_index);
    w.pod(c.shard_count);
    w.vec(c.basis_layout);
    w.vec(c.radiance_cache);
    w.vec(c.guide);
  };
  Writer count;
  fields(count);
  // The same bytes as hashing the whole file before its checksum at once.
  return write_file_atomic_with(path, [&](int fd, const std::string&) {
    Writer w(fd, count.size());
    fields(w);
    return w.finish();
  });
}

Result<BakeCheckpoint> read_checkpoint(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return not_found(strprintf("checkpoint '%s' does not exist", path.c_str()));
  auto corrupt = [&](const char* why) {
    return data_loss(strprintf("checkpoint '%s' is corrupt (%s)", path.c_str(), why));
  };
  // One read of the whole file (a 4096^2 shard state is ~0.5 GB; reading it
  // through istreambuf_iterator byte by byte took longer than the checksum).
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  in.seekg(0, std::ios::beg);
  if (size < 0) return corrupt("unreadable");
  std::string bytes(static_cast<size_t>(size), '\0');
  if (!in.read(bytes.data(), size)) return corrupt("unreadable");
  if (bytes.size() < sizeof kMagic + 32) return corrupt("too short");
  const size_t body = bytes.size() - 32;
  if (Hasher().add(std::string_view(bytes).substr(0, body)).hex() != bytes.substr(body))
    return corrupt("checksum mismatch");
  Reader r(bytes, body);
  char magic[8];
  BakeCheckpoint c;
  std::vector<char> fp;
  const uint64_t texels_max = uint64_t{1} << 28;
  if (!r.raw(magic, sizeof magic)) return corrupt("not a Luxel checkpoint");
  const bool v1 = std::memcmp(magic, kMagicV1, sizeof kMagicV1) == 0;
  const bool v2 = std::memcmp(magic, kMagicV2, sizeof kMagicV2) == 0;
  const bool v3 = std::memcmp(magic, kMagicV3, sizeof kMagicV3) == 0;
  const bool v4_only = std::memcmp(magic, kMagicV4, sizeof kMagicV4) == 0;
  if (!v1 && !v2 && !v3 && !v4_only && std::memcmp(magic, kMagic, sizeof kMagic) != 0)
    return corrupt("not a Luxel checkpoint");
  const bool v4 = !v1 && !v2 && !v3;  // version 4 or later
  const bool v5 = v4 && !v4_only;
  c.per_texel = v1 || v2;
  if (!r.vec(fp, 4096) || !r.pod(c.width) || !r.pod(c.height) || !r.pod(c.paths_done) ||
      !r.pod(c.iteration) || !r.pod(c.elapsed_s) || !r.pod(c.nonfinite) ||
      !r.vec(c.series, texels_max) || !r.vec(c.mean, texels_max) || !r.vec(c.m2, texels_max) ||
      !r.vec(c.weight, texels_max) || !r.vec(c.spp, texels_max) ||
      (!v1 && !r.vec(c.basis, texels_max * 64)) || (!c.per_texel && !r.vec(c.tile, 64)) ||
      (v4 && (!r.pod(c.shard_index) || !r.pod(c.shard_count) || !r.vec(c.basis_layout, 64))) ||
      (v5 && (!r.vec(c.radiance_cache, texels_max) || !r.vec(c.guide, texels_max * kGuideStride))))
    return corrupt("truncated record");
  c.fingerprint.assign(fp.begin(), fp.end());
  c.series_stride = v1 ? 5 : 7;
  // Whole images (versions 1-2) or at most one entry per texel (version 3).
  const size_t texels = size_t{c.width} * c.height;
  const size_t n = c.mean.size();
  if ((c.per_texel ? n != texels : n > texels) || n == 0 || c.m2.size() != n ||
      c.weight.size() != n || c.spp.size() != n || c.series.size() % c.series_stride != 0 ||
      c.basis.size() % n != 0 || (!c.tile.empty() && c.tile.size() != kTileFields) ||
      (!c.radiance_cache.empty() && c.radiance_cache.size() != n) ||
      (!c.guide.empty() && c.guide.size() != n * kGuideStride))
    return corrupt("array sizes do not match the lightmap");
  if (c.shard_count == 0 || c.shard_index >= c.shard_count) return corrupt("invalid shard");
  return c;
}

BakeCheckpoint compact_checkpoint(const BakeCheckpoint& c, const std::vector<uint32_t>& texels) {
  BakeCheckpoint k = c;
  k.per_texel = false;
  const size_t n = texels.size();
  k.mean.resize(n);
  k.m2.resize(n);
  k.weight.resize(n);
  k.spp.resize(n);
  const size_t stride = c.mean.empty() ? 0 : c.basis.size() / c.mean.size();
  k.basis.resize(n * stride);
  for (size_t i = 0; i < n; ++i) {
    const size_t t = texels[i];
    if (t >= c.mean.size()) return {};  // not a whole image of this lightmap
    k.mean[i] = c.mean[t];
    k.m2[i] = c.m2[t];
    k.weight[i] = c.weight[t];
    k.spp[i] = c.spp[t];
    for (size_t j = 0; j < stride; ++j) k.basis[i * stride + j] = c.basis[t * stride + j];
  }
  return k;
}

BakeCheckpoint slice_checkpoint(const BakeCheckpoint& c, size_t begin, size_t end) {
  BakeCheckpoint k;
  k.fingerprint = c.fingerprint;
  k.shard_index = c.shard_index;
  k.shard_count = c.shard_count;
  k.basis_layout = c.basis_layout;
  k.width = c.width;
  k.height = c.height;
  k.paths_done = c.paths_done;
  k.iteration = c.iteration;
  k.elapsed_s = c.elapsed_s;
  k.nonfinite = c.nonfinite;
  k.mean.assign(c.mean.begin() + begin, c.mean.begin() + end);
  k.m2.assign(c.m2.begin() + begin, c.m2.begin() + end);
  k.weight.assign(c.weight.begin() + begin, c.weight.begin() + end);
  k.spp.assign(c.spp.begin() + begin, c.spp.begin() + end);
  const size_t stride = c.mean.empty() ? 0 : c.basis.size() / c.mean.size();
  k.basis.assign(c.basis.begin() + begin * stride, c.basis.begin() + end * stride);
  if (!c.radiance_cache.empty())
    k.radiance_cache.assign(c.radiance_cache.begin() + begin, c.radiance_cache.begin() + end);
  if (!c.guide.empty())
    k.guide.assign(c.guide.begin() + begin * kGuideStride, c.guide.begin() + end * kGuideStride);
  return k;
}

}  // namespace luxel::pipeline
