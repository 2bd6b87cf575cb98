// FeatureSet: what a scene and its settings need from the kernels. It turns
// into -D build options so a compiled program contains only those code paths
// (DESIGN.md: "leave out what a scene does not need"). The features, what
// each compiles in and which take a value, are declared once in
// kernels/shared/features.h; Feature::NEE here is LUX_NEE there.
#pragma once

#include <array>
#include <string>

#include "kernels/shared/features.h"

namespace luxel::device {

// "NEE", "STACK_SIZE": the macro without LUX_.
const char* feature_name(Feature f);
// Whether the feature takes a value (STACK_SIZE=64) or is a flag (=1).
bool feature_takes_value(Feature f);

class FeatureSet {
 public:
  // value 0 turns the feature off (removes it); a flag takes 0 or 1.
  FeatureSet& set(Feature f, int value = 1);
  bool has(Feature f) const { return value(f) != 0; }
  int value(Feature f) const { return values_[static_cast<size_t>(f)]; }
  // Sets every feature of `other` to its value there (the tracer's features
  // reported with the bake's).
  FeatureSet& merge(const FeatureSet& other);

  // "-DLUX_ALPHA_MASK=1 -DLUX_STACK_SIZE=64": sorted by name, so the
  // options, and with them the program cache key, do not depend on the order
  // of the list or of the set() calls.
  std::string build_options() const;
  // "alpha_mask, stack_size=64" (or "none"), for reports; sorted as above.
  std::string describe() const;

 private:
  std::array<int, kFeatureCount> values_{};  // 0: off
};

}  // namespace luxel::device
