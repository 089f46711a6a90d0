// The classic integrators (simpson, stratified_mc, rqmc, miser) on
// integrands with closed-form integrals, loaded through the registry as
// yarfd loads them: accuracy, convergence order, calibration of the
// reported error, advantage over mean-sample Monte Carlo where theory
// promises one, batching, and rejection of bad properties.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "components/registry.h"
#include "test_integrands.h"
#include "yarf/math.h"

namespace yarf {
namespace {

// f(x) = 2x³ − x² + 3x + 1; ∫_0^2 f = 40/3.
class Cubic final : public Function {
 public:
  uint32_t InputDimensions() const override { return 1; }
  uint32_t OutputDimensions() const override { return 1; }
  void Evaluate(std::span<const float> points, std::span<float> values) override {
    for (size_t i = 0; i < points.size(); ++i) {
      const double x = points[i];
      values[i] = float(2 * x * x * x - x * x + 3 * x + 1);
    }
  }
};

// f(x, y) = (x³y³ − 2xy² + y + 1, x²y³): degree ≤ 3 in each variable.
// Over [0,1]×[0,2]: (7/3, 4/3).
class BicubicPair final : public Function {
 public:
  uint32_t InputDimensions() const override { return 2; }
  uint32_t OutputDimensions() const override { return 2; }
  void Evaluate(std::span<const float> points, std::span<float> values) override {
    for (size_t i = 0; i < points.size() / 2; ++i) {
      const double x = points[2 * i], y = points[2 * i + 1];
      values[2 * i] = float(x * x * x * y * y * y - 2 * x * y * y + y + 1);
      values[2 * i + 1] = float(x * x * y * y * y);
    }
  }
};

// f(x) = e^x; ∫_0^4 f = e^4 − 1.
class Exponential final : public Function {
 public:
  uint32_t InputDimensions() const override { return 1; }
  uint32_t OutputDimensions() const override { return 1; }
  void Evaluate(std::span<const float> points, std::span<float> values) override {
    for (size_t i = 0; i < points.size(); ++i) values[i] = float(std::exp(double(points[i])));
  }
};

// Passes calls through, counting them and the points they carry.
class Counting final : public Function {
 public:
  explicit Counting(Function& inner) : inner_(inner) {}
  uint32_t InputDimensions() const override { return inner_.InputDimensions(); }
  uint32_t OutputDimensions() const override { return inner_.OutputDimensions(); }
  void Evaluate(std::span<const float> points, std::span<float> values) override {
    ++calls;
    evaluated += points.size() / InputDimensions();
    inner_.Evaluate(points, values);
  }
  uint64_t calls = 0, evaluated = 0;

 private:
  Function& inner_;
};

class ClassicIntegratorsTest : public testing::Test {
 protected:
  void SetUp() override { registry_.LoadDirectory(YARF_PLUGIN_DIR); }

  std::unique_ptr<Integrator> Make(const std::string& name, const Properties& props = {}) const {
    return registry_.CreateAs<Integrator>(name, props);
  }
  std::unique_ptr<Sampler> MakeSampler(const std::string& name) const {
    return registry_.CreateAs<Sampler>(name, Properties{});
  }
  static Properties Intervals(int64_t n) {
    Properties p;
    p.Set("intervals", n);
    return p;
  }

  // Over `seeds` runs on [0,1]^d: how many land within 2σ of `exact`, and
  // the largest |error| / σ seen.
  struct Calibration {
    int within_two_sigma = 0;
    double worst_ratio = 0;
  };
  static Calibration Calibrate(Integrator& integrator, Function& f, double exact, uint64_t evaluations,
                               const Sampler& sampler, int seeds) {
    const std::vector<double> lower(f.InputDimensions(), 0.0), upper(f.InputDimensions(), 1.0);
    Calibration out;
    for (int seed = 0; seed < seeds; ++seed) {
      const IntegrationResult r = integrator.Integrate(f, lower, upper, evaluations, uint64_t(seed), sampler);
      EXPECT_GT(r.standard_error[0], 0);
      const double ratio = std::abs(r.estimate[0] - exact) / r.standard_error[0];
      if (ratio < 2) ++out.within_two_sigma;
      out.worst_ratio = std::max(out.worst_ratio, ratio);
    }
    return out;
  }

