// The kernel features (kernels/shared/features.h) and FeatureSet, without a
// device: the build options keep their text and order (the program cache key
// depends on them), and the kernels test no LUX_ name the list does not know.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "device/feature_set.h"
#include "device/kernel_sources.h"

namespace luxel::device {
namespace {

struct Listed {
  std::string macro;  // "LUX_NEE"
  std::string what;
};

std::vector<Listed> listed_features() {
  return {
#define LUX_TEST_LISTED(name, kind, what) {"LUX_" #name, what},
      LUX_FEATURES(LUX_TEST_LISTED)
#undef LUX_TEST_LISTED
  };
}

TEST(FeatureSet, BuildOptionsAreSortedAndOmitDisabledFeatures) {
  FeatureSet f;
  f.set(Feature::STACK_SIZE, 64).set(Feature::ALPHA_MASK).set(Feature::SKY, 1).set(Feature::SKY, 0);
  EXPECT_EQ(f.build_options(), "-DLUX_ALPHA_MASK=1 -DLUX_STACK_SIZE=64");
  EXPECT_EQ(f.describe(), "alpha_mask, stack_size=64");
  EXPECT_FALSE(f.has(Feature::SKY));
  EXPECT_EQ(FeatureSet().build_options(), "");
  EXPECT_EQ(FeatureSet().describe(), "none");
}

// The options are sorted by name, not by the order of the list (which is
// grouped by subsystem): SKY sorts before SKY_IMAGE, BVH4 before COMPACTION,
// PRIM_ITEMS before PRIM_LOCAL_REORDER before PRIM_WG.
TEST(FeatureSet, OptionsFollowNameOrder) {
  FeatureSet f;
  f.set(Feature::SKY_IMAGE)
      .set(Feature::SKY)
      .set(Feature::COMPACTION)
      .set(Feature::BVH4)
      .set(Feature::PRIM_WG, 128)
      .set(Feature::PRIM_ITEMS, 8)
      .set(Feature::PRIM_LOCAL_REORDER);
  EXPECT_EQ(f.build_options(),
            "-DLUX_BVH4=1 -DLUX_COMPACTION=1 -DLUX_PRIM_ITEMS=8 -DLUX_PRIM_LOCAL_REORDER=1 "
            "-DLUX_PRIM_WG=128 -DLUX_SKY=1 -DLUX_SKY_IMAGE=1");
  EXPECT_EQ(f.describe(),
            "bvh4, compaction, prim_items=8, prim_local_reorder, prim_wg=128, sky, sky_image");
}

TEST(FeatureSet, MergeTakesTheOtherSetsFeatures) {
  FeatureSet bake, tracer;
  bake.set(Feature::NEE).set(Feature::STACK_SIZE, 16);
  tracer.set(Feature::STACK_SIZE, 40).set(Feature::INTERSECTOR_EMBREE);
  bake.merge(tracer);
  EXPECT_EQ(bake.describe(), "intersector_embree, nee, stack_size=40");
  EXPECT_EQ(tracer.describe(), "intersector_embree, stack_size=40");
}

TEST(Features, NamesAndKindsComeFromTheList) {
  const auto listed = listed_features();
  ASSERT_EQ(listed.size(), size_t(kFeatureCount));
  for (int i = 0; i < kFeatureCount; ++i) {
    const auto f = static_cast<Feature>(i);
    EXPECT_EQ("LUX_" + std::string(feature_name(f)), listed[size_t(i)].macro);
    EXPECT_FALSE(listed[size_t(i)].what.empty()) << feature_name(f);
  }
  EXPECT_TRUE(feature_takes_value(Feature::STACK_SIZE));
  EXPECT_TRUE(feature_takes_value(Feature::PRIM_WG));
  EXPECT_TRUE(feature_takes_value(Feature::PRIM_ITEMS));
  EXPECT_FALSE(feature_takes_value(Feature::NEE));
}

// A kernel file without comments, continuation lines joined.
std::string strip_comments(std::string_view text) {
  std::string out;
  for (size_t i = 0; i < text.size(); ++i) {
    if (text.compare(i, 2, "/*") == 0) {
      const size_t end = text.find("*/", i + 2);
      i = end == std::string_view::npos ? text.size() : end + 1;
      out += ' ';
    } else if (text.compare(i, 2, "//") == 0) {
      while (i + 1 < text.size() && text[i + 1] != '\n') ++i;
    } else if (text.compare(i, 2, "\\\n") == 0) {
      ++i;
      out += ' ';
    } else {
      out += text[i];
    }
  }
  return out;
}

// The identifiers of `text` that start with LUX_.
std::vector<std::string> lux_names(std::string_view text) {
  std::vector<std::string> out;
  auto ident = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; };
  for (size_t i = 0; i < text.size();) {
    if (!ident(text[i])) {
      ++i;
      continue;
    }
    size_t end = i;
    while (end < text.size() && ident(text[end])) ++end;
    if (text.compare(i, 4, "LUX_") == 0) out.emplace_back(text.substr(i, end - i));
    i = end;
  }
  return out;
}

struct Directive {
  std::string where;    // "bake/raygen.h: #if LUX_PROBES"
  std::string keyword;  // "if", "define", ...
  std::string rest;     // what follows the keyword
};

// The preprocessor lines of every kernel file.
std::vector<Directive> directives() {
  std::vector<Directive> out;
  for (const EmbeddedKernelFile& file : embedded_kernel_files()) {
    const std::string text = strip_comments(file.text);
    size_t at = 0;
    while (at < text.size()) {
      size_t end = text.find('\n', at);
      if (end == std::string::npos) end = text.size();
      const std::string line = text.substr(at, end - at);
      at = end + 1;
      size_t k = line.find_first_not_of(" \t");
      if (k == std::string::npos || line[k] != '#') continue;
      k = line.find_first_not_of(" \t", k + 1);
      if (k == std::string::npos) continue;
      const size_t word_end = std::min(line.find_first_of(" \t(", k), line.size());
      out.push_back({std::string(file.path) + ": " + line, line.substr(k, word_end - k),
                     line.substr(word_end)});
    }
  }
  return out;
}

// A misspelt `#if LUX_SKY_IMGE` would compile its code path out without a
// word: every LUX_ name in a condition must be a feature or a macro that some
// kernel file defines.
TEST(Features, KernelConditionsNameOnlyKnownMacros) {
  std::set<std::string> known;
  for (const Listed& l : listed_features()) known.insert(l.macro);
  const auto lines = directives();
  for (const Directive& d : lines)
    if (d.keyword == "define")
      for (const std::string& n : lux_names(d.rest)) {
        known.insert(n);  // the defined name is the first
        break;
      }
  size_t checked = 0;
  for (const Directive& d : lines) {
    if (d.keyword != "if" && d.keyword != "ifdef" && d.keyword != "ifndef" && d.keyword != "elif")
      continue;
    for (const std::string& n : lux_names(d.rest)) {
      ++checked;
      EXPECT_TRUE(known.count(n)) << n << " in " << d.where;
    }
  }
  EXPECT_GT(checked, 50u);  // the scan found the kernels' feature tests
}

// The other direction: a feature no kernel reads is marked "host:" in its
// line of the list (it only keys the program cache or the reports).
TEST(Features, EveryFeatureIsReadByAKernelOrMarkedHost) {
  std::set<std::string> used;
  for (const EmbeddedKernelFile& file : embedded_kernel_files())
    for (std::string& n : lux_names(strip_comments(file.text))) used.insert(std::move(n));
  for (const Listed& l : listed_features()) {
    const bool host = l.what.rfind("host:", 0) == 0;
    EXPECT_NE(used.count(l.macro) != 0, host) << l.macro << ": " << l.what;
  }
}

}  // namespace
}  // namespace luxel::device
