#include "kernel/light_bvh.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "yarf/support/hash.h"

namespace yarf {
namespace {

// A light at `at`, of power `phi`, shining from normals around `w`.
LightBounds Light(Vec3 at, float phi, Vec3 w = Vec3(0, 0, 1), float cos_theta_o = -1, bool two_sided = true) {
  LightBounds b;
  b.lower = at - Vec3(0.1f, 0.1f, 0.1f);
  b.upper = at + Vec3(0.1f, 0.1f, 0.1f);
  b.phi = phi;
  b.w = w;
  b.cos_theta_o = cos_theta_o;
  b.two_sided = two_sided;
  return b;
}

std::vector<LightBounds> Grid() {
  std::vector<LightBounds> lights;
  for (int k = 0; k < 37; ++k)
    lights.push_back(Light(Vec3(float(k % 6), 1, float(k / 6)), 1.0f + float(k % 5), Vec3(0, -1, 0), 0.9f, false));
  return lights;
}

TEST(LightBvh, ProbabilitiesOfEveryLightSumToOneAndSamplesCarryThem) {
  const LightBvh bvh(Grid());
  for (uint64_t k = 0; k < 50; ++k) {
    const Vec3 p(ToUnitFloat(uint32_t(Hash(1, k) >> 32)) * 8 - 1, 0, ToUnitFloat(uint32_t(Hash(2, k) >> 32)) * 8 - 1);
    double sum = 0;
    for (uint32_t l = 0; l < 37; ++l) sum += bvh.Pmf(p, l);
    EXPECT_NEAR(sum, 1.0, 1e-4);
    for (uint64_t j = 0; j < 20; ++j) {
      float rest = -1;
      const auto picked = bvh.Sample(p, ToUnitFloat(uint32_t(Hash(3, k, j) >> 32)), rest);
      ASSERT_TRUE(picked);
      EXPECT_FLOAT_EQ(picked->second, bvh.Pmf(p, picked->first));
      EXPECT_TRUE(rest >= 0 && rest < 1);
    }
  }
}

TEST(LightBvh, NearLightsAreChosenMoreOften) {
  const LightBvh bvh(Grid());
  // Below light (0, 1, 0) the nearest lights are many times likelier than
  // the far corner's, of the same power.
  EXPECT_GT(bvh.Pmf(Vec3(0, 0, 0), 0), 10 * bvh.Pmf(Vec3(0, 0, 0), 35));
}

TEST(LightBvh, OneSidedLightsFacingAwayAreNeverChosen) {
  // Lights shining down (normals within ~25° of −y) give nothing above them.
  const LightBvh bvh(Grid());
  float rest = 0;
  EXPECT_FALSE(bvh.Sample(Vec3(2, 5, 2), 0.5f, rest));
  EXPECT_EQ(bvh.Pmf(Vec3(2, 5, 2), 3), 0.0f);
  // Two-sided, the same lights light it.
  std::vector<LightBounds> two_sided = Grid();
  for (LightBounds& b : two_sided) b.two_sided = true;
  EXPECT_TRUE(LightBvh(two_sided).Sample(Vec3(2, 5, 2), 0.5f, rest));
}

TEST(LightBvh, LightsOfNoPowerAreLeftOut) {
  const LightBvh bvh({Light(Vec3(0, 1, 0), 0), Light(Vec3(1, 1, 0), 2)});
  EXPECT_EQ(bvh.Pmf(Vec3(0, 0, 0), 0), 0.0f);
  EXPECT_FLOAT_EQ(bvh.Pmf(Vec3(0, 0, 0), 1), 1.0f);
  EXPECT_TRUE(LightBvh().Empty());
}

}  // namespace
}  // namespace yarf
