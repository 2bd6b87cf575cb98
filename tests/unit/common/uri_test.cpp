// percent_decode_uri: the one decoder of glTF file uris (importer, daemon
// upload checks, CLI upload).
#include "common/uri.h"

#include <gtest/gtest.h>

namespace luxel {
namespace {

std::string decoded(const std::string& uri) {
  auto r = percent_decode_uri(uri);
  EXPECT_TRUE(r.is_ok()) << uri << ": " << r.status().to_string();
  return r.is_ok() ? r.value() : std::string();
}

void expect_refused(const std::string& uri, const std::string& escape) {
  auto r = percent_decode_uri(uri);
  ASSERT_FALSE(r.is_ok()) << uri << " decoded to '" << r.value() << "'";
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
  const std::string& m = r.status().message();
  EXPECT_NE(m.find("'" + uri + "'"), std::string::npos) << "uri not named: " << m;
  EXPECT_NE(m.find(escape), std::string::npos) << "escape '" << escape << "' not named: " << m;
}

TEST(PercentDecodeUri, PlainUrisAreUnchanged) {
  EXPECT_EQ(decoded(""), "");
  EXPECT_EQ(decoded("textures/wood.png"), "textures/wood.png");
  EXPECT_EQ(decoded("a+b.bin"), "a+b.bin") << "'+' is not a space in a URI";
  EXPECT_EQ(decoded("a%2Bb.bin"), "a+b.bin");
}

TEST(PercentDecodeUri, DecodesEscapesOfEitherCase) {
  EXPECT_EQ(decoded("my%20tex.png"), "my tex.png");
  EXPECT_EQ(decoded("%41%62%7a%7A"), "Abzz");
  EXPECT_EQ(decoded("%2e%2e/x"), "../x") << "decoded first, so path checks see the real name";
  EXPECT_EQ(decoded("100%25.png"), "100%.png");
  EXPECT_EQ(decoded("%25zz"), "%zz") << "decoded once, not twice";
}

TEST(PercentDecodeUri, Utf8PassesThroughRawOrEscaped) {
  EXPECT_EQ(decoded("caf\xC3\xA9.png"), "caf\xC3\xA9.png");
  EXPECT_EQ(decoded("caf%C3%A9.png"), "caf\xC3\xA9.png");
  EXPECT_EQ(decoded("%E6%9C%A8/%F0%9F%8C%B2.png"), "\xE6\x9C\xA8/\xF0\x9F\x8C\xB2.png");
}

TEST(PercentDecodeUri, MalformedEscapesAreRefusedNamingTheUri) {
  expect_refused("%", "'%'");
  expect_refused("tex.png%", "'%'");
  expect_refused("%4", "'%4'");
  expect_refused("a%4", "'%4'");
  expect_refused("%zz.png", "'%zz'");
  expect_refused("a%g1.png", "'%g1'");
  expect_refused("a%1g.png", "'%1g'");
  expect_refused("a% 1.png", "'% 1'");
  expect_refused("ok%20then%x", "'%x'");
}

TEST(PercentDecodeUri, EscapedNulIsRefused) {
  expect_refused("%00", "%00");
  expect_refused("a.png%00.txt", "%00");
  EXPECT_EQ(decoded("%01"), "\x01") << "only NUL is refused among control bytes";
}

}  // namespace
}  // namespace luxel
