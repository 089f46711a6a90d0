// The hair fibre model: lossless without absorption (its lobes and
// attenuations share out all the light), sampled by its own pdf, darker
// the more melanin, and refusing what it cannot use.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "surface_test_support.h"

namespace yarf::surface_testing {
namespace {

class HairTest : public SurfacePluginTest {};

// Incoming directions: along, across and oblique to the fibre (x), from
// either side of the normal (z), so that the offset h takes many values.
std::vector<Vec3> FibreDirections() {
  std::vector<Vec3> out;
  for (const double cos_theta : {0.9, 0.3, -0.2, -0.7})
    for (const double phi : {0.4, 1.3, 2.6, -1.0, -2.2}) out.push_back(DirectionAt(cos_theta, phi));
  return out;
}

Properties Lossless(double beta_m, double beta_n, double alpha) {
  return Props({{"beta_m", beta_m}, {"beta_n", beta_n}, {"alpha", alpha}, {"sigma_a", 0.0}});
}

TEST_F(HairTest, WithoutAbsorptionNoLightIsLost) {
  for (const double beta_m : {0.2, 0.7})
    for (const double beta_n : {0.2, 0.6})
      for (const double alpha : {0.0, 2.0}) {
        const auto model = Make("hair", Lossless(beta_m, beta_n, alpha));
        // Half the directions each, the untilted the even ones, the tilted the odd.
        const std::vector<Vec3> directions = FibreDirections();
        for (size_t d = alpha == 0 ? 0 : 1; d < directions.size(); d += 2) {
          const Vec3 wi = directions[d];
          const SphereIntegrals integral = IntegrateOverSphere(*model, wi);
          const std::string where = "beta_m " + std::to_string(beta_m) + " beta_n " + std::to_string(beta_n) +
                                    " alpha " + std::to_string(alpha) + " wi " + Describe(wi);
          // d'Eon's lobes are normalised for an untilted cone: the scales'
          // tilt changes the albedo and the pdf's total by a little, as in pbrt.
          const float tolerance = alpha == 0 ? 0.01f : 0.03f;
          ExpectVecNear(integral.albedo, Vec3(1, 1, 1), tolerance, where);
          EXPECT_NEAR(integral.pdf, 1.0, tolerance) << where;
        }
      }
}

TEST_F(HairTest, SampleAgreesWithPdfAndEvaluateAndLosesNothingWithoutAbsorption) {
  const auto model = Make("hair", Lossless(0.3, 0.3, 2.0));
  for (const Vec3 wi : FibreDirections()) {
    const std::vector<Scattered> samples = SampleMany(*model, wi, 20000, 17);
    for (size_t k = 0; k < samples.size(); k += 97) {
      const Scattered& s = samples[k];
      ASSERT_GT(s.pdf, 0.0f) << Describe(wi);
      const std::string where = "wi " + Describe(wi) + " wo " + Describe(s.wo);
      EXPECT_NEAR(Length(s.wo), 1.0f, 1e-4f) << where;
      EXPECT_EQ(s.flags, wi.z * s.wo.z >= 0 ? uint32_t(kScatterReflect | kScatterGlossy)
                                            : uint32_t(kScatterRefract | kScatterGlossy))
          << where;
      const float pdf = PdfOne(*model, wi, s.wo);
      EXPECT_NEAR(s.pdf, pdf, 1e-3f * std::max(1.0f, pdf)) << where;
      ExpectVecNear(s.weight, EvaluateOne(*model, wi, s.wo) * (std::abs(s.wo.z) / pdf), 1e-3f, where);
    }
    const MeanWithError mean = MeanWeight(samples);
    EXPECT_NEAR(mean.mean.x, 1.0f, 0.03f + 4 * mean.standard_error.x) << Describe(wi);
  }
}

TEST_F(HairTest, SamplesFollowThePdf) {
  constexpr int kCount = 400000;
  for (const double beta : {0.2, 0.6}) {
    const auto model = Make("hair", Props({{"beta_m", beta}, {"beta_n", beta}}));
    for (const Vec3 wi : {DirectionAt(0.3, 0.8), DirectionAt(-0.6, 2.5)}) {
      std::vector<Vec3> directions;
      for (const Scattered& s : SampleMany(*model, wi, kCount, 23))
        if (s.pdf > 0) directions.push_back(s.wo);
      EXPECT_TRUE(DirectionsFollowPdf(*model, wi, directions, kCount)) << "beta " << beta << " wi " << Describe(wi);
    }
  }
}

TEST_F(HairTest, MelaninDarkensAndEumelaninAbsorbsBlueMost) {
  const Vec3 wi = DirectionAt(0.4, 1.1);
  const auto albedo = [&](const Properties& props) { return IntegrateOverSphere(*Make("hair", props), wi).albedo; };
  const Vec3 blonde = albedo(Props({{"eumelanin", 0.3}}));
  const Vec3 brown = albedo(Properties());  // pbrt's default: eumelanin 1.3
  const Vec3 black = albedo(Props({{"eumelanin", 8.0}}));
  EXPECT_GT(blonde.z, brown.z);
  EXPECT_GT(brown.z, black.z);
  EXPECT_GT(brown.x, brown.z);  // brown: red leaves, blue is absorbed
  // Black hair still shows its surface reflection (R), colourless.
  EXPECT_GT(black.z, 0.02f);
  EXPECT_NEAR(black.x, black.z, 0.02f);
  // A colour asked for: more of its own channel survives.
  const Vec3 red = albedo(Props({{"reflectance", Rgb{Vec3(0.8f, 0.2f, 0.1f)}}}));
  EXPECT_GT(red.x, red.y);
  EXPECT_GT(red.y, red.z);
}

TEST_F(HairTest, BadPropertiesAreRefused) {
  EXPECT_NE(CreationError("hair", Props({{"eta", 0.5}})), "");
  EXPECT_NE(CreationError("hair", Props({{"beta_m", 0.0}})), "");
  EXPECT_NE(CreationError("hair", Props({{"beta_n", 2.0}})), "");
  EXPECT_NE(CreationError("hair", Props({{"eumelanin", -1.0}})), "");
  EXPECT_NE(CreationError("hair", Props({{"alpha", 90.0}})), "");
  EXPECT_EQ(CreationError("hair", Properties()), "");
}

}  // namespace
}  // namespace yarf::surface_testing
