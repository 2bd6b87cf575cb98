// See import_budget.h.
#include "scene/import_budget.h"

#include <unistd.h>

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <optional>
#include <string>

#include "common/math.h"
#include "scene/scene.h"

namespace luxel::scene {
namespace {

// The cgroup memory limit of this process, 0 when there is none: cgroup v2
// memory.max ("max" = none), else cgroup v1 memory.limit_in_bytes (a huge
// number = none).
uint64_t cgroup_limit() {
  for (const char* path :
       {"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"}) {
    std::ifstream f(path);
    std::string text;
    if (!(f >> text) || text == "max") continue;
    char* end = nullptr;
    const unsigned long long v = std::strtoull(text.c_str(), &end, 10);
    if (end != nullptr && *end == '\0' && v > 0 && v < (uint64_t{1} << 60)) return v;
  }
  return 0;
}

uint64_t physical_memory() {
  const long pages = sysconf(_SC_PHYS_PAGES);
  const long page = sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || page <= 0) return uint64_t{8} << 30;  // unknown: assume 8 GiB
  return static_cast<uint64_t>(pages) * static_cast<uint64_t>(page);
}

}  // namespace

ImportMemoryPool::ImportMemoryPool(uint64_t capacity_bytes, std::string description)
    : capacity_(capacity_bytes), description_(std::move(description)) {}

bool ImportMemoryPool::try_reserve(uint64_t bytes) {
  uint64_t cur = in_use_.load();
  do {
    if (bytes > capacity_ || cur > capacity_ - bytes) return false;
  } while (!in_use_.compare_exchange_weak(cur, cur + bytes));
  return true;
}

void ImportMemoryPool::release(uint64_t bytes) {
  in_use_.fetch_sub(bytes);
}

uint64_t default_import_memory_budget() {
  static const uint64_t budget = [] {
    uint64_t mem = physical_memory();
    const uint64_t cg = cgroup_limit();
    if (cg > 0 && cg < mem) mem = cg;
    return mem / 8;
  }();
  return budget;
}

Result<uint64_t> parse_byte_size(std::string_view text) {
  auto bad = [&] {
    return invalid_argument("'" + std::string(text) +
                            "' is not a size in bytes (e.g. 3221225472, 512MiB, 3GiB)");
  };
  size_t i = 0;
  uint64_t v = 0;
  while (i < text.size() && std::isdigit(static_cast<unsigned char>(text[i]))) {
    const uint64_t d = static_cast<uint64_t>(text[i] - '0');
    if (v > (std::numeric_limits<uint64_t>::max() - d) / 10) return bad();
    v = v * 10 + d;
    ++i;
  }
  if (i == 0) return bad();
  // A decimal ("1.5GiB", "2e9"): read again as a double; the bytes it
  // gives must be whole.
  std::optional<double> decimal;
  if (i < text.size() && (text[i] == '.' || text[i] == 'e' || text[i] == 'E')) {
    const std::string number(text.substr(0, text.find_first_not_of("0123456789.eE+-")));
    char* end = nullptr;
    const double d = std::strtod(number.c_str(), &end);
    if (end != number.c_str() + number.size() || !(d >= 0) || !std::isfinite(d)) return bad();
    decimal = d;
    i = number.size();
  }
  while (i < text.size() && text[i] == ' ') ++i;
  const std::string_view unit = text.substr(i);
  static const struct {
    const char* name;
    uint64_t scale;
  } kUnits[] = {{"", 1},
                {"B", 1},
                {"KiB", uint64_t{1} << 10},
                {"MiB", uint64_t{1} << 20},
                {"GiB", uint64_t{1} << 30},
                {"TiB", uint64_t{1} << 40},
                {"kB", 1000},
                {"KB", 1000},
                {"MB", 1000000},
                {"GB", 1000000000},
                {"TB", 1000000000000}};
  for (const auto& u : kUnits) {
    if (unit != u.name) continue;
    if (decimal) {
      const double bytes = *decimal * static_cast<double>(u.scale);
      // 2^64 is exactly representable: anything below it converts.
      if (!(bytes < 18446744073709551616.0) || bytes != std::floor(bytes)) return bad();
      return static_cast<uint64_t>(bytes);
    }
    if (v > std::numeric_limits<uint64_t>::max() / u.scale) return bad();
    return v * u.scale;
  }
  return bad();
}

