// The shading-normal rules of yarf/support/shading.h: the frame's orientation,
// side agreement and the importance correction.
#include "yarf/support/shading.h"

#include <gtest/gtest.h>

namespace yarf {
namespace {

Hit HitWith(Vec3 ng, Vec3 ns) {
  Hit hit;
  hit.shape = 0;
  hit.normal = ng;
  hit.shading_normal = ns;
  hit.dpdu = Vec3(1, 0, 0);
  return hit;
}

TEST(Shading, TheFrameIsTheShadingNormal) {
  const Vec3 ng = Normalize(Vec3(0.2f, -0.3f, 0.9f)), ns = Normalize(Vec3(0.5f, -0.3f, 0.8f));
  const Frame frame = ShadingFrame(HitWith(ng, ns));
  EXPECT_NEAR(Dot(frame.n, ns), 1, 1e-6);
  EXPECT_FLOAT_EQ(ImportanceShadingFactor(Vec3(0, 0.6f, 0.8f), Vec3(0.8f, 0, 0.6f), Vec3(0, 0, 1), Vec3(0, 0, 1)), 1);
}

TEST(Shading, FrameFollowsDpduAndIsOrthonormal) {
  Hit hit = HitWith(Vec3(0, 0, 1), Normalize(Vec3(0.1f, 0, 1)));
  hit.dpdu = Vec3(2, 0.5f, 0);
  const Frame frame = ShadingFrame(hit);
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
