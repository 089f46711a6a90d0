// brent — root of f by Brent's method
//
// Brent's method (1973) keeps a bracket [b, c] with f(b), f(c) of opposite
// signs, b the end where |f| is smaller (the current estimate), and a the
// previous estimate. Each step fits a curve through the last points and
// steps to its zero: inverse quadratic interpolation — x as a quadratic
// in y through (f(a), a), (f(b), b), (f(c), c), evaluated at y = 0 — when
// the three points differ, the secant otherwise. It takes that step only if
// it lands well inside the bracket (within 3/4 of the way from b to c) and
// is less than half the step before last; otherwise it bisects. So it is
// superlinear near a simple root, always converges (at worst a few times
// slower than bisection, at a multiple root, where interpolation gains
// only linearly), and it needs f alone, not its derivative.
//
// FindRoot(f, lower, upper, tolerance, max_iterations): f is a Function of
// one input; its first output is f(x) (further outputs are ignored).
// Converges when the bracket is narrower than tolerance + 4ε|x|, with ε
// float's epsilon (a Function's points are float32, so f can tell the
// root no closer), and returns its end with the smaller |f|. Iterations
// are the evaluations of f after the two at the ends; a root exactly at
// an end is returned after none.
// Errors: f(lower) and f(upper) of the same sign ("no root bracketed"),
// the bracket still too wide after max_iterations ("did not converge"),
// tolerance ≤ 0, lower ≥ upper, f not of one variable, f not finite.
//
// Parameters: none (Brent::Parameters() below).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "bracket.h"
#include "yarf/plugin.h"

namespace {

class Brent final : public yarf::BracketingRootFinder {
 public:
  static yarf::ParameterSchema Parameters() { return {}; }

  explicit Brent(const yarf::Properties&) {}

 private:
  yarf::RootResult Search(yarf::Function& f, double lower, double upper, yarf::EndValues ends,
                          double tolerance, uint32_t max_iterations, std::vector<float>& values) override {
    double a = lower, fa = ends.lower;
    double b = upper, fb = ends.upper;

    // c: the other end of the bracket. step: the last step; step_before:
    // the one before it, which an interpolation step must beat by half.
    double c = a, fc = fa;
    double step = b - a, step_before = step;
    // The precision of x as f sees it: f's points are floats.
    constexpr double kEpsilon = std::numeric_limits<float>::epsilon();
    for (uint32_t iterations = 0;; ++iterations) {
      // b is the estimate: the end with the smaller |f|.
      if (std::abs(fc) < std::abs(fb)) {
        a = b;
        fa = fb;
        std::swap(b, c);
        std::swap(fb, fc);
      }
      // Half the tolerance, plus two float spacings of b: no step is
      // smaller, so that every point evaluated is a new float.
      const double tol = 2 * kEpsilon * std::abs(b) + 0.5 * tolerance;
      const double half = 0.5 * (c - b);
      if (std::abs(half) <= tol || fb == 0) return {b, iterations};
      if (iterations == max_iterations)
        throw yarf::NotConverged(max_iterations, b, c, "wider than the tolerance " + yarf::Str(tolerance));

      bool bisect = true;
      if (std::abs(step_before) >= tol && std::abs(fa) > std::abs(fb)) {
        // The step from b to the interpolant's zero, as p / q.
        double p, q;
        const double s = fb / fa;
        if (a == c) {
          // Two distinct points: the secant through (a, fa), (b, fb).
          p = 2 * half * s;
          q = 1 - s;
        } else {
          // Inverse quadratic interpolation through a, b and c, by
          // Lagrange's formula for x(y) at y = 0 rearranged around b.
          const double qa = fa / fc, r = fb / fc;
          p = s * (2 * half * qa * (qa - r) - (b - a) * (r - 1));
          q = (qa - 1) * (r - 1) * (s - 1);
        }
        // Orient so that p ≥ 0; the step's sign is then q's.
        if (p > 0)
          q = -q;
        else
          p = -p;
        // Accept if the step lands within 3/4 of the way to c (short of
        // where the interpolant is poor) and is under half the step
        // before last (so that the steps keep shrinking fast).
        if (2 * p < std::min(3 * half * q - std::abs(tol * q), std::abs(step_before * q))) {
          step_before = step;
          step = p / q;
          bisect = false;
        }
      }
      if (bisect) {
        step = half;
        step_before = half;
      }
      a = b;
      fa = fb;
      // A step under the tolerance would evaluate f where it tells nothing
      // new: step by the tolerance toward c instead.
      // Rounded to the float f sees, so that fb is f at b itself.
      b = double(float(b + (std::abs(step) > tol ? step : std::copysign(tol, half))));
      fb = yarf::ValueAt(f, b, values);
      // Keep the sign change between b and c.
      if ((fb < 0) == (fc < 0)) {
        c = a;
        fc = fa;
        step = b - a;
        step_before = step;
      }
    }
  }
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Brent>(registrar, "brent", "1.0.0",
                        "Root of a function by Brent's method (inverse quadratic interpolation "
                        "with bisection)");
}
