#include "device/feature_set.h"

#include <algorithm>
#include <cctype>
#include <cstring>

#include "common/status.h"

namespace luxel::device {
namespace {

struct FeatureInfo {
  const char* name;
  bool takes_value;
};

// The kinds of kernels/shared/features.h; another word there fails to compile.
constexpr bool kKind_flag = false;
constexpr bool kKind_value = true;

constexpr FeatureInfo kFeatures[] = {
#define LUX_FEATURE_INFO(name, kind, what) {#name, kKind_##kind},
    LUX_FEATURES(LUX_FEATURE_INFO)
#undef LUX_FEATURE_INFO
};
static_assert(std::size(kFeatures) == kFeatureCount);

// The features in name order: build_options() and describe() were sorted by
// name when features were strings, and the program cache key and the
// reports must stay as they were.
const std::array<Feature, kFeatureCount>& by_name() {
  static const std::array<Feature, kFeatureCount> order = [] {
    std::array<Feature, kFeatureCount> a;
    for (int i = 0; i < kFeatureCount; ++i) a[i] = static_cast<Feature>(i);
    std::sort(a.begin(), a.end(), [](Feature x, Feature y) {
      return std::strcmp(feature_name(x), feature_name(y)) < 0;
    });
    return a;
  }();
  return order;
}

}  // namespace

const char* feature_name(Feature f) {
  return kFeatures[static_cast<size_t>(f)].name;
}

bool feature_takes_value(Feature f) {
  return kFeatures[static_cast<size_t>(f)].takes_value;
}

FeatureSet& FeatureSet::set(Feature f, int value) {
  LUXEL_CHECK_MSG(feature_takes_value(f) || value == 0 || value == 1, "a flag feature is 0 or 1");
  values_[static_cast<size_t>(f)] = value;
  return *this;
}

FeatureSet& FeatureSet::merge(const FeatureSet& other) {
  for (int i = 0; i < kFeatureCount; ++i)
    if (other.values_[i] != 0) values_[i] = other.values_[i];
  return *this;
}

std::string FeatureSet::build_options() const {
  std::string out;
  for (Feature f : by_name()) {
    if (!has(f)) continue;
    if (!out.empty()) out += ' ';
    out += strprintf("-DLUX_%s=%d", feature_name(f), value(f));
  }
  return out;
}

std::string FeatureSet::describe() const {
  std::string out;
  for (Feature f : by_name()) {
    if (!has(f)) continue;
    if (!out.empty()) out += ", ";
    std::string lower;
    for (const char* c = feature_name(f); *c; ++c)
      lower += static_cast<char>(std::tolower(static_cast<unsigned char>(*c)));
    out += value(f) == 1 ? lower : strprintf("%s=%d", lower.c_str(), value(f));
  }
  return out.empty() ? "none" : out;
}

}  // namespace luxel::device
