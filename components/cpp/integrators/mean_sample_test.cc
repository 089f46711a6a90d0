// The mean-sample integrator on functions with known integrals, driven by
// the shipped samplers.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "components/registry.h"
#include "image_passes.h"
#include "yarf/math.h"

namespace yarf {
namespace {

// f(x, y, z) = (x² y + z, 1).
class Polynomial final : public Function {
 public:
  uint32_t InputDimensions() const override { return 3; }
  uint32_t OutputDimensions() const override { return 2; }
  void Evaluate(std::span<const float> points, std::span<float> values) override {
    for (size_t i = 0; i < points.size() / 3; ++i) {
      const float x = points[3 * i], y = points[3 * i + 1], z = points[3 * i + 2];
      values[2 * i] = x * x * y + z;
      values[2 * i + 1] = 1;
    }
  }
};

class MeanSampleTest : public ::testing::Test {
 protected:
  void SetUp() override { registry_.LoadDirectory(YARF_PLUGIN_DIR); }
  Registry registry_;
};

TEST_F(MeanSampleTest, EstimatesAKnownIntegralWithinItsStandardError) {
  auto integrator = registry_.CreateAs<Integrator>("mean_sample", Properties{});
  Polynomial f;
  const double lower[] = {0, 0, -1}, upper[] = {1, 2, 1};
  // ∫ x² y + z = (1/3)(2)(2) + 0 = 4/3 over a box of volume 4.
  const double exact = 4.0 / 3.0;
  for (const char* sampler_name : {"independent", "sobol"}) {
    auto sampler = registry_.CreateAs<Sampler>(sampler_name, Properties{});
    int within = 0;
    for (uint64_t seed = 0; seed < 20; ++seed) {
      const IntegrationResult r = integrator->Integrate(f, lower, upper, 4096, seed, *sampler);
      ASSERT_EQ(r.estimate.size(), 2u);
      EXPECT_NEAR(r.estimate[1], 4.0, 1e-6);  // the volume, exactly
      EXPECT_EQ(r.evaluations, 4096u);
      EXPECT_GT(r.standard_error[0], 0);
      if (std::abs(r.estimate[0] - exact) < 2 * r.standard_error[0]) ++within;
    }
    // Calibrated σ: ~95% of independent runs fall within 2σ; QMC errors
    // are smaller than the i.i.d. σ, so all of them should.
    EXPECT_GE(within, 16) << sampler_name;
  }
}

TEST_F(MeanSampleTest, RejectsABoxOfTheWrongDimension) {
  auto integrator = registry_.CreateAs<Integrator>("mean_sample", Properties{});
  auto sampler = registry_.CreateAs<Sampler>("independent", Properties{});
  Polynomial f;
  const double lower[] = {0, 0}, upper[] = {1, 1};
  EXPECT_THROW(integrator->Integrate(f, lower, upper, 100, 0, *sampler), Error);
}

TEST_F(MeanSampleTest, AReversedBoxGivesTheSignedIntegralWithAPositiveErrorAndAnInfiniteOneIsRefused) {
  auto integrator = registry_.CreateAs<Integrator>("mean_sample", Properties{});
  auto sampler = registry_.CreateAs<Sampler>("independent", Properties{});
  Polynomial f;
  // x from 1 down to 0: the integral over the box of volume -4.
  const double lower[] = {1, 0, -1}, upper[] = {0, 2, 1};
  const IntegrationResult r = integrator->Integrate(f, lower, upper, 4096, 0, *sampler);
  EXPECT_NEAR(r.estimate[1], -4.0, 1e-6);
  EXPECT_GT(r.standard_error[0], 0);
  EXPECT_NEAR(r.estimate[0], -4.0 / 3.0, 4 * r.standard_error[0]);
  const double infinite[] = {1, 2, std::numeric_limits<double>::infinity()};
  const double zeros[] = {0, 0, 0};
  EXPECT_THROW(integrator->Integrate(f, zeros, infinite, 100, 0, *sampler), Error);
}

TEST_F(MeanSampleTest, ATilesDeepCoordinatesAreTheSameWhenAskedForAgainAfterOthers) {
  // A tile keeps only the last pairs of deep dimensions: one asked for
  // again after many others is made again, and must come out the same.
  auto sampler = registry_.CreateAs<Sampler>("sobol", Properties{});
  TilePoints points(*sampler, 0, 8, 8, 4);
  points.Reset(0, 0, 8, 8, 7);
  const std::vector<uint32_t> all = [&] {
    std::vector<uint32_t> v(points.Count());
    for (uint32_t i = 0; i < v.size(); ++i) v[i] = i;
    return v;
  }();
  std::vector<float> first(all.size()), again(all.size()), other(all.size());
  constexpr uint32_t kDeep = 1001;
  points.Gather(all, kDeep, first);
  for (uint32_t d = kDeep + 1; d < kDeep + 400; ++d) points.Gather(all, d, other);
  points.Gather(all, kDeep, again);
  EXPECT_EQ(first, again);
  EXPECT_EQ(points.Get(5, kDeep), first[5]);
  // And the coordinates differ from dimension to dimension.
  EXPECT_NE(first, other);
}

}  // namespace
}  // namespace yarf
