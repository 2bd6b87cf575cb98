// Host transforms (common/math.h): normals under mirroring transforms.
#include "common/math.h"

#include <gtest/gtest.h>

namespace luxel {
namespace {

void expect_near(Vec3 a, Vec3 b) {
  EXPECT_NEAR(a.x, b.x, 1e-6);
  EXPECT_NEAR(a.y, b.y, 1e-6);
  EXPECT_NEAR(a.z, b.z, 1e-6);
}

// glTF 2.0 §3.7.4: a mirroring node transform reverses the winding of the
// front face, while normals follow the inverse transpose. A plane facing +y
// mirrored x -> -x still faces +y, and a wall facing +x then faces -x (the
// cofactor form alone, det * inverse transpose, turned both to the back).
TEST(TransformNormal, MirroringTransformKeepsNormalsOnTheFrontFace) {
  Mat4 mirror;
  mirror.at(0, 0) = -1;
  EXPECT_EQ(front_face_sign(mirror), -1.0f);
  expect_near(transform_normal(mirror, {0, 1, 0}), {0, 1, 0});
  expect_near(transform_normal(mirror, {1, 0, 0}), {-1, 0, 0});
  // Non-uniform scale with a mirror: the inverse transpose, normalized.
  Mat4 scaled = mirror;
  scaled.at(0, 0) = -2;
  scaled.at(1, 1) = 0.5;
  const Vec3 n = normalize(Vec3{1, 1, 0});
  expect_near(transform_normal(scaled, n), normalize(Vec3{-0.5f, 2.0f, 0}));
  // A rotation (det +1) and a flattening transform (det 0) keep the sign.
  Mat4 rot;
  rot.at(0, 0) = rot.at(1, 1) = 0;
  rot.at(0, 1) = -1;
  rot.at(1, 0) = 1;
  EXPECT_EQ(front_face_sign(rot), 1.0f);
  expect_near(transform_normal(rot, {1, 0, 0}), {0, 1, 0});
  Mat4 flat;
  flat.at(1, 1) = 0;
  EXPECT_EQ(front_face_sign(flat), 1.0f);
  expect_near(transform_normal(flat, {0, 1, 0}), {0, 1, 0});
}

}  // namespace
}  // namespace luxel