std::string describe_bytes(uint64_t bytes) {
  const double b = static_cast<double>(bytes);
  if (bytes >= (uint64_t{1} << 30))
    return strprintf("%.1f GiB (%llu bytes)", b / double(uint64_t{1} << 30),
                     static_cast<unsigned long long>(bytes));
  if (bytes >= (uint64_t{1} << 20))
    return strprintf("%.1f MiB (%llu bytes)", b / double(uint64_t{1} << 20),
                     static_cast<unsigned long long>(bytes));
  return strprintf("%llu bytes", static_cast<unsigned long long>(bytes));
}

namespace detail {

uint64_t bytes_per_instance() {
  // Instance record, twice for the vector's doubling; the name's heap block
  // ("node 'x' instance 123456", ~32 bytes with malloc's header); one Mat4.
  return 2 * sizeof(Instance) + 48 + sizeof(Mat4);
}

uint64_t mul_sat(uint64_t a, uint64_t b, uint64_t c) {
  uint64_t r = 0;
  if (__builtin_mul_overflow(a, b, &r) || __builtin_mul_overflow(r, c, &r))
    return std::numeric_limits<uint64_t>::max();
  return r;
}

ImportBudget::ImportBudget(ImportMemoryPool* pool, uint64_t max_bytes, uint64_t max_elements,
                           double timeout_s)
    : elements_left(max_elements), pool_(pool), timeout_s_(timeout_s) {
  if (pool_ == nullptr) {
    // (The CLI's budget is the default, ImportOptions::max_import_bytes.)
    own_pool_ = std::make_unique<ImportMemoryPool>(max_bytes, "the import memory budget");
    pool_ = own_pool_.get();
  }
  const auto now = std::chrono::steady_clock::now();
  // Beyond ~30 years counts as no limit (and keeps the addition in range).
  deadline_ = timeout_s > 0 && timeout_s < 1e9
                  ? now + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                              std::chrono::duration<double>(timeout_s))
              : timeout_s <= 0 ? now
                               : std::chrono::steady_clock::time_point::max();
}

ImportBudget::~ImportBudget() {
  pool_->release(reserved_);
}

Status ImportBudget::reserve(uint64_t bytes, const std::string& what) {
  if (pool_->try_reserve(bytes)) {
    reserved_ += bytes;
    peak_ = std::max(peak_, reserved_);
    return Status::ok();
  }
  const uint64_t cap = pool_->capacity();
  // Over the whole budget by itself, or over what the other imports leave.
  const bool alone = bytes > cap || reserved_ > cap - bytes;
  if (alone) {
    return resource_exhausted(
        strprintf("%s: needs %s, which with the %s the import already holds exceeds %s of %s",
                  what.c_str(), describe_bytes(bytes).c_str(), describe_bytes(reserved_).c_str(),
                  pool_->description().c_str(), describe_bytes(cap).c_str()));
  }
  const uint64_t used = pool_->in_use();
  return resource_exhausted(
      strprintf("%s: needs %s, but %s of %s has %s left while other imports run (retry later)",
                what.c_str(), describe_bytes(bytes).c_str(), pool_->description().c_str(),
                describe_bytes(cap).c_str(), describe_bytes(used >= cap ? 0 : cap - used).c_str()));
}

void ImportBudget::release(uint64_t bytes) {
  bytes = std::min(bytes, reserved_);
  reserved_ -= bytes;
  pool_->release(bytes);
}

Status ImportBudget::check_deadline(const std::string& where) const {
  if (std::chrono::steady_clock::now() < deadline_) return Status::ok();
  return deadline_exceeded(
      strprintf("%s: the import ran past its time limit of %g s (luxeld --import-timeout)",
                where.c_str(), timeout_s_ > 0 ? timeout_s_ : 0.0));
}

}  // namespace detail
}  // namespace luxel::scene
