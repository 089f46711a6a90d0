// Tests of the root-finder plugins (rootfinders/*.cc), loaded through the
// registry as yarfd loads them: every finder on smooth functions, on a
// flat derivative, on a multiple root and on several roots in one bracket,
// roots at the bracket's ends, the errors for no bracket, no convergence
// and bad arguments, and the interpolating finders' speed over bisection.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <numbers>
#include <span>
#include <string>
#include <utility>

#include "components/registry.h"
#include "yarf/math.h"

namespace yarf {
namespace {

constexpr const char* kFinders[] = {"bisection", "newton", "brent"};

// A scalar function with its derivative, as a batch Function R -> R²
// (outputs f, f'), computed in double from the float points. Counts the
// points it is asked for.
class Scalar final : public Function {
 public:
  Scalar(std::function<double(double)> f, std::function<double(double)> df,
         uint32_t outputs = 2, uint32_t inputs = 1)
      : f_(std::move(f)), df_(std::move(df)), outputs_(outputs), inputs_(inputs) {}

  uint32_t InputDimensions() const override { return inputs_; }
  uint32_t OutputDimensions() const override { return outputs_; }
  void Evaluate(std::span<const float> points, std::span<float> values) override {
    const size_t count = points.size() / inputs_;
    for (size_t i = 0; i < count; ++i) {
      const double x = points[i * inputs_];
      values[i * outputs_] = float(f_(x));
      if (outputs_ > 1) values[i * outputs_ + 1] = float(df_(x));
    }
    evaluations += count;
  }

  uint64_t evaluations = 0;

 private:
  std::function<double(double)> f_, df_;
  uint32_t outputs_, inputs_;
};

// x³ - 2x - 5, Wallis's example (the one Newton used).
Scalar Cubic() {
  return Scalar([](double x) { return x * x * x - 2 * x - 5; },
                [](double x) { return 3 * x * x - 2; });
}
constexpr double kCubicRoot = 2.0945514815423265;

// cos x - x: its root is the fixed point of cos (the Dottie number).
Scalar CosMinusX() {
  return Scalar([](double x) { return std::cos(x) - x; },
                [](double x) { return -std::sin(x) - 1; });
}
constexpr double kCosRoot = 0.7390851332151607;

// (x - 1)⁵: f' vanishes to fourth order at the root, so Newton's steps
// shrink only by 4/5 each.
Scalar FlatAtRoot() {
  return Scalar([](double x) { return std::pow(x - 1, 5); },
                [](double x) { return 5 * std::pow(x - 1, 4); });
}

// (x - 0.5)³ (x + 2): a triple root at 0.5 (f changes sign there).
Scalar TripleRoot() {
  return Scalar([](double x) { return std::pow(x - 0.5, 3) * (x + 2); },
                [](double x) { return 3 * std::pow(x - 0.5, 2) * (x + 2) + std::pow(x - 0.5, 3); });
}

class RootFinderTest : public testing::Test {
 protected:
  RootFinderTest() { registry_.LoadDirectory(YARF_PLUGIN_DIR); }

  std::unique_ptr<RootFinder> Make(const std::string& name) const {
    return registry_.CreateAs<RootFinder>(name, Properties());
  }

