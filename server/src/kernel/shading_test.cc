// The shading-normal rules of yarf/shading.h: the bend that keeps views
// from reflecting below the surface, the frame's orientation, side
// agreement and the importance correction.
#include "yarf/shading.h"

#include <gtest/gtest.h>

#include <random>

namespace yarf {
namespace {

Vec3 Reflect(Vec3 wi, Vec3 n) { return n * (2 * Dot(wi, n)) - wi; }

Vec3 RandomUnit(std::mt19937& rng) {
  std::normal_distribution<float> normal;
  return Normalize(Vec3(normal(rng), normal(rng), normal(rng)));
}

Hit HitWith(Vec3 ng, Vec3 ns) {
  Hit hit;
  hit.shape = 0;
  hit.normal = ng;
  hit.shading_normal = ns;
  hit.dpdu = Vec3(1, 0, 0);
  return hit;
}

TEST(Shading, FlatSurfacesKeepTheirNormal) {
  const Vec3 ng = Normalize(Vec3(0.2f, -0.3f, 0.9f));
  for (const Vec3 wi : {Normalize(Vec3(0, 0.1f, 1)), Normalize(Vec3(1, 0, 0.01f)), Normalize(Vec3(0, -1, -0.5f))}) {
    const Vec3 n = ShadingNormalSeenFrom(HitWith(ng, ng), wi);
    EXPECT_NEAR(Dot(n, ng), 1, 1e-6);
  }
  EXPECT_FLOAT_EQ(ImportanceShadingFactor(Vec3(0, 0.6f, 0.8f), Vec3(0.8f, 0, 0.6f), Vec3(0, 0, 1), Vec3(0, 0, 1)), 1);
}

TEST(Shading, BentNormalsReflectEveryViewAboveTheSurface) {
  std::mt19937 rng(7);
  int bent = 0;
  for (int i = 0; i < 20000; ++i) {
    const Vec3 ng = RandomUnit(rng);
    // Shading normals up to ~70° from the geometric one.
    Vec3 ns = Normalize(ng + RandomUnit(rng) * 1.2f);
    if (Dot(ns, ng) <= 0.05f) continue;
    Vec3 wi = RandomUnit(rng);
    if (std::abs(Dot(wi, ng)) < 1e-3f) continue;
    const Hit hit = HitWith(ng, ns);
    const Vec3 n = ShadingNormalSeenFrom(hit, wi);
    ASSERT_NEAR(Length(n), 1, 1e-4);
    // Outward, as the geometric normal, whichever side wi lies on.
    EXPECT_GT(Dot(n, ng), 0);
    const float side = Dot(wi, ng) > 0 ? 1.0f : -1.0f;
    const float iz = side * Dot(wi, ng);
    const float height = side * Dot(Reflect(wi, n), ng);
    EXPECT_GE(height, std::min(0.9f * iz, 0.01f) - 2e-4f) << "view " << i;
    // The view itself is in front of the shading plane: no black pixels.
    EXPECT_GT(side * Dot(wi, n), 0) << "view " << i;
    if (Dot(n, ns) < 1 - 1e-5f) {
      ++bent;
      // Bent no further than needed: between ns and ng, at the threshold.
      EXPECT_NEAR(height, std::min(0.9f * iz, 0.01f), 2e-3f) << "view " << i;
    }
  }
  EXPECT_GT(bent, 100);  // the rule was exercised
}

TEST(Shading, FrameFollowsDpduAndIsOrthonormal) {
  Hit hit = HitWith(Vec3(0, 0, 1), Normalize(Vec3(0.1f, 0, 1)));
  hit.dpdu = Vec3(2, 0.5f, 0);
  const Frame frame = ShadingFrame(hit, Vec3(0, 0, 1));
  EXPECT_NEAR(Dot(frame.n, hit.shading_normal), 1, 1e-6);
  EXPECT_NEAR(Dot(frame.s, frame.n), 0, 1e-6);
  EXPECT_NEAR(Dot(frame.t, frame.n), 0, 1e-6);
  EXPECT_NEAR(Length(frame.s), 1, 1e-6);
  EXPECT_NEAR(Length(frame.t), 1, 1e-6);
  EXPECT_GT(Dot(frame.s, hit.dpdu), 0);
  EXPECT_NEAR(Dot(Cross(frame.s, frame.t), frame.n), 1, 1e-5);
}

TEST(Shading, SidesAgreeOnlyWhenBothNormalsSeeTheSameScattering) {
  const Vec3 ng(0, 0, 1);
  // A reflection for ng and for the shading frame.
  EXPECT_TRUE(SidesAgree(Vec3(0, 0.6f, 0.8f), Vec3(0.6f, 0, 0.8f), ng, 0.7f, 0.9f));
  // Reflection for ng, transmission in the shading frame: refused.
  EXPECT_FALSE(SidesAgree(Vec3(0, 0.6f, 0.8f), Vec3(0.99f, 0, 0.05f), ng, 0.7f, -0.1f));
  // Transmission for both.
  EXPECT_TRUE(SidesAgree(Vec3(0, 0.6f, 0.8f), Vec3(0, 0, -1), ng, 0.7f, -0.9f));
}

TEST(Shading, ImportanceFactorIsVeachsAdjointCorrection) {
  const Vec3 ng(0, 0, 1), ns = Normalize(Vec3(0.3f, 0, 1));
  const Vec3 wi = Normalize(Vec3(-0.5f, 0.2f, 0.6f)), wo = Normalize(Vec3(0.4f, -0.3f, 0.5f));
  const float expected = std::abs(Dot(wi, ns)) * std::abs(Dot(wo, ng)) / (std::abs(Dot(wi, ng)) * std::abs(Dot(wo, ns)));
  EXPECT_NEAR(ImportanceShadingFactor(wi, wo, ng, ns), expected, 1e-6);
  EXPECT_EQ(ImportanceShadingFactor(Vec3(1, 0, 0), wo, ng, ns), 0);  // grazing wi: no finite factor
}

}  // namespace
}  // namespace yarf
