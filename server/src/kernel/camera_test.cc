#include "kernel/camera.h"

#include <gtest/gtest.h>

#include <cmath>

namespace yarf {
namespace {

v1::Camera LookAlongZ(double fov) {
  v1::Camera c;
  c.mutable_origin()->set_x(1);
  c.mutable_target()->set_x(1);
  c.mutable_target()->set_z(5);
  c.mutable_up()->set_y(1);
  c.set_fov(fov);
  return c;
}

TEST(Camera, CentreRayLooksAtTheTarget) {
  const Ray r = Camera(LookAlongZ(40), 64, 64).Generate(0.5f, 0.5f, 0.5f, 0.5f);
  EXPECT_NEAR(r.direction.z, 1.0f, 1e-6f);
  EXPECT_NEAR(r.origin.x, 1.0f, 1e-6f);
}

TEST(Camera, FilmEdgeIsHalfTheFieldOfViewAlongTheSmallerAxis) {
  v1::Camera spec = LookAlongZ(40);
  spec.set_fov_axis(v1::Camera::SMALLER);
  const Camera camera(spec, 200, 100);  // smaller axis: y
  const Ray top = camera.Generate(0.5f, 0.0f, 0.5f, 0.5f);
  EXPECT_NEAR(std::atan2(top.direction.y, top.direction.z) * 180 / kPi, 20.0, 1e-3);
  const Ray right = camera.Generate(1.0f, 0.5f, 0.5f, 0.5f);
  EXPECT_NEAR(std::atan2(-right.direction.x, right.direction.z), std::atan(2 * std::tan(20 * kPi / 180)), 1e-4);
}

TEST(Camera, ThinLensFocusesEveryLensPointOnTheFocalPlane) {
  v1::Camera spec = LookAlongZ(40);
  spec.set_model(v1::Camera::THIN_LENS);
  spec.set_lens_radius(0.5);
  spec.set_focus_distance(4);
  const Camera camera(spec, 64, 64);
  const Ray a = camera.Generate(0.3f, 0.6f, 0.1f, 0.9f), b = camera.Generate(0.3f, 0.6f, 0.8f, 0.2f);
  EXPECT_GT(Length(a.origin - b.origin), 0.1f);
  const Vec3 pa = a.origin + a.direction * (4 / a.direction.z);
  const Vec3 pb = b.origin + b.direction * (4 / b.direction.z);
  EXPECT_NEAR(Length(pa - pb), 0.0f, 1e-4f);
}

TEST(Camera, RejectsDegeneratePlacement) {
  v1::Camera spec = LookAlongZ(40);
  spec.mutable_up()->set_y(0);
  spec.mutable_up()->set_z(1);
  EXPECT_ANY_THROW(Camera(spec, 8, 8));
  EXPECT_ANY_THROW(Camera(LookAlongZ(180), 8, 8));
}

}  // namespace
}  // namespace yarf