  // 40 runs of `name` with the sampler `sampler_name` on an oscillatory
  // integrand with coefficients `a` and on a corner peak: how many land
  // within 2σ, and the worst |error| / σ, reported under `label`.
  void ExpectCalibrated(const std::string& name, const std::string& sampler_name, std::vector<double> a,
                        uint64_t evaluations, const char* label) const {
    auto integrator = Make(name);
    auto sampler = MakeSampler(sampler_name);
    Oscillatory oscillatory(std::move(a), 0.3);
    CornerPeak peak({3.0, 2.0, 1.0});
    for (Function* f : std::initializer_list<Function*>{&oscillatory, &peak}) {
      const double exact = f == &oscillatory ? oscillatory.Exact() : peak.Exact();
      const Calibration c = Calibrate(*integrator, *f, exact, evaluations, *sampler, 40);
      std::printf("%s, d = %u: %d / 40 within 2σ, worst |error|/σ = %.2f\n", label, f->InputDimensions(),
                  c.within_two_sigma, c.worst_ratio);
      EXPECT_LT(c.worst_ratio, 4.0);
      EXPECT_GE(c.within_two_sigma, 34);
    }
  }

  // Root-mean-square error over `seeds` runs on [0,1]^d.
  static double Rmse(Integrator& integrator, Function& f, double exact, uint64_t evaluations,
                     const Sampler& sampler, int seeds) {
    const std::vector<double> lower(f.InputDimensions(), 0.0), upper(f.InputDimensions(), 1.0);
    double sum = 0;
    for (int seed = 0; seed < seeds; ++seed) {
      const IntegrationResult r =
          integrator.Integrate(f, lower, upper, evaluations, uint64_t(1000 + seed), sampler);
      const double e = r.estimate[0] - exact;
      sum += e * e;
    }
    return std::sqrt(sum / seeds);
  }

