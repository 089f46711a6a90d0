// The batched light-point kernels give, lane for lane, what the scalar
// code they stand in for gives: SampleSphereCone, and SphericalTriangle::Seen
// with SampleSphericalTriangle. Batches of odd sizes, so that partly
// filled blocks are covered.
#include "kernel/light_point_kernels.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "kernel/shape_surfaces.h"
#include "yarf/support/warps.h"

namespace yarf {
namespace {

class LightPointKernelsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!LightPointKernelsAvailable()) GTEST_SKIP() << "this CPU lacks AVX2 and FMA";
  }

  Vec3 RandomDirection() {
    const float u0 = unit_(rng_), u1 = unit_(rng_);
    return SampleUniformSphere(u0, u1);
  }
  std::vector<float> Uniform(size_t n) {
    std::vector<float> u(3 * n);
    for (float& v : u) v = unit_(rng_);
    return u;
  }

  std::mt19937 rng_{20261205};
  std::uniform_real_distribution<float> unit_{0.0f, 0x1.fffffep-1f};
};

// Directions agree to this much (their cosine to 1 - kAngle²/2).
constexpr float kAngle = 2e-3f;

TEST_F(LightPointKernelsTest, SphereConesAreTheScalarOnes) {
  std::uniform_real_distribution<float> radius(0.01f, 10.0f), distance(1.01f, 200.0f), coordinate(-50, 50);
  for (int trial = 0; trial < 40; ++trial) {
    SphereGeometry sphere;
    sphere.center = Vec3(coordinate(rng_), coordinate(rng_), coordinate(rng_));
    sphere.radius = radius(rng_);
    const Frame axes(RandomDirection());
    sphere.axes = {axes.s, axes.t, axes.n};
    sphere.flip_normals = trial % 2 == 1;
    const size_t n = 1 + size_t(trial) * 3 % 37;
    std::vector<Vec3> from(n);
    for (Vec3& p : from) p = sphere.center + RandomDirection() * (sphere.radius * distance(rng_));
    const std::vector<float> u = Uniform(n);
    std::vector<SurfaceSample> batched(n);
    SampleSphereCones(sphere, from, u, batched);
    for (size_t k = 0; k < n; ++k) {
      const SurfaceSample want = SampleSphereCone(sphere, from[k], u[3 * k + 1], u[3 * k + 2]);
      const SurfaceSample& got = batched[k];
      SCOPED_TRACE(testing::Message() << "trial " << trial << " point " << k);
      // The direction from the point is well conditioned; where it meets a
      // small, far sphere is not, in either form, so the point is held to
      // lie on the sphere with its own normal and uv.
      EXPECT_GT(Dot(Normalize(got.position - from[k]), Normalize(want.position - from[k])), 1 - kAngle * kAngle / 2);
      EXPECT_NEAR(got.pdf, want.pdf, 1e-3f * want.pdf);
      const Vec3 d = (got.position - sphere.center) / sphere.radius;
      EXPECT_NEAR(Length(d), 1.0f, 1e-4f);
      const SurfaceSample at = SpherePointAt(sphere, Normalize(d));
      EXPECT_GT(Dot(got.normal, at.normal), 1 - kAngle * kAngle / 2);
      // u wraps at φ = 0; v has no seam.
      const float du = std::abs(got.u - at.u);
      EXPECT_LT(std::min(du, 1 - du), 1e-4f);
      EXPECT_NEAR(got.v, at.v, 1e-4f);
    }
  }
}

TEST_F(LightPointKernelsTest, SphericalTrianglesAreTheScalarOnes) {
  std::uniform_real_distribution<float> coordinate(-1, 1), distance(0.05f, 20.0f);
  size_t compared = 0;
  for (int trial = 0; trial < 40; ++trial) {
    // A few random triangles, seen from points around them.
    std::vector<std::array<Vec3, 3>> corners(5);
    for (auto& triangle : corners)
      for (Vec3& v : triangle) v = Vec3(coordinate(rng_), coordinate(rng_), coordinate(rng_));
    const size_t n = 1 + size_t(trial) * 5 % 41;
    std::vector<uint32_t> triangle(n);
    std::vector<Vec3> from(n);
    for (size_t k = 0; k < n; ++k) {
      triangle[k] = uint32_t(rng_() % corners.size());
      from[k] = RandomDirection() * distance(rng_);
    }
    // One point exactly at a corner: not sampled, and no solid angle.
    from[0] = corners[triangle[0]][1];
    const std::vector<float> u = Uniform(n);
    std::vector<SphericalTriangleSample> batched(n);
    SampleSphericalTriangles(corners, triangle, from, u, batched);
    for (size_t k = 0; k < n; ++k) {
      SCOPED_TRACE(testing::Message() << "trial " << trial << " point " << k);
      const Vec3* v = corners[triangle[k]].data();
      const SphericalTriangle seen = SphericalTriangle::Seen(v, from[k]);
      std::array<float, 3> b;
      const bool sampled = seen.area > 0 && SampleSphericalTriangle(v, from[k], seen, u[3 * k + 1], u[3 * k + 2], b);
      const SphericalTriangleSample& got = batched[k];
      EXPECT_NEAR(got.solid_angle, seen.area, 1e-4f * std::max(1.0f, seen.area));
      if (k == 0) {
        EXPECT_FALSE(got.sampled);
        EXPECT_EQ(got.solid_angle, 0.0f);
        continue;
      }
      // Near-degenerate views (tiny or edge-on) may tip either way.
      if (seen.area < 1e-3f) continue;
      ASSERT_EQ(got.sampled, sampled);
      if (!sampled) continue;
      const Vec3 want_point = v[0] * b[0] + v[1] * b[1] + v[2] * b[2];
      const Vec3 got_point = v[0] * (1 - got.b1 - got.b2) + v[1] * got.b1 + v[2] * got.b2;
      EXPECT_GT(Dot(Normalize(got_point - from[k]), Normalize(want_point - from[k])), 1 - kAngle * kAngle / 2);
      EXPECT_GE(got.b1, 0.0f);
      EXPECT_GE(got.b2, 0.0f);
      EXPECT_LE(got.b1 + got.b2, 1.0f + 1e-6f);
      ++compared;
    }
  }
  EXPECT_GT(compared, 400u);
}

}  // namespace
}  // namespace yarf
