// Tests of the phase functions (phase.h) and of the homogeneous medium,
// loaded through the registry as yarfd loads it: each phase function
// integrates to one, its samples follow its density (mean cosine, and a
// binned comparison), Rayleigh's and a table's values are theirs, and the
// homogeneous medium's majorant is its own extinction.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
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

Properties RayleighPhase() {
  Properties props;
  props.Set("phase", std::string("rayleigh"));
  return props;
}

Properties TabulatedPhase(std::vector<float> values) {
  Properties props;
  props.Set("phase", std::string("tabulated"));
  props.Set("phase_values", std::move(values));
  return props;
}

// A direction at scattering cosine μ from wi (the light's travel turned by
// acos μ): wo = -frame(wi)·(μ's direction).
Vec3 ScatteredAt(Vec3 wi, float mu, float phi = 0) {
  return -Frame(wi).ToWorld(SphericalDirection(SinFromCos(mu), mu, phi));
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
  EXPECT_NEAR(PhaseIntegral(PhaseFunction(RayleighPhase())), 1.0, 2e-3);
  EXPECT_NEAR(PhaseIntegral(PhaseFunction(TabulatedPhase({1, 0.5f, 0.1f}))), 1.0, 2e-3);
  EXPECT_NEAR(PhaseIntegral(PhaseFunction(TabulatedPhase({0, 0, 3, 0, 7, 7, 0.2f}))), 1.0, 2e-3);
  // Whatever the values' scale: denormal or near the float's largest.
  EXPECT_NEAR(PhaseIntegral(PhaseFunction(TabulatedPhase({1e-45f, 0, 1e-45f}))), 1.0, 2e-3);
  EXPECT_NEAR(PhaseIntegral(PhaseFunction(TabulatedPhase({3e38f, 1e38f, 3e38f}))), 1.0, 2e-3);
}

TEST(PhaseFunction, RayleighAndTablesTakeTheirValues) {
  const Vec3 wi = Normalize(Vec3(0.4f, 0.1f, -0.7f));
  const PhaseFunction rayleigh(RayleighPhase());
  for (float mu : {-1.0f, -0.5f, 0.0f, 0.3f, 1.0f})
    EXPECT_NEAR(rayleigh.Evaluate(wi, ScatteredAt(wi, mu)), 3 * (1 + mu * mu) / (16 * kPi), 1e-5f) << mu;
  // Values 1, 0.5, 0.1 at μ = -1, 0, 1 (back-scattering the most): their
  // integral over the sphere is 2π (0.75 + 0.3).
  const PhaseFunction table(TabulatedPhase({1, 0.5f, 0.1f}));
  const float scale = 1 / (2 * kPi * 1.05f);
  EXPECT_NEAR(table.Evaluate(wi, ScatteredAt(wi, -1)), 1 * scale, 1e-4f);
  EXPECT_NEAR(table.Evaluate(wi, ScatteredAt(wi, -0.5f)), 0.75f * scale, 1e-4f);
  EXPECT_NEAR(table.Evaluate(wi, ScatteredAt(wi, 0.5f)), 0.3f * scale, 1e-4f);
  EXPECT_NEAR(table.Evaluate(wi, ScatteredAt(wi, 1)), 0.1f * scale, 1e-4f);
}

TEST(PhaseFunction, ForwardScatteringIsAlongThePath) {
  // g > 0: the light goes on the way it came, wo = -wi, most often.
  const PhaseFunction phase(Phase(0.8));
  const Vec3 wi(0, 0, 1);
  EXPECT_GT(phase.Evaluate(wi, -wi), 10 * phase.Evaluate(wi, wi));
}

// Samples: unit directions whose mean of μ = -wi·wo is the mean cosine
// (g, for Henyey–Greenstein lobes; 0 for Rayleigh's; the density's own by
// quadrature for a table), and whose μ histogram matches the density's.
TEST(PhaseFunction, SamplesFollowTheDensity) {
  struct Case {
    const char* name;
    Properties props;
    double mean;  // NaN: by quadrature of the density
  };
  const double by_quadrature = std::nan("");
  const std::vector<Case> cases = {
      {"isotropic", Phase(0), 0},
      {"hg 0.6", Phase(0.6), 0.6},
      {"hg -0.3", Phase(-0.3), -0.3},
      {"blend", Phase(0.8, -0.5, 0.25), 0.75 * 0.8 + 0.25 * -0.5},
      {"rayleigh", RayleighPhase(), 0},
      {"table", TabulatedPhase({1, 0.5f, 0.1f}), by_quadrature},
      {"table with gaps", TabulatedPhase({0, 0, 3, 0, 7, 7, 0.2f}), by_quadrature},
  };
  for (const Case& c : cases) {
    const PhaseFunction phase(c.props);
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
    double expected_mean = 0;
    for (int b = 0; b < bins; ++b) {
      // The bin's probability by quadrature of 2π p dμ.
      double expected = 0;
      for (int q = 0; q < 1000; ++q) {
        const float mu = -1 + 2 * (float(b) + (float(q) + 0.5f) / 1000) / bins;
        const double mass = phase.Evaluate(wi, ScatteredAt(wi, mu)) * 2 * kPi * (2.0 / bins / 1000);
        expected += mass;
        expected_mean += mu * mass;
      }
      EXPECT_NEAR(histogram[b], expected, 5 * std::sqrt(expected / n) + 1e-4) << c.name << " bin " << b;
    }
    EXPECT_NEAR(mean_mu, std::isnan(c.mean) ? expected_mean : c.mean, 5e-3) << c.name;
  }
}

TEST(PhaseFunction, RefusesAsymmetryOutsideTheOpenInterval) {
  EXPECT_THROW(PhaseFunction(Phase(1.0)), Error);
  EXPECT_THROW(PhaseFunction(Phase(-1.5)), Error);
  EXPECT_THROW(PhaseFunction(Phase(0.5, 0.2, 1.5)), Error);
  EXPECT_THROW(PhaseFunction(Phase(std::nan(""))), Error);
}

TEST(PhaseFunction, RefusesMalformedTablesAndMixedShapes) {
  for (const std::vector<float>& values :
       {std::vector<float>{}, {1}, {0, 0, 0}, {1, -0.5f, 1}, {1, std::nanf(""), 1}, {1, INFINITY}})
    EXPECT_THROW(PhaseFunction(TabulatedPhase(values)), Error) << values.size() << " values";
  Properties no_values;
  no_values.Set("phase", std::string("tabulated"));
  EXPECT_THROW(PhaseFunction{no_values}, Error);
  Properties rayleigh_with_g = RayleighPhase();
  rayleigh_with_g.Set("g", 0.3);
  EXPECT_THROW(PhaseFunction{rayleigh_with_g}, Error);
  Properties hg_with_values = Phase(0.3);
  hg_with_values.Set("phase_values", std::vector<float>{1, 2});
  EXPECT_THROW(PhaseFunction{hg_with_values}, Error);
  Properties unknown;
  unknown.Set("phase", std::string("mie"));
  EXPECT_THROW(PhaseFunction{unknown}, Error);
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
