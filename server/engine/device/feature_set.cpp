#include "device/feature_set.h"

#include <cctype>

#include "common/status.h"

namespace luxel::device {

FeatureSet& FeatureSet::set(const std::string& name, int value) {
  LUXEL_CHECK_MSG(!name.empty(), "empty feature name");
  for (char c : name)
    LUXEL_CHECK_MSG(std::isupper(static_cast<unsigned char>(c)) ||
                        std::isdigit(static_cast<unsigned char>(c)) || c == '_',
                    "feature names are upper-case identifiers");
  if (value == 0)
    values_.erase(name);
  else
    values_[name] = value;
  return *this;
}

int FeatureSet::value(const std::string& name) const {
  auto it = values_.find(name);
  return it == values_.end() ? 0 : it->second;
}

std::string FeatureSet::build_options() const {
  std::string out;
  for (const auto& [name, v] : values_) {
    if (!out.empty()) out += ' ';
    out += strprintf("-DLUX_%s=%d", name.c_str(), v);
  }
  return out;
}

std::string FeatureSet::describe() const {
  if (values_.empty()) return "none";
  std::string out;
  for (const auto& [name, v] : values_) {
    if (!out.empty()) out += ", ";
    std::string lower;
    for (char c : name) lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    out += v == 1 ? lower : strprintf("%s=%d", lower.c_str(), v);
  }
  return out;
}

}  // namespace luxel::device