  // The message of the Error that FindRoot throws; "" when it returns.
  static std::string FindRootError(RootFinder& finder, Function& f, double lower, double upper,
                                   double tolerance, uint32_t max_iterations) {
    try {
      finder.FindRoot(f, lower, upper, tolerance, max_iterations);
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  }

  Registry registry_;
};

TEST_F(RootFinderTest, RegistersEveryFinderWithItsInterface) {
  for (const char* name : kFinders) {
    ASSERT_TRUE(registry_.Has(name)) << name;
    const auto finder = Make(name);
    EXPECT_EQ(finder->Describe().class_name, name);
    EXPECT_EQ(finder->Describe().interfaces, std::vector<std::string>{RootFinder::kInterface});
    EXPECT_FALSE(finder->Describe().summary.empty()) << name;
  }
}

// Functions are evaluated at float points, so a root is known to about a
// float's spacing (2.4e-7 near 2) even with a smaller tolerance.
constexpr double kFloatLimited = 1e-6;

TEST_F(RootFinderTest, FindsTheRootOfACubic) {
  for (const char* name : kFinders) {
    Scalar f = Cubic();
    const RootResult result = Make(name)->FindRoot(f, 2, 3, 1e-9, 100);
    EXPECT_NEAR(result.root, kCubicRoot, kFloatLimited) << name;
    EXPECT_GE(result.iterations, 1u) << name;
    // The two ends, then one evaluation per iteration.
    EXPECT_EQ(f.evaluations, result.iterations + 2u) << name;
  }
}

TEST_F(RootFinderTest, FindsTheFixedPointOfCosine) {
  for (const char* name : kFinders) {
    Scalar f = CosMinusX();
    const RootResult result = Make(name)->FindRoot(f, 0, 1, 1e-9, 100);
    EXPECT_NEAR(result.root, kCosRoot, kFloatLimited) << name;
  }
}

TEST_F(RootFinderTest, ToleranceBoundsTheError) {
  // With a tolerance above float resolution the error is within it.
  for (const char* name : kFinders)
    for (double tolerance : {1e-2, 1e-4}) {
      Scalar f = CosMinusX();
      const RootResult result = Make(name)->FindRoot(f, -2, 3, tolerance, 100);
      EXPECT_NEAR(result.root, kCosRoot, tolerance) << name << ", tolerance " << tolerance;
    }
}

TEST_F(RootFinderTest, FindsARootWhereTheDerivativeIsFlat) {
  for (const char* name : kFinders) {
    Scalar f = FlatAtRoot();
    const RootResult result = Make(name)->FindRoot(f, 0.3, 2.1, 1e-9, 200);
    EXPECT_NEAR(result.root, 1.0, kFloatLimited) << name;
    RecordProperty(std::string("iterations_") + name, int(result.iterations));
  }
}

TEST_F(RootFinderTest, FindsATripleRoot) {
  for (const char* name : kFinders) {
    Scalar f = TripleRoot();
    const RootResult result = Make(name)->FindRoot(f, 0.05, 1, 1e-9, 200);
    EXPECT_NEAR(result.root, 0.5, kFloatLimited) << name;
    RecordProperty(std::string("iterations_") + name, int(result.iterations));
  }
}

TEST_F(RootFinderTest, FindsOneOfSeveralRootsInTheBracket) {
  // sin x on [-1, 7] changes sign at 0, π and 2π: any of them will do.
  for (const char* name : kFinders) {
    Scalar f([](double x) { return std::sin(x); }, [](double x) { return std::cos(x); });
    const double root = Make(name)->FindRoot(f, -1, 7, 1e-9, 200).root;
    const double nearest = std::round(root / std::numbers::pi) * std::numbers::pi;
    EXPECT_NEAR(root, nearest, kFloatLimited) << name;
    EXPECT_GE(root, -1.0) << name;
    EXPECT_LE(root, 7.0) << name;
  }
}

TEST_F(RootFinderTest, ReturnsARootAtAnEnd) {
  for (const char* name : kFinders) {
    Scalar f([](double x) { return x - 2; }, [](double) { return 1.0; });
    const RootResult at_lower = Make(name)->FindRoot(f, 2, 5, 1e-9, 100);
    EXPECT_EQ(at_lower.root, 2.0) << name;
    EXPECT_EQ(at_lower.iterations, 0u) << name;
    const RootResult at_upper = Make(name)->FindRoot(f, -1, 2, 1e-9, 100);
    EXPECT_EQ(at_upper.root, 2.0) << name;
    EXPECT_EQ(at_upper.iterations, 0u) << name;
  }
}

TEST_F(RootFinderTest, NoBracketIsAnError) {
  for (const char* name : kFinders) {
    const auto finder = Make(name);
    Scalar positive([](double x) { return x * x + 1; }, [](double x) { return 2 * x; });
    EXPECT_EQ(FindRootError(*finder, positive, -1, 1.5, 1e-6, 100),
              "no root bracketed in [-1, 1.5]: f(-1) = 2, f(1.5) = 3.25")
        << name;
    // A double root does not change sign: it cannot be bracketed.
    Scalar touching([](double x) { return x * x; }, [](double x) { return 2 * x; });
    EXPECT_NE(FindRootError(*finder, touching, -1, 2, 1e-6, 100).find("no root bracketed"),
              std::string::npos)
        << name;
  }
}

TEST_F(RootFinderTest, NonConvergenceIsAnError) {
  for (const char* name : kFinders) {
    Scalar f = Cubic();
    const std::string message = FindRootError(*Make(name), f, 2, 3, 1e-12, 2);
    EXPECT_NE(message.find("did not converge in 2 iterations"), std::string::npos)
        << name << ": '" << message << "'";
    // No iterations at all, and the root not at an end.
    Scalar g = Cubic();
    EXPECT_NE(FindRootError(*Make(name), g, 2, 3, 1e-3, 0).find("did not converge in 0"),
              std::string::npos)
        << name;
  }
}

TEST_F(RootFinderTest, BadArgumentsAreErrors) {
  for (const char* name : kFinders) {
    const auto finder = Make(name);
    Scalar f = Cubic();
    for (double tolerance : {0.0, -1e-3, std::nan("")})
      EXPECT_NE(FindRootError(*finder, f, 2, 3, tolerance, 100).find("tolerance"),
                std::string::npos)
          << name << ", tolerance " << tolerance;
    EXPECT_NE(FindRootError(*finder, f, 3, 2, 1e-6, 100).find("lower < upper"), std::string::npos)
        << name;
    EXPECT_NE(FindRootError(*finder, f, 2, INFINITY, 1e-6, 100).find("lower < upper"),
              std::string::npos)
        << name;
    Scalar two_inputs([](double x) { return x; }, [](double) { return 1.0; }, 2, 2);
    EXPECT_NE(FindRootError(*finder, two_inputs, -1, 1, 1e-6, 100).find("one variable"),
              std::string::npos)
        << name;
    // A value that is not a number is reported, not bisected.
    Scalar nan_inside([](double x) { return x < 0.3 ? -1.0 : (x < 0.7 ? NAN : 1.0); },
                      [](double) { return 0.0; });
    EXPECT_NE(FindRootError(*finder, nan_inside, 0, 1, 1e-6, 100).find("not a finite number"),
              std::string::npos)
        << name;
  }
}

TEST_F(RootFinderTest, NewtonNeedsTheDerivativeAsSecondOutput) {
  Scalar value_only([](double x) { return x - 0.25; }, nullptr, 1);
  const std::string message = FindRootError(*Make("newton"), value_only, 0, 1, 1e-6, 100);
  EXPECT_NE(message.find("2 outputs (f, f')"), std::string::npos) << message;
  // The others read only the first output.
  for (const char* name : {"bisection", "brent"})
    EXPECT_NEAR(Make(name)->FindRoot(value_only, 0, 1, 1e-7, 100).root, 0.25, 1e-6) << name;
}

TEST_F(RootFinderTest, NewtonSurvivesAZeroDerivative) {
  // f' = 0 at the start (the middle of the bracket): Newton's step is
  // undefined there, so the finder must bisect.
  Scalar f([](double x) { return x * x * x - 0.001; }, [](double x) { return 3 * x * x; });
  EXPECT_NEAR(Make("newton")->FindRoot(f, -1, 1, 1e-9, 100).root, 0.1, kFloatLimited);
}

TEST_F(RootFinderTest, InterpolationBeatsBisectionOnSmoothFunctions) {
  // A tolerance above float resolution, so that the counts reflect the
  // methods and not the float grid of the points.
  constexpr double kTolerance = 1e-6;
  const std::pair<const char*, Scalar (*)()> kFunctions[] = {{"cubic", Cubic},
                                                             {"cos_minus_x", CosMinusX}};
  for (const auto& [label, make] : kFunctions) {
    Scalar f = make();
    const uint32_t bisection = Make("bisection")->FindRoot(f, 0, 3, kTolerance, 100).iterations;
    const uint32_t newton = Make("newton")->FindRoot(f, 0, 3, kTolerance, 100).iterations;
    const uint32_t brent = Make("brent")->FindRoot(f, 0, 3, kTolerance, 100).iterations;
    RecordProperty(std::string("iterations_") + label, std::to_string(bisection) + " bisection, " +
                                     std::to_string(newton) + " newton, " +
                                     std::to_string(brent) + " brent");
    EXPECT_LE(3 * newton, bisection) << newton << " newton vs " << bisection << " bisection";
    EXPECT_LE(2 * brent, bisection) << brent << " brent vs " << bisection << " bisection";
  }
}

}  // namespace
}  // namespace yarf
