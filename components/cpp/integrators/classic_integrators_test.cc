// The classic integrators (simpson, stratified_mc, rqmc, miser) and the
// paper's future ones (control_variate, adaptive_hierarchical) on
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
#include <functional>
#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <tuple>
#include <utility>
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

// Π_j e^{a_j x_j} over [0,1]^8: smooth, every coordinate interacting.
class Exponentials final : public Function {
 public:
  uint32_t InputDimensions() const override { return 8; }
  uint32_t OutputDimensions() const override { return 1; }
  void Evaluate(std::span<const float> points, std::span<float> values) override {
    for (size_t i = 0; i < values.size(); ++i) {
      double s = 0;
      for (size_t j = 0; j < 8; ++j) s += kA[j] * points[i * 8 + j];
      values[i] = float(std::exp(s));
    }
  }
  static double Exact() {
    double v = 1;
    for (double a : kA) v *= std::expm1(a) / a;
    return v;
  }
  static constexpr double kA[8] = {0.9, 0.8, 0.7, 0.6, 0.5, 0.4, 0.3, 0.2};
};

// A scalar function of `dimensions` inputs, given as a callable.
class FunctionOf final : public Function {
 public:
  FunctionOf(uint32_t dimensions, std::function<double(std::span<const float>)> f)
      : dimensions_(dimensions), f_(std::move(f)) {}
  uint32_t InputDimensions() const override { return dimensions_; }
  uint32_t OutputDimensions() const override { return 1; }
  void Evaluate(std::span<const float> points, std::span<float> values) override {
    for (size_t i = 0; i < values.size(); ++i) values[i] = float(f_(points.subspan(i * dimensions_, dimensions_)));
  }

