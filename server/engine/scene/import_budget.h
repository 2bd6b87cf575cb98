// What one glTF import may cost: bytes of memory and seconds of CPU.
//
// A count or an image size in a glTF file is only a number: a 7.9 KB file can
// declare 50 million vertices, an 8 KB one a million instances, a 90 KB PNG
// 65 million texels. The importer therefore charges every allocation it is
// about to make, from the declared counts and the bytes it spends per element
// (kBytesPer* below, measured in docs/operations.md "Import budgets"),
// before making it, and refuses with RESOURCE_EXHAUSTED naming the accessor /
// extension / image and the bytes when the charge does not fit.
//
// Charges go to an ImportMemoryPool. The daemon owns one pool that every
// upload (and every import of a stored scene for a bake) reserves from, so
// concurrent imports share one bound; an import with no pool given gets a
// private one of ImportOptions::max_import_bytes. Transient buffers are
// released when freed, the rest when the import ends (the imported Scene is
// then the scene cache's to bound, service/scene_cache.h).
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "common/status.h"

namespace luxel::scene {

// Bytes shared by the imports running at one time. Thread-safe.
class ImportMemoryPool {
 public:
  // `description` names the budget in refusals, e.g. "the daemon's import
  // memory budget (--import-memory-budget)".
  ImportMemoryPool(uint64_t capacity_bytes, std::string description);

  // Reserves `bytes` if they fit next to what is reserved; false otherwise.
  bool try_reserve(uint64_t bytes);
  void release(uint64_t bytes);

  uint64_t capacity() const { return capacity_; }
  uint64_t in_use() const { return in_use_.load(); }
  const std::string& description() const { return description_; }

 private:
  const uint64_t capacity_;
  const std::string description_;
  std::atomic<uint64_t> in_use_{0};
};

// The default import budget: 1/8 of the memory this process may use (the
// smaller of physical memory and the cgroup v2/v1 limit). 1/8 leaves the rest
// to bakes, which need several times a scene's size (BVH, device buffers,
// accumulators): ~2.9 GiB on a 24 GiB machine, which refuses the measured
// zero-filled accessor and bounds the other import bombs (docs/operations.md
// "Import budgets").
uint64_t default_import_memory_budget();

// "3221225472", "512MiB", "3GiB", "64 KiB" (also kB/MB/GB as powers of 1000).
Result<uint64_t> parse_byte_size(std::string_view text);
// "2.9 GiB (3133866803 bytes)"-style text for messages.
std::string describe_bytes(uint64_t bytes);

namespace detail {

// Bytes the importer spends per element (measured: docs/operations.md).
// Accessor reads stage components as doubles before converting
// (accessor.cpp): 8 per component, released after the read; the float result
// is 4 per component, released with the primitive.
inline constexpr uint64_t kStagingBytesPerComponent = 8;
inline constexpr uint64_t kFloatBytesPerComponent = 4;
// A primitive's working arrays per vertex: the generated index list (4),
// smooth normals (12); per index: the index list, its triangle-list copy and
// the kept list (4 each) plus the source-triangle index (4/3, rounded up).
inline constexpr uint64_t kWorkBytesPerVertex = 16;
inline constexpr uint64_t kWorkBytesPerIndex = 14;
// Mesh arrays kept per vertex: positions, normals (12 each), uv0, uv1 (8
// each), plus file_uv1 (8) and tangents (16) where the mesh has them.
inline constexpr uint64_t kMeshBytesPerVertex = 40;
// Mesh arrays kept per triangle: 3 indices, material and source triangle.
inline constexpr uint64_t kMeshBytesPerTriangle = 20;
// One EXT_mesh_gpu_instancing instance: its Instance record, the name string
// on the heap, the per-instance transform, and the vector's growth slack.
uint64_t bytes_per_instance();
// Decoded texels: the kept RGBA (4 bytes per texel for 8-bit images, 8 for
// 16-bit); stb_image's inflated rows and its output are transient
// (released after the decode, textures.cpp).

// One import's account against a pool and its deadline. Not thread-safe (one
// import runs on one thread); the pool is.
class ImportBudget {
 public:
  // `pool` may be null: a private pool of `max_bytes` is made. `timeout_s`
  // <= 0 ends the import at its first check.
  ImportBudget(ImportMemoryPool* pool, uint64_t max_bytes, uint64_t max_elements, double timeout_s);
  ~ImportBudget();
  ImportBudget(const ImportBudget&) = delete;
  ImportBudget& operator=(const ImportBudget&) = delete;

  // Reserves `bytes` that `what` ("mesh[0] primitive 0: accessor 3
  // (POSITION): 50331648 elements") is about to allocate; RESOURCE_EXHAUSTED
  // naming it, the bytes and the budget when they do not fit.
  Status reserve(uint64_t bytes, const std::string& what);
  // Gives back bytes reserved earlier (a transient buffer was freed).
  void release(uint64_t bytes);

  // DEADLINE_EXCEEDED naming `where` once the import has run past its time.
  // Reads the clock: call it once per batch of work (kDeadlineStride).
  Status check_deadline(const std::string& where) const;

  uint64_t reserved() const { return reserved_; }
  uint64_t peak() const { return peak_; }
  // Accessor elements left (ImportOptions::max_accessor_elements).
  uint64_t elements_left;

 private:
  std::unique_ptr<ImportMemoryPool> own_pool_;
  ImportMemoryPool* pool_;
  uint64_t reserved_ = 0, peak_ = 0;
  double timeout_s_;
  std::chrono::steady_clock::time_point deadline_;
};

// Loops check the deadline once per this many elements.
inline constexpr uint64_t kDeadlineStride = uint64_t{1} << 16;

// Reserves bytes for the life of a scope (a transient buffer).
class ScopedReservation {
 public:
  explicit ScopedReservation(ImportBudget* budget) : budget_(budget) {}
  ~ScopedReservation() {
    if (budget_ != nullptr) budget_->release(bytes_);
  }
  ScopedReservation(const ScopedReservation&) = delete;
  ScopedReservation& operator=(const ScopedReservation&) = delete;
  Status reserve(uint64_t bytes, const std::string& what) {
    if (budget_ == nullptr) return Status::ok();
    LUXEL_RETURN_IF_ERROR(budget_->reserve(bytes, what));
    bytes_ += bytes;
    return Status::ok();
  }
  // Takes over `bytes` the budget reserved already (released with the scope).
  void adopt(uint64_t bytes) { bytes_ += bytes; }

 private:
  ImportBudget* budget_;
  uint64_t bytes_ = 0;
};

// a * b * c and a + b, saturating at UINT64_MAX (declared counts are
// untrusted).
uint64_t mul_sat(uint64_t a, uint64_t b, uint64_t c = 1);
inline uint64_t add_sat(uint64_t a, uint64_t b) {
  return a > UINT64_MAX - b ? UINT64_MAX : a + b;
}

}  // namespace detail
}  // namespace luxel::scene
