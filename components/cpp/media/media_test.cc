// Tests of the phase functions (phase.h) and of the homogeneous medium,
// loaded through the registry as yarfd loads it: each phase function
// integrates to one, its samples follow its density (mean cosine g, and a
// binned comparison), and the homogeneous medium's majorant is its own
// extinction.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

#include "components/registry.h"
#include "phase.h"
#include "yarf/support/hash.h"

namespace yarf {
namespace {

Properties Phase(double g, double g2 = 0, double blend = 0) {
  Properties props;
  props.Set("g", g);
  props.Set("g2", g2);
  props.Set("blend", blend);
  return props;
}

// ∫ p(wi, wo) dwo over the sphere, by a midpoint rule in μ (p depends on
// the angle to wi only).
double PhaseIntegral(const PhaseFunction& phase) {
  const Vec3 wi = Normalize(Vec3(0.3f, -0.5f, 0.8f));
  const Frame frame(wi);
  const int n = 200000;
  double sum = 0;
  for (int i = 0; i < n; ++i) {
    const float mu = -1 + 2 * (float(i) + 0.5f) / float(n);
    const Vec3 wo = frame.ToWorld(SphericalDirection(SinFromCos(mu), mu, 0.7f));
    sum += phase.Evaluate(wi, wo) * 2 * kPi * 2.0 / n;
  }
  return sum;
}

TEST(PhaseFunction, IntegratesToOne) {
  for (double g : {0.0, 0.3, -0.6, 0.9})
    EXPECT_NEAR(PhaseIntegral(PhaseFunction(Phase(g))), 1.0, 2e-3) << "g = " << g;
  EXPECT_NEAR(PhaseIntegral(PhaseFunction(Phase(0.7, -0.4, 0.3))), 1.0, 2e-3);
}

TEST(PhaseFunction, ForwardScatteringIsAlongThePath) {
  // g > 0: the light goes on the way it came, wo = -wi, most often.
  const PhaseFunction phase(Phase(0.8));
  const Vec3 wi(0, 0, 1);
  EXPECT_GT(phase.Evaluate(wi, -wi), 10 * phase.Evaluate(wi, wi));
}

// Samples: unit directions whose mean of μ = -wi·wo is the mean cosine of
// the mixture, and whose μ histogram matches the density's.
TEST(PhaseFunction, SamplesFollowTheDensity) {
  struct Case {
    double g, g2, blend;
  };
  for (const Case c : {Case{0, 0, 0}, Case{0.6, 0, 0}, Case{-0.3, 0, 0}, Case{0.8, -0.5, 0.25}}) {
    const PhaseFunction phase(Phase(c.g, c.g2, c.blend));
    const Vec3 wi = Normalize(Vec3(-0.2f, 0.9f, 0.1f));
    const int n = 400000, bins = 20;
    std::vector<double> histogram(bins);
    double mean_mu = 0;
    for (int i = 0; i < n; ++i) {
      const Vec3 wo = phase.Sample(wi, ToUnitFloat(uint32_t(Hash(i, 0))), ToUnitFloat(uint32_t(Hash(i, 1))));
      ASSERT_NEAR(Length(wo), 1.0f, 1e-4f);
      const float mu = -Dot(wi, wo);
      mean_mu += mu / n;
      histogram[std::min(bins - 1, int((mu + 1) / 2 * bins))] += 1.0 / n;
    }
    EXPECT_NEAR(mean_mu, (1 - c.blend) * c.g + c.blend * c.g2, 5e-3) << c.g;
    const Frame frame(wi);
    for (int b = 0; b < bins; ++b) {
      // The bin's probability by quadrature of 2π p dμ.
      double expected = 0;
      for (int q = 0; q < 1000; ++q) {
        const float mu = -1 + 2 * (float(b) + (float(q) + 0.5f) / 1000) / bins;
        expected += phase.Evaluate(wi, -frame.ToWorld(SphericalDirection(SinFromCos(mu), mu, 0))) * 2 * kPi *
                    (2.0 / bins / 1000);
      }
      EXPECT_NEAR(histogram[b], expected, 5 * std::sqrt(expected / n) + 1e-4) << "g " << c.g << " bin " << b;
    }
  }
}

TEST(PhaseFunction, RefusesAsymmetryOutsideTheOpenInterval) {
  EXPECT_THROW(PhaseFunction(Phase(1.0)), Error);
  EXPECT_THROW(PhaseFunction(Phase(-1.5)), Error);
  EXPECT_THROW(PhaseFunction(Phase(0.5, 0.2, 1.5)), Error);
  EXPECT_THROW(PhaseFunction(Phase(std::nan(""))), Error);
}

class HomogeneousTest : public testing::Test {
 protected:
  HomogeneousTest() { registry_.LoadDirectory(YARF_PLUGIN_DIR); }
  std::unique_ptr<Medium> Make(const Properties& props) const { return registry_.CreateAs<Medium>("homogeneous", props); }
  Registry registry_;
};

TEST_F(HomogeneousTest, CoefficientsAndMajorantAreItsOwn) {
  Properties props;
  props.Set("sigma_a", Rgb{Vec3(0.1f, 0.2f, 0.3f)});
  props.Set("sigma_s", Rgb{Vec3(1, 0.5f, 0)});
  props.Set("scale", 2.0);
  const auto medium = Make(props);
  EXPECT_EQ(medium->Describe().interfaces, std::vector<std::string>{Medium::kInterface});
  const std::vector<float> origin{0, 0, 0, 1, 2, 3}, direction{0, 0, 1, 1, 0, 0}, tmax{5, 0};
  MajorantSegments segments;
  medium->Majorants(origin, direction, tmax, segments);
  ASSERT_EQ(segments.offsets, (std::vector<uint32_t>{0, 1, 1}));
  EXPECT_EQ(segments.segments[0].t0, 0);
  EXPECT_EQ(segments.segments[0].t1, 5);
  EXPECT_NEAR(segments.segments[0].sigma_maj.x, 2.2f, 1e-6f);
  EXPECT_NEAR(segments.segments[0].sigma_maj.z, 0.6f, 1e-6f);
  std::vector<float> sigma_a(6), sigma_s(6), emission(6, -1);
  medium->Coefficients(origin, sigma_a, sigma_s, emission);
  EXPECT_NEAR(sigma_a[4], 0.4f, 1e-6f);
  EXPECT_NEAR(sigma_s[3], 2.0f, 1e-6f);
  EXPECT_EQ(emission[0], 0);
  EXPECT_FALSE(medium->Emits());
}

TEST_F(HomogeneousTest, RefusesNegativeOrNonFiniteCoefficients) {
  Properties negative;
  negative.Set("sigma_s", Rgb{Vec3(1, -1, 1)});
  EXPECT_THROW(Make(negative), Error);
  Properties infinite;
  infinite.Set("sigma_a", double(INFINITY));
  EXPECT_THROW(Make(infinite), Error);
  Properties scale;
  scale.Set("scale", -2.0);
  EXPECT_THROW(Make(scale), Error);
}

}  // namespace
}  // namespace yarf