  Registry registry_;
};

TEST_F(ClassicIntegratorsTest, SimpsonIsExactForCubics) {
  auto sampler = MakeSampler("independent");
  // Power-of-two interval counts on boxes of dyadic size keep every node
  // and every value exact in float, so only double rounding remains.
  {
    auto simpson = Make("simpson", Intervals(16));
    Cubic f;
    const double lower[] = {0}, upper[] = {2};
    const IntegrationResult r = simpson->Integrate(f, lower, upper, 0, 0, *sampler);
    EXPECT_NEAR(r.estimate[0], 40.0 / 3.0, 1e-9 * 40.0 / 3.0);
    EXPECT_EQ(r.evaluations, 17u);
    EXPECT_LT(r.standard_error[0], 1e-9);  // both rules exact: no error seen
  }
  {
    auto simpson = Make("simpson", Intervals(8));
    BicubicPair f;
    const double lower[] = {0, 0}, upper[] = {1, 2};
    const IntegrationResult r = simpson->Integrate(f, lower, upper, 0, 0, *sampler);
    ASSERT_EQ(r.estimate.size(), 2u);
    EXPECT_NEAR(r.estimate[0], 7.0 / 3.0, 1e-9 * 7.0 / 3.0);
    EXPECT_NEAR(r.estimate[1], 4.0 / 3.0, 1e-9 * 4.0 / 3.0);
    EXPECT_EQ(r.evaluations, 81u);
  }
  // An odd coarse grid (3/8 rule) is exact for cubics too; nodes at sixths
  // are not exact in float, hence the looser bound.
  {
    auto simpson = Make("simpson", Intervals(6));
    Cubic f;
    const double lower[] = {0}, upper[] = {2};
    const IntegrationResult r = simpson->Integrate(f, lower, upper, 0, 0, *sampler);
    EXPECT_NEAR(r.estimate[0], 40.0 / 3.0, 1e-6 * 40.0 / 3.0);
    EXPECT_LT(r.standard_error[0], 1e-5);
  }
}

TEST_F(ClassicIntegratorsTest, SimpsonErrorFallsAsHToTheFourth) {
  auto sampler = MakeSampler("independent");
  Exponential f;
  const double lower[] = {0}, upper[] = {4};
  const double exact = std::exp(4.0) - 1;
  double previous = 0;
  for (int64_t n : {4, 8, 16, 32}) {
    const IntegrationResult r = Make("simpson", Intervals(n))->Integrate(f, lower, upper, 0, 0, *sampler);
    const double error = std::abs(r.estimate[0] - exact);
    // Richardson's estimate follows the true error (it is asymptotically
    // exact for smooth f).
    EXPECT_GT(r.standard_error[0], 0.5 * error) << n;
    EXPECT_LT(r.standard_error[0], 2.0 * error) << n;
    if (previous > 0) {
      const double ratio = previous / error;
      std::printf("simpson on e^x over [0,4]: error(%lld) / error(%lld) = %.2f\n", (long long)(n / 2),
                  (long long)n, ratio);
      EXPECT_GT(ratio, 14.0) << n;
      EXPECT_LT(ratio, 18.0) << n;
    }
    previous = error;
  }
}

TEST_F(ClassicIntegratorsTest, SimpsonChoosesItsGridFromTheBudget) {
  auto sampler = MakeSampler("independent");
  auto simpson = Make("simpson");
  BicubicPair f;
  const double lower[] = {0, 0}, upper[] = {1, 2};
  Counting counted(f);
  // 31² = 961 ≤ 1000 < 33²: 30 intervals per axis.
  const IntegrationResult r = simpson->Integrate(counted, lower, upper, 1000, 0, *sampler);
  EXPECT_EQ(r.evaluations, 961u);
  EXPECT_EQ(counted.evaluated, 961u);
  EXPECT_NEAR(r.estimate[0], 7.0 / 3.0, 1e-6);
  // Too small a budget for one Simpson panel per axis.
  EXPECT_THROW(simpson->Integrate(f, lower, upper, 8, 0, *sampler), Error);
}

TEST_F(ClassicIntegratorsTest, StratifiedMcIsWithinItsErrorBarsAndCalibrated) {
  ExpectCalibrated("stratified_mc", "independent", {1.5, 2.5}, 4096, "stratified_mc");
}

TEST_F(ClassicIntegratorsTest, RqmcWithSobolIsWithinItsErrorBarsAndCalibrated) {
  ExpectCalibrated("rqmc", "sobol", {1.5, 2.5, 0.5, 1.0}, 4096, "rqmc (sobol)");
}

TEST_F(ClassicIntegratorsTest, MiserIsWithinItsErrorBarsAndCalibrated) {
  ExpectCalibrated("miser", "independent", {1.5, 2.5}, 8192, "miser");
}

TEST_F(ClassicIntegratorsTest, RqmcBeatsMeanSampleOnASmoothIntegrand) {
  auto sobol = MakeSampler("sobol");
  auto independent = MakeSampler("independent");
  auto rqmc = Make("rqmc");
  auto mean_sample = Make("mean_sample");
  // Smooth, of effective dimension two: the scrambled nets stratify each
  // pair of coordinates, so the error falls far faster than 1/√N.
  PairSum pairs;
  const double rqmc_pairs = Rmse(*rqmc, pairs, pairs.Exact(), 4096, *sobol, 20);
  const double mc_pairs = Rmse(*mean_sample, pairs, pairs.Exact(), 4096, *independent, 20);
  std::printf("4-D pair sum, 4096 evaluations: RMSE mean_sample %.3g, rqmc %.3g (%.0f×)\n", mc_pairs,
              rqmc_pairs, mc_pairs / rqmc_pairs);
  EXPECT_LT(rqmc_pairs, mc_pairs / 30);
  // Strong interactions across the sampler's 2-D blocks converge at the
  // Monte Carlo rate (blocks are paired at random), so the gain is smaller.
  Oscillatory oscillatory({1.5, 2.5, 0.5, 1.0}, 0.3);
  const double rqmc_osc = Rmse(*rqmc, oscillatory, oscillatory.Exact(), 4096, *sobol, 20);
  const double mc_osc = Rmse(*mean_sample, oscillatory, oscillatory.Exact(), 4096, *independent, 20);
  std::printf("4-D oscillatory, 4096 evaluations: RMSE mean_sample %.3g, rqmc %.3g (%.1f×)\n", mc_osc,
              rqmc_osc, mc_osc / rqmc_osc);
  EXPECT_LT(rqmc_osc, mc_osc / 3);
}

TEST_F(ClassicIntegratorsTest, MiserBeatsMeanSampleOnACornerPeak) {
  CornerPeak f({20.0, 20.0});
  auto independent = MakeSampler("independent");
  const double miser = Rmse(*Make("miser"), f, f.Exact(), 16384, *independent, 20);
  const double mc = Rmse(*Make("mean_sample"), f, f.Exact(), 16384, *independent, 20);
  std::printf("2-D corner peak, 16384 evaluations: RMSE mean_sample %.3g, miser %.3g (%.1f×)\n", mc, miser,
              mc / miser);
  EXPECT_LT(miser, mc / 3);
}

TEST_F(ClassicIntegratorsTest, CallTheFunctionInLargeBatchesAndCountWhatTheyUse) {
  auto independent = MakeSampler("independent");
  Oscillatory f({1.5, 2.5, 0.5}, 0.3);
  const double lower[] = {0, 0, 0}, upper[] = {1, 1, 1};
  for (const char* name : {"simpson", "stratified_mc", "rqmc", "miser"}) {
    Counting counted(f);
    const IntegrationResult r = Make(name)->Integrate(counted, lower, upper, 100000, 7, *independent);
    EXPECT_EQ(r.evaluations, counted.evaluated) << name;
    EXPECT_LE(r.evaluations, 100000u) << name;
    EXPECT_GE(r.evaluations, 50000u) << name;
    // Thousands of points per call on average: f may be remote.
    EXPECT_GE(counted.evaluated / counted.calls, 1000u) << name;
    EXPECT_NEAR(r.estimate[0], f.Exact(), 1e-2) << name;
    std::printf("%s: %llu evaluations in %llu calls\n", name, (unsigned long long)counted.evaluated,
                (unsigned long long)counted.calls);
  }
}

TEST_F(ClassicIntegratorsTest, RejectBadPropertiesNamingThem) {
  const auto expect_rejected = [&](const std::string& name, const std::string& key, Properties::Value v) {
    Properties props;
    props.Set(key, v);
    try {
      Make(name, props);
      ADD_FAILURE() << name << " accepted " << key;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("'" + key + "'"), std::string::npos) << e.what();
    }
  };
  expect_rejected("simpson", "intervals", int64_t(3));
  expect_rejected("simpson", "intervals", int64_t(-2));
  expect_rejected("stratified_mc", "points_per_cell", int64_t(1));
  expect_rejected("rqmc", "replicates", int64_t(1));
  expect_rejected("miser", "explore_fraction", 0.0);
  expect_rejected("miser", "explore_fraction", 1.0);
  expect_rejected("miser", "min_points", int64_t(1));
  expect_rejected("miser", "dither", 0.5);
  expect_rejected("miser", "dither", std::string("large"));
}

TEST_F(ClassicIntegratorsTest, RejectABoxOfTheWrongDimension) {
  auto sampler = MakeSampler("independent");
  Oscillatory f({1.0, 2.0, 3.0}, 0.0);
  const double lower[] = {0, 0}, upper[] = {1, 1};
  for (const char* name : {"simpson", "stratified_mc", "rqmc", "miser"})
    EXPECT_THROW(Make(name)->Integrate(f, lower, upper, 1000, 0, *sampler), Error) << name;
}

}  // namespace
}  // namespace yarf
