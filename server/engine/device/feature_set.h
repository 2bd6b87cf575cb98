// FeatureSet: what a scene and its settings need from the kernels. It turns
// into -D build options so a compiled program contains only those code paths
// (DESIGN.md: "leave out what a scene does not need"). A feature that is off
// is simply not defined, so kernels test it with `#if LUX_<NAME>`.
#pragma once

#include <map>
#include <string>

namespace luxel::device {

class FeatureSet {
 public:
  // name: upper-case identifier without the LUX_ prefix, e.g. "ALPHA_MASK".
  // value 0 turns the feature off (removes it).
  FeatureSet& set(const std::string& name, int value = 1);
  bool has(const std::string& name) const { return values_.count(name) != 0; }
  int value(const std::string& name) const;

  // "-DLUX_ALPHA_MASK=1 -DLUX_STACK_SIZE=64", sorted, deterministic.
  std::string build_options() const;
  // "alpha_mask, stack_size=64" (or "none"), for reports.
  std::string describe() const;
  const std::map<std::string, int>& values() const { return values_; }

 private:
  std::map<std::string, int> values_;
};

}  // namespace luxel::device
