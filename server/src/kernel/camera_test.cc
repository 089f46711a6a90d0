#include "kernel/camera.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <utility>

#include "yarf/support/chi_square.h"
#include "yarf/error.h"
#include "yarf/support/warps.h"

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
  const Ray r = Camera(LookAlongZ(40), 64, 64).Generate(0.5f, 0.5f, 0.5f, 0.5f, 0.0f);
  EXPECT_NEAR(r.direction.z, 1.0f, 1e-6f);
  EXPECT_NEAR(r.origin.x, 1.0f, 1e-6f);
}

TEST(Camera, FilmEdgeIsHalfTheFieldOfViewAlongTheSmallerAxis) {
  v1::Camera spec = LookAlongZ(40);
  spec.set_fov_axis(v1::Camera::SMALLER);
  const Camera camera(spec, 200, 100);  // smaller axis: y
  const Ray top = camera.Generate(0.5f, 0.0f, 0.5f, 0.5f, 0.0f);
  EXPECT_NEAR(std::atan2(top.direction.y, top.direction.z) * 180 / kPi, 20.0, 1e-3);
  const Ray right = camera.Generate(1.0f, 0.5f, 0.5f, 0.5f, 0.0f);
  EXPECT_NEAR(std::atan2(-right.direction.x, right.direction.z), std::atan(2 * std::tan(20 * kPi / 180)), 1e-4);
}

TEST(Camera, OrthographicRaysAreParallelAcrossTheViewSize) {
  v1::Camera spec = LookAlongZ(40);
  spec.set_model(v1::Camera::ORTHOGRAPHIC);
  spec.set_view_size(4);
  spec.set_fov_axis(v1::Camera::SMALLER);
  spec.set_near_clip(0.5);
  const Camera camera(spec, 200, 100);  // smaller axis: y, 4 units; x spans 8
  for (const auto [x, y] : {std::pair{0.5f, 0.5f}, {0.0f, 0.0f}, {1.0f, 1.0f}, {0.25f, 0.75f}}) {
    const Ray r = camera.Generate(x, y, 0.3f, 0.8f, 0.0f);
    EXPECT_NEAR(r.direction.z, 1.0f, 1e-6f);
    // Camera x runs opposite to world x here (right = forward × up).
    EXPECT_NEAR(r.origin.x, 1 - (2 * x - 1) * 4, 1e-5f);
    EXPECT_NEAR(r.origin.y, (1 - 2 * y) * 2, 1e-5f);
    EXPECT_NEAR(r.origin.z, 0.0f, 1e-6f);
    EXPECT_FLOAT_EQ(r.tnear, 0.5f);
  }
  // Light paths cannot reach it: no connection, no direction density.
  Vec3 lens;
  float fx = 0, fy = 0, importance = 0;
  EXPECT_FALSE(camera.Connect(Vec3(1, 0, 3), 0.5f, 0.5f, &lens, &fx, &fy, &importance));
  EXPECT_EQ(camera.DirectionPdf(Vec3(0, 0, 1)), 0.0f);
  // A pixel's step is the same at every depth: 8 / 200 across.
  Vec3 dpdx, dpdy;
  camera.PixelSpacing(Vec3(1, 0, 9), Vec3(0, 0, -1), &dpdx, &dpdy);
  EXPECT_NEAR(Length(dpdx), 0.04f, 1e-6f);
  EXPECT_NEAR(Length(dpdy), 0.04f, 1e-6f);
  spec.set_view_size(0);
  EXPECT_THROW(Camera(spec, 200, 100), Error);
}

TEST(Camera, ThinLensFocusesEveryLensPointOnTheFocalPlane) {
  v1::Camera spec = LookAlongZ(40);
  spec.set_model(v1::Camera::THIN_LENS);
  spec.set_lens_radius(0.5);
  spec.set_focus_distance(4);
  const Camera camera(spec, 64, 64);
  const Ray a = camera.Generate(0.3f, 0.6f, 0.1f, 0.9f, 0.0f), b = camera.Generate(0.3f, 0.6f, 0.8f, 0.2f, 0.0f);
  EXPECT_GT(Length(a.origin - b.origin), 0.1f);
  const Vec3 pa = a.origin + a.direction * (4 / a.direction.z);
  const Vec3 pb = b.origin + b.direction * (4 / b.direction.z);
  EXPECT_NEAR(Length(pa - pb), 0.0f, 1e-4f);
}

