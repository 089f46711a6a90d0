#include "importers/matrix.h"

#include <gtest/gtest.h>

namespace yarf::importers {
namespace {

void ExpectNear(const Vec3d& a, const Vec3d& b) {
  EXPECT_NEAR(a.x, b.x, 1e-12);
  EXPECT_NEAR(a.y, b.y, 1e-12);
  EXPECT_NEAR(a.z, b.z, 1e-12);
}

TEST(Matrix, RotateIsRightHanded) {
  ExpectNear(Matrix4::Rotate({0, 0, 1}, 90)->Point({1, 0, 0}), {0, 1, 0});
  ExpectNear(Matrix4::Rotate({0, 1, 0}, 90)->Point({0, 0, 1}), {1, 0, 0});
  EXPECT_FALSE(Matrix4::Rotate({0, 0, 0}, 90));
}

TEST(Matrix, LookAtMapsTheCameraFrame) {
  const Matrix4 m = *Matrix4::LookAt({1, 2, 3}, {1, 2, 4}, {0, 1, 0});
  ExpectNear(m.Point({0, 0, 0}), {1, 2, 3});
  ExpectNear(m.Vector({0, 0, 1}), {0, 0, 1});
  ExpectNear(m.Vector({0, 1, 0}), {0, 1, 0});
  ExpectNear(m.Vector({1, 0, 0}), {1, 0, 0});  // cross(up, dir), Mitsuba's and pbrt's x
  EXPECT_FALSE(Matrix4::LookAt({0, 0, 0}, {0, 1, 0}, {0, 1, 0}));
}

TEST(Matrix, InverseAndNormals) {
  const Matrix4 m = Matrix4::Translate({1, 2, 3}) * Matrix4::Scale({2, 4, 8});
  const Matrix4 identity = *m.Inverse() * m;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) EXPECT_NEAR(identity(i, j), i == j ? 1 : 0, 1e-12);
  ExpectNear(*m.Normal({1, 1, 0}), {0.5, 0.25, 0});
  EXPECT_DOUBLE_EQ(m.Determinant3(), 64);
  EXPECT_FALSE(Matrix4::Scale({1, 0, 1}).Inverse());
}

}  // namespace
}  // namespace yarf::importers
