// common/hash.h: the plain FNV-1a against the published test vectors.
#include "common/hash.h"

#include <gtest/gtest.h>

namespace luxel {
namespace {

static_assert(fnv1a64("") == kFnv1aBasis);

TEST(Fnv1a, PublishedVectors) {
  EXPECT_EQ(fnv1a64(""), 0xcbf29ce484222325ull);
  EXPECT_EQ(fnv1a64("a"), 0xaf63dc4c8601ec8cull);
  EXPECT_EQ(fnv1a64("foobar"), 0x85944171f73967e8ull);
}

TEST(Fnv1a, BasisIsWhereTheHashStarts) {
  EXPECT_EQ(fnv1a64("", 42), 42u);
  EXPECT_EQ(fnv1a64("a", 42), (42u ^ 'a') * kFnv1aPrime);
}

}  // namespace
}  // namespace luxel