TEST(Camera, ConnectFindsTheFilmPositionWhoseRayPassesThroughThePoint) {
  for (const bool lens : {false, true}) {
    v1::Camera spec = LookAlongZ(50);
    if (lens) {
      spec.set_model(v1::Camera::THIN_LENS);
      spec.set_lens_radius(0.3);
      spec.set_focus_distance(3);
    }
    const Camera camera(spec, 80, 60);
    const Vec3 p(1.7f, -0.4f, 6.0f);
    Vec3 lens_point;
    float x = 0, y = 0, importance = 0;
    ASSERT_TRUE(camera.Connect(p, 0.2f, 0.7f, &lens_point, &x, &y, &importance)) << lens;
    const Ray ray = camera.Generate(x, y, 0.2f, 0.7f, 0.0f);
    EXPECT_NEAR(Length(ray.origin - lens_point), 0.0f, 1e-5f) << lens;
    const Vec3 to_p = Normalize(p - ray.origin);
    EXPECT_NEAR(Dot(to_p, ray.direction), 1.0f, 1e-6f) << lens;
    // 1/(A cos³θ), A the film's area at distance 1.
    const float tan_x = std::tan(25 * kPi / 180), tan_y = tan_x * 60 / 80;
    const float cos_theta = ray.direction.z;
    EXPECT_NEAR(importance, 1 / (4 * tan_x * tan_y * cos_theta * cos_theta * cos_theta), 1e-4f);
    if (!lens) {
      EXPECT_NEAR(camera.DirectionPdf(ray.direction), importance, 1e-4f);
    }
    // Behind the camera, or off the film: not seen.
    EXPECT_FALSE(camera.Connect(Vec3(1, 0, -3), 0.2f, 0.7f, &lens_point, &x, &y, &importance));
    EXPECT_FALSE(camera.Connect(Vec3(40, 0, 3), 0.2f, 0.7f, &lens_point, &x, &y, &importance));
  }
}

TEST(Camera, ShutterScalesTime) {
  v1::Camera spec = LookAlongZ(40);
  EXPECT_EQ(Camera(spec, 8, 8).Time(0.7f), 0.0f);
  spec.set_shutter(0.5);
  EXPECT_EQ(Camera(spec, 8, 8).Time(0.5f), 0.25f);
  EXPECT_EQ(Camera(spec, 8, 8).Generate(0.5f, 0.5f, 0.5f, 0.5f, 0.25f).time, 0.25f);
  spec.set_shutter(2);
  EXPECT_ANY_THROW(Camera(spec, 8, 8));
}

TEST(Camera, RejectsDegeneratePlacement) {
  v1::Camera spec = LookAlongZ(40);
  spec.mutable_up()->set_y(0);
  spec.mutable_up()->set_z(1);
  EXPECT_ANY_THROW(Camera(spec, 8, 8));
  EXPECT_ANY_THROW(Camera(LookAlongZ(180), 8, 8));
}

TEST(Camera, RadianceMeterIsOneRayAlongItsDirection) {
  v1::Camera spec;
  spec.set_model(v1::Camera::RADIANCE_METER);
  spec.mutable_origin()->set_x(1);
  spec.mutable_target()->set_x(1);
  spec.mutable_target()->set_y(3);  // along +y; up (absent) does not matter
  const Camera camera(spec, 1, 1);
  for (const auto [x, y] : {std::pair{0.5f, 0.5f}, {0.0f, 0.9f}, {0.7f, 0.1f}}) {
    const Ray r = camera.Generate(x, y, y, x, 0);
    EXPECT_EQ(r.origin.x, 1.0f);
    EXPECT_EQ(r.origin.y, 0.0f);
    EXPECT_NEAR(r.direction.y, 1.0f, 1e-7f);
    EXPECT_EQ(r.tnear, 0.0f);
  }
  EXPECT_EQ(camera.RayWeight(), 1.0f);
  EXPECT_FALSE(camera.UnreachableReason().empty());
  Vec3 lens;
  float fx = 0, fy = 0, importance = 0;
  EXPECT_FALSE(camera.Connect(Vec3(1, 2, 0), 0.5f, 0.5f, &lens, &fx, &fy, &importance));
  EXPECT_EQ(camera.DirectionPdf(Vec3(0, 1, 0)), 0.0f);
  // One value: one pixel.
  EXPECT_THROW(Camera(spec, 2, 2), Error);
  EXPECT_THROW(Camera(spec, 1, 4), Error);
  spec.mutable_target()->set_y(0);
  EXPECT_THROW(Camera(spec, 1, 1), Error);
}