 private:
  uint32_t dimensions_;
  std::function<double(std::span<const float>)> f_;
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
    // Every level exact: what is left is the float32 rounding of the values.
    EXPECT_LT(r.standard_error[0], 1e-6);
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
  for (int64_t n : {8, 16, 32, 64}) {
    const IntegrationResult r = Make("simpson", Intervals(n))->Integrate(f, lower, upper, 0, 0, *sampler);
    const double error = std::abs(r.estimate[0] - exact);
    // Once the error is seen to fall as h^4, Richardson's estimate follows
    // it (it is asymptotically exact for smooth f); before that (8: the
    // coarsest level is one interval) it is an upper bound.
    EXPECT_GT(r.standard_error[0], (n == 8 ? 1.0 : 0.5) * error) << n;
    if (n > 8) {
      EXPECT_LT(r.standard_error[0], 2.0 * error) << n;
    }
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
  // 31² = 961 ≤ 1000 < 33²: 30 intervals per axis fit, and 24, a multiple
  // of 8, keeps more than half of them.
  const IntegrationResult r = simpson->Integrate(counted, lower, upper, 1000, 0, *sampler);
  EXPECT_EQ(r.evaluations, 625u);
  EXPECT_EQ(counted.evaluated, 625u);
  // 3-D, 10⁴: 21³ fit, and 17³ is more than half of them.
  FunctionOf product(3, [](std::span<const float> x) { return x[0] * x[1] * x[2]; });
  Counting cubes(product);
  const double lower3[] = {0, 0, 0}, upper3[] = {1, 1, 1};
  EXPECT_EQ(simpson->Integrate(cubes, lower3, upper3, 10000, 0, *sampler).evaluations, 4913u);
  EXPECT_NEAR(r.estimate[0], 7.0 / 3.0, 1e-6);
  // Too small a budget for one Simpson panel per axis.
  EXPECT_THROW(simpson->Integrate(f, lower, upper, 8, 0, *sampler), Error);
}

TEST_F(ClassicIntegratorsTest, SimpsonsErrorBoundsTheErrorWhereFIsNotSmooth) {
  // A step, a kink and √|x − c| at 300 places c each, on 1000 evaluations:
  // S(n)'s error does not fall as h^4 there, and Richardson's
  // |S(n) − S(n/2)| / 15 was below it in 95% of the runs, 5–30 times. The
  // estimate bounds it now; on e^{ax} it is still Richardson's, within 2×.
  auto sampler = MakeSampler("independent");
  auto simpson = Make("simpson");
  const double lower[] = {0}, upper[] = {1};
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> place(0.05, 0.95);
  struct Family {
    const char* name;
    std::function<double(double, double)> f;  // (x, c)
    std::function<double(double)> integral;   // over [0, 1], of c
  };
  const Family families[] = {
      {"step", [](double x, double c) { return x > c ? 1.0 : 0.0; }, [](double c) { return 1 - c; }},
      {"kink", [](double x, double c) { return std::abs(x - c); },
       [](double c) { return (c * c + (1 - c) * (1 - c)) / 2; }},
      {"root", [](double x, double c) { return std::sqrt(std::abs(x - c)); },
       [](double c) { return 2.0 / 3 * (std::pow(c, 1.5) + std::pow(1 - c, 1.5)); }},
  };
  for (const Family& family : families) {
    int bounded = 0;
    for (int run = 0; run < 300; ++run) {
      const double c = place(random);
      FunctionOf f(1, [&](std::span<const float> x) { return family.f(x[0], c); });
      const IntegrationResult r = simpson->Integrate(f, lower, upper, 1000, 0, *sampler);
      bounded += std::abs(r.estimate[0] - family.integral(c)) <= r.standard_error[0];
    }
    std::printf("simpson, 1000 evaluations, %s at 300 places: error ≤ estimate in %d\n", family.name, bounded);
    EXPECT_GE(bounded, 294) << family.name;  // 98%
  }
  for (double a : {3.0, 4.0, 5.0}) {
    FunctionOf f(1, [a](std::span<const float> x) { return std::exp(a * x[0]); });
    const IntegrationResult r = Make("simpson", Intervals(16))->Integrate(f, lower, upper, 0, 0, *sampler);
    const double error = std::abs(r.estimate[0] - std::expm1(a) / a);
    EXPECT_GT(r.standard_error[0], 0.5 * error) << a;
    EXPECT_LT(r.standard_error[0], 2.0 * error) << a;
  }
}

TEST_F(ClassicIntegratorsTest, AdaptiveHierarchicalsQFlagsOnlyWhatDisagrees) {
  // On a step the tree's later iterations have far smaller σ_t than the
  // first; χ² about the equal-weight average counted the early ones' noise
  // against them: Q < 0.05 in 12 (10⁴ points) and 18 (10⁵) of 20 runs
  // whose errors were right. At most 4 of 20 now (1 expected), and the
  // results within 3σ.
  auto sampler = MakeSampler("independent");
  auto integrator = Make("adaptive_hierarchical");
  const double lower[] = {0}, upper[] = {1};
  FunctionOf step(1, [](std::span<const float> x) { return x[0] > 0.5123f ? 1.0 : 0.0; });
  for (uint64_t evaluations : {10000, 100000}) {
    int flagged = 0;
    for (uint64_t seed = 0; seed < 20; ++seed) {
      const IntegrationResult r = integrator->Integrate(step, lower, upper, evaluations, seed, *sampler);
      flagged += r.q[0] < 0.05;
      EXPECT_LT(std::abs(r.estimate[0] - (1 - double(0.5123f))), 3 * r.standard_error[0]) << seed;
    }
    EXPECT_LE(flagged, 4) << evaluations;
  }
}

TEST_F(ClassicIntegratorsTest, ReportedErrorIsCalibratedOnEveryIntegrandFamily) {
  // Independent runs fall within 2σ of the exact value about 95% of the
  // time when σ is right (93.6% for rqmc's Student t with 15 degrees of
  // freedom); 200 runs put the count within [90%, 99%] unless σ is off.
  //
  // Left out: the narrow peak (width 0.02 in 4-D, 6·10⁻⁶ of the volume)
  // at 10⁵ points for the methods that do not adapt, or adapt by cells
  // larger than the peak. Plain sampling sees it about once; the estimate
  // is then skewed (usually low, with a small σ) and no error bar from
  // such a sample covers 95% of runs: that takes the ~10⁷ points at which
  // the central limit applies. (Measured, 200 runs: mean_sample 76.5%,
  // stratified_mc 78%, rqmc 82%, control_variate 72.5%,
  // adaptive_hierarchical 84%.) miser, and vegas in vegas_test, find the
  // peak and are held to the interval there too.
  constexpr int kRuns = 200;
  struct Method {
    const char* name;
    const char* sampler;
    bool held_on_narrow_peak;
  };
  const Method methods[] = {{"mean_sample", "independent", false},     {"stratified_mc", "independent", false},
                            {"rqmc", "sobol_nd", false},               {"miser", "independent", true},
                            {"control_variate", "independent", false}, {"adaptive_hierarchical", "independent", false}};
  auto families = CalibrationFamilies();
  for (const Method& method : methods) {
    auto integrator = Make(method.name);
    auto sampler = MakeSampler(method.sampler);
    for (CalibrationFamily& family : families) {
      if (!method.held_on_narrow_peak && std::string(family.name) == "narrow peak d=4") continue;
      const Calibration c = Calibrate(*integrator, *sampler, family, kRuns);
      std::printf("[ measured ] %s (%s), %s, %llu points: |error| < 2 sigma in %.1f%% of %d runs\n", method.name,
                  method.sampler, family.name, static_cast<unsigned long long>(family.evaluations), 100 * c.Within(),
                  c.runs);
      EXPECT_GE(c.Within(), 0.90) << method.name << ", " << family.name;
      EXPECT_LE(c.Within(), 0.99) << method.name << ", " << family.name;
    }
  }
}

TEST_F(ClassicIntegratorsTest, RqmcWithScrambledSobolConvergesNearOneOverN) {
  // A smooth 8-D product with every coordinate interacting: Owen-scrambled Sobol nets give an RMSE falling about as
  // N⁻¹ (N^−3/2 up to log factors in theory), Monte Carlo as N^−1/2.
  Exponentials f;
  const auto fit_slope = [&](Integrator& integrator, const Sampler& sampler) {
    // Least-squares slope of log RMSE against log N, N = 2¹⁰ … 2¹⁶.
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    int n = 0;
    for (int m = 10; m <= 16; m += 2, ++n) {
      const double x = std::log(double(1 << m));
      const double y = std::log(Rmse(integrator, f, f.Exact(), uint64_t(1) << m, sampler, 24));
      sx += x, sy += y, sxx += x * x, sxy += x * y;
    }
    return (n * sxy - sx * sy) / (n * sxx - sx * sx);
  };
  Properties four;
  four.Set("replicates", int64_t(4));
  const double rqmc = fit_slope(*Make("rqmc", four), *MakeSampler("sobol_nd"));
  const double mc = fit_slope(*Make("mean_sample"), *MakeSampler("independent"));
  std::printf("[ measured ] 8-D product of exponentials, N = 2^10 ... 2^16: RMSE slope rqmc (sobol_nd) %.2f, "
              "mean_sample %.2f\n",
              rqmc, mc);
  EXPECT_LT(rqmc, -0.85);
  EXPECT_GT(rqmc, -2.0);
  EXPECT_NEAR(mc, -0.5, 0.15);
}

TEST_F(ClassicIntegratorsTest, ControlVariateIntegratesItsFitExactly) {
  // f is a polynomial of degree 3 in each output (x²y + z + 1, and 1): a
  // degree-3 fit is f itself, the residual is float rounding, and the
  // integral is exact whatever the sample.
  Polynomial f;
  Properties cubic;
  cubic.Set("degree", int64_t(3));
  auto sampler = MakeSampler("independent");
  const IntegrationResult r = Make("control_variate", cubic)->Integrate(f, Polynomial::kLower, Polynomial::kUpper,
                                                                       4000, 3, *sampler);
  EXPECT_NEAR(r.estimate[0], Polynomial::kExact, 1e-5);
  EXPECT_NEAR(r.estimate[1], Polynomial::kVolume, 1e-5);
  EXPECT_LT(r.standard_error[0], 1e-5);
  // Degree 0 is Lafortune's constant ambient term: no better than the mean.
  Properties constant;
  constant.Set("degree", int64_t(0));
  const IntegrationResult flat = Make("control_variate", constant)->Integrate(f, Polynomial::kLower,
                                                                              Polynomial::kUpper, 4000, 3, *sampler);
  EXPECT_GT(flat.standard_error[0], 0.01);
  EXPECT_NEAR(flat.estimate[0], Polynomial::kExact, 4 * flat.standard_error[0]);
}

TEST_F(ClassicIntegratorsTest, ControlVariateBeatsMeanSampleOnASmoothIntegrand) {
  Oscillatory f({1.5, 2.5, 0.5, 1.0}, 0.3);
  auto independent = MakeSampler("independent");
  const double cv = Rmse(*Make("control_variate"), f, f.Exact(), 10000, *independent, 20);
  const double mc = Rmse(*Make("mean_sample"), f, f.Exact(), 10000, *independent, 20);
  std::printf("[ measured ] 4-D oscillatory, 10000 evaluations: RMSE mean_sample %.3g, control_variate %.3g "
              "(%.0f×)\n",
              mc, cv, mc / cv);
  EXPECT_LT(cv, mc / 10);
}

TEST_F(ClassicIntegratorsTest, AdaptiveHierarchicalBeatsMeanSampleWhereFIsLocalised) {
  auto independent = MakeSampler("independent");
  auto adaptive = Make("adaptive_hierarchical");
  auto mean_sample = Make("mean_sample");
  CornerPeak corner({20.0, 20.0});
  Discontinuous jump({1.0, 2.0, 0.5}, 0.6, 0.35);
  GaussianPeaks narrow = NarrowPeak();
  const std::tuple<const char*, Function*, double> cases[] = {
      {"2-D corner peak", &corner, corner.Exact()},
      {"3-D discontinuous", &jump, jump.Exact()},
      {"4-D narrow peak", &narrow, narrow.Exact()}};
  for (const auto& [label, f, exact] : cases) {
    const double ah = Rmse(*adaptive, *f, exact, 16384, *independent, 20);
    const double mc = Rmse(*mean_sample, *f, exact, 16384, *independent, 20);
    std::printf("[ measured ] %s, 16384 evaluations: RMSE mean_sample %.3g, adaptive_hierarchical %.3g (%.1f×)\n",
                label, mc, ah, mc / ah);
    EXPECT_LT(ah, mc / 2) << label;
  }
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
  for (const char* name : {"simpson", "stratified_mc", "rqmc", "miser", "control_variate", "adaptive_hierarchical"}) {
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
  expect_rejected("control_variate", "degree", int64_t(-1));
  expect_rejected("control_variate", "degree", int64_t(9));
  expect_rejected("control_variate", "pilot_fraction", 1.0);
  expect_rejected("adaptive_hierarchical", "iterations", int64_t(1));
  expect_rejected("adaptive_hierarchical", "discard", int64_t(8));
  expect_rejected("adaptive_hierarchical", "cell_points", int64_t(3));
  expect_rejected("adaptive_hierarchical", "floor", 1.5);
}

TEST_F(ClassicIntegratorsTest, RejectABoxOfTheWrongDimension) {
  auto sampler = MakeSampler("independent");
  Oscillatory f({1.0, 2.0, 3.0}, 0.0);
  const double lower[] = {0, 0}, upper[] = {1, 1};
  for (const char* name : {"simpson", "stratified_mc", "rqmc", "miser", "control_variate", "adaptive_hierarchical"})
    EXPECT_THROW(Make(name)->Integrate(f, lower, upper, 1000, 0, *sampler), Error) << name;
}

}  // namespace
}  // namespace yarf
