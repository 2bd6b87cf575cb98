// scene_id: the content address of an uploaded scene (CLI and daemon).
#include "common/scene_id.h"

#include <gtest/gtest.h>

#include "common/sha256.h"

namespace luxel {
namespace {

const std::string kMain = sha256_hex("main file");
const std::string kBin = sha256_hex("buffer");
const std::string kPng = sha256_hex("image");

TEST(SceneId, WithoutResourcesIsTheMainFilesSha256) {
  EXPECT_EQ(scene_id(kMain, {}), kMain);
}

TEST(SceneId, WithResourcesHashesTheSortedManifest) {
  const std::string manifest = "luxel-scene-v1\n" + kMain + "\n" + "a%20b.png\t5\t" + kPng + "\n" +
                               "scene.bin\t6\t" + kBin + "\n";
  const std::string want = sha256_hex(manifest);
  EXPECT_EQ(scene_id(kMain, {{"scene.bin", 6, kBin}, {"a%20b.png", 5, kPng}}), want);
  EXPECT_EQ(scene_id(kMain, {{"a%20b.png", 5, kPng}, {"scene.bin", 6, kBin}}), want)
      << "the order of the resources does not matter";
  EXPECT_TRUE(is_sha256_hex(want));
}

TEST(SceneId, EveryFieldOfAResourceCounts) {
  const std::string base = scene_id(kMain, {{"scene.bin", 6, kBin}});
  EXPECT_NE(scene_id(kMain, {{"scene.bin", 7, kBin}}), base);
  EXPECT_NE(scene_id(kMain, {{"scene.bin", 6, kPng}}), base);
  EXPECT_NE(scene_id(kMain, {{"scene2.bin", 6, kBin}}), base);
  EXPECT_NE(scene_id(kPng, {{"scene.bin", 6, kBin}}), base);
}

TEST(SceneId, UrisSortByteWise) {
  // 'B' (0x42) < 'a' (0x61) < 0xC3 (UTF-8 lead byte): byte order, not locale.
  const std::string manifest = "luxel-scene-v1\n" + kMain + "\n" + "B.bin\t1\t" + kBin + "\n" +
                               "a.bin\t1\t" + kBin + "\n" + "\xC3\xA9.bin\t1\t" + kBin + "\n";
  EXPECT_EQ(scene_id(kMain, {{"\xC3\xA9.bin", 1, kBin}, {"a.bin", 1, kBin}, {"B.bin", 1, kBin}}),
            sha256_hex(manifest));
}

}  // namespace
}  // namespace luxel