// The irradiance meter's rays on a tilted quad, normal (0, -1, 1)/√2:
// origins on it, directions cosine-distributed about its normal (cos²θ and
// φ both uniform), each weighing π.
TEST(Camera, IrradianceMeterRaysLeaveItsShapeCosineDistributed) {
  TriangleMesh mesh;
  mesh.positions = {Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(2, 1, 1), Vec3(0, 1, 1)};
  mesh.indices = {0, 1, 2, 0, 2, 3};
  mesh.uvs = {0, 0, 1, 0, 1, 1, 0, 1};
  const Vec3 normal = Normalize(Vec3(0, -1, 1));
  std::vector<std::array<Vec3, 3>> corners = {{mesh.positions[0], mesh.positions[1], mesh.positions[2]},
                                               {mesh.positions[0], mesh.positions[2], mesh.positions[3]}};
  auto quad = std::make_shared<MeshSurface>(corners, std::vector<Vec3>(2, normal), mesh, false);

  v1::Camera spec;
  spec.set_model(v1::Camera::IRRADIANCE_METER);
  EXPECT_THROW(Camera(spec, 1, 1), Error);  // no meter_shape
  spec.set_meter_shape("quad");
  EXPECT_THROW(Camera(spec, 3, 1), Error);
  Camera camera(spec, 1, 1);
  camera.MeasureOn(quad);
  EXPECT_NEAR(camera.RayWeight(), kPi, 1e-6f);
  EXPECT_FALSE(camera.UnreachableReason().empty());

  constexpr int kCosBins = 10, kPhiBins = 16;
  constexpr size_t kN = 160000;
  std::vector<double> observed(kCosBins * kPhiBins, 0), expected(kCosBins * kPhiBins, double(kN) / observed.size());
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0, 0x1.fffffep-1f);
  const Frame frame(normal);
  double mean_x = 0;
  for (size_t k = 0; k < kN; ++k) {
    const Ray r = camera.Generate(u(rng), u(rng), u(rng), u(rng), 0);
    // On the quad, moved off it to its normal's side by the surface
    // offset (2e-4 here), inside it.
    EXPECT_GT(Dot(r.origin, normal), 0);
    EXPECT_LT(Dot(r.origin, normal), 2.1e-4f);
    EXPECT_GE(r.origin.x, -3e-4f);
    EXPECT_LE(r.origin.x, 2 + 3e-4f);
    EXPECT_GE(r.origin.y, -3e-4f);
    EXPECT_LE(r.origin.y, 1 + 3e-4f);
    mean_x += r.origin.x / kN;
    const Vec3 local = frame.ToLocal(r.direction);
    ASSERT_GT(local.z, 0) << "a ray leaves the back of its shape";
    float phi = std::atan2(local.y, local.x);
    if (phi < 0) phi += 2 * kPi;
    const int c = std::min(kCosBins - 1, int(local.z * local.z * kCosBins));
    const int p = std::min(kPhiBins - 1, int(phi / (2 * kPi) * kPhiBins));
    observed[c * kPhiBins + p] += 1;
  }
  EXPECT_NEAR(mean_x, 1, 0.01);
  EXPECT_TRUE(testing_support::PearsonChiSquareTest(observed, expected, 1e-3));

  // A sphere: rays leave outward from points on it.
  SphereGeometry ball;
  ball.center = Vec3(0, 0, 5);
  ball.radius = 0.5f;
  Camera on_ball(spec, 1, 1);
  on_ball.MeasureOn(std::make_shared<SphereSurface>(ball, true));
  EXPECT_NEAR(on_ball.origin().z, 5, 1e-6f);
  for (int k = 0; k < 1000; ++k) {
    const Ray r = on_ball.Generate(u(rng), u(rng), u(rng), u(rng), 0);
    EXPECT_NEAR(Length(r.origin - ball.center), 0.5f, 1e-3f);
    EXPECT_GT(Dot(r.direction, r.origin - ball.center), 0);
  }
}

// LookAlongZ's frame: forward +z, up +y, right −x.
v1::Camera Spherical(v1::Camera::SphericalMapping mapping) {
  v1::Camera spec = LookAlongZ(0);
  spec.set_model(v1::Camera::SPHERICAL);
  spec.set_spherical_mapping(mapping);
  return spec;
}

void ExpectDirection(const Camera& camera, float x, float y, Vec3 expected) {
  const Ray r = camera.Generate(x, y, 0.3f, 0.7f, 0);
  EXPECT_NEAR(r.origin.x, 1, 1e-6f);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(r.direction[i], expected[i], 1e-5f) << "film " << x << ", " << y;
}

// The share of a film grid's rays within `angle` of `axis`.
double ShareWithin(const Camera& camera, Vec3 axis, float angle) {
  constexpr int kSide = 400;
  int within = 0;
  for (int j = 0; j < kSide; ++j)
    for (int i = 0; i < kSide; ++i) {
      const Ray r = camera.Generate((i + 0.5f) / kSide, (j + 0.5f) / kSide, 0.5f, 0.5f, 0);
      within += Dot(r.direction, axis) > std::cos(angle);
    }
  return double(within) / (kSide * kSide);
}

TEST(Camera, SphericalEquirectangularMapsLatitudeDownAndLongitudeFromRightTowardForward) {
  const Camera camera(Spherical(v1::Camera::EQUIRECTANGULAR), 64, 32);
  const Vec3 right(-1, 0, 0), up(0, 1, 0), forward(0, 0, 1);
  ExpectDirection(camera, 0.3f, 0, up);
  ExpectDirection(camera, 0.6f, 1, -up);
  ExpectDirection(camera, 0, 0.5f, right);
  ExpectDirection(camera, 0.25f, 0.5f, forward);
  ExpectDirection(camera, 0.5f, 0.5f, -right);
  ExpectDirection(camera, 0.75f, 0.5f, -forward);
  // Rows are latitudes: a cap of angle a about up is the top a/π of the film.
  EXPECT_NEAR(ShareWithin(camera, up, 0.5f), 0.5 / kPi, 3e-3);
}

TEST(Camera, SphericalEqualAreaSeesTheSameSolidAngleThroughEveryPartOfTheFilm) {
  const Camera camera(Spherical(v1::Camera::EQUAL_AREA), 32, 32);
  const Vec3 right(-1, 0, 0), up(0, 1, 0), forward(0, 0, 1);
  // The map's pole, its centre, is up; its corners down; its edges' middles
  // the horizon.
  ExpectDirection(camera, 0.5f, 0.5f, up);
  ExpectDirection(camera, 0, 0, -up);
  ExpectDirection(camera, 1, 1, -up);
  ExpectDirection(camera, 0.5f, 1, forward);
  ExpectDirection(camera, 0.5f, 0, -forward);
  ExpectDirection(camera, 1, 0.5f, right);
  ExpectDirection(camera, 0, 0.5f, -right);
  // Any cone of half-angle a holds (1 − cos a)/2 of the film.
  const Vec3 axes[] = {up, -up, forward, Normalize(Vec3(1, 2, -3))};
  for (const Vec3 axis : axes)
    for (const float angle : {0.3f, 1.0f, 2.0f})
      EXPECT_NEAR(ShareWithin(camera, axis, angle), (1 - std::cos(angle)) / 2, 3e-3) << angle;
}

TEST(Camera, SphericalCameraCannotBeReachedAndRefusesUnknownMappings) {
  const Camera camera(Spherical(v1::Camera::EQUAL_AREA), 16, 16);
  EXPECT_NE(camera.UnreachableReason().find("spherical camera"), std::string_view::npos);
  Vec3 lens;
  float x, y, importance;
  EXPECT_FALSE(camera.Connect(Vec3(1, 0, 5), 0.5f, 0.5f, &lens, &x, &y, &importance));
  EXPECT_EQ(camera.DirectionPdf(Vec3(0, 0, 1)), 0);
  EXPECT_ANY_THROW(Camera(Spherical(v1::Camera::SphericalMapping(7)), 16, 16));
}

}  // namespace
}  // namespace yarf
