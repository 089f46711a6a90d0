// newton — root of f by Newton–Raphson steps, safeguarded by bisection
//
// Newton's step x ← x - f(x)/f'(x) doubles the correct digits per step
// near a simple root, but far from it, or where f' is small, it can jump
// anywhere. So the finder keeps a bracket [xl, xh] with f(xl) < 0 < f(xh),
// narrowed by the sign of every evaluation, and bisects instead of taking a
// Newton step that would leave the bracket or that is not at most half the
// step before last (the steps are not shrinking fast enough — at a
// multiple root or on a flat stretch Newton converges only linearly). The
// result converges for any f with a sign change, quadratically near a
// simple root; at a root of multiplicity m Newton gains only a factor
// m / (m - 1) per step, which for m > 2 is slower than bisection.
//
// FindRoot(f, lower, upper, tolerance, max_iterations): f is a Function
// of one input with at least two outputs, (f(x), f'(x)) — the derivative
// comes from f itself; further outputs are ignored. Starts from the middle
// of the bracket. Converges when a step moves x by less than tolerance (a
// bisection step: when the bracket is narrower than twice the tolerance),
// or when no float lies strictly inside the bracket where the step would
// go (a Function's points are float32, so f can tell the root no closer).
// Iterations are the evaluations of f after the two at the ends; a root
// exactly at an end is returned after none.
// Errors: fewer than two outputs, f(lower) and f(upper) of the same sign
// ("no root bracketed"), no convergence within max_iterations, tolerance
// ≤ 0, lower ≥ upper, f not of one variable, f not finite. A derivative
// that is not finite makes that step a bisection.
//
// Parameters: none (Newton::Parameters() below).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "bracket.h"
#include "yarf/plugin.h"

namespace {

class Newton final : public yarf::BracketingRootFinder {
 public:
  static yarf::ParameterSchema Parameters() { return {}; }

  explicit Newton(const yarf::Properties&)
      : BracketingRootFinder(2, "newton needs a function of one variable with 2 outputs (f, f')") {}

 private:
  yarf::RootResult Search(yarf::Function& f, double lower, double upper, yarf::EndValues ends,
                          double tolerance, uint32_t max_iterations, std::vector<float>& values) override {
    // f(xl) < 0 < f(xh); xl may lie above xh.
    double xl = ends.lower < 0 ? lower : upper;
    double xh = ends.lower < 0 ? upper : lower;
    // Whether a point lies strictly inside the bracket.
    const auto inside = [&](double at) { return std::min(xl, xh) < at && at < std::max(xl, xh); };
    // Points are rounded to the floats f sees, so that the value and slope
    // found belong to the point recorded.
    double x = double(float(0.5 * (lower + upper)));
    if (!inside(x)) return {0.5 * (lower + upper), 0};
    double fx = 0, dfx = 0;
    const auto evaluate_at = [&](double at) {
      fx = yarf::ValueAt(f, at, values);
      // Without a usable slope the sign still narrows the bracket.
      dfx = std::isfinite(values[1]) ? values[1] : 0.0;
    };
    const auto not_converged = [&] {
      return yarf::NotConverged(max_iterations, xl, xh,
                                "and the last step was not below the tolerance " + yarf::Str(tolerance));
    };
    if (max_iterations == 0) throw not_converged();
    evaluate_at(x);
    uint32_t iterations = 1;
    // The last step and the one before. Both start as the bracket's width,
    // so the first Newton step must be under half of it.
    double step = upper - lower, step_before = step;
    for (;;) {
      if (fx == 0) return {x, iterations};
      (fx < 0 ? xl : xh) = x;
      // Where the Newton step would land relative to the bracket's ends,
      // scaled by f'² (so that f' = 0 counts as outside, without dividing).
      const bool leaves_bracket = ((x - xh) * dfx - fx) * ((x - xl) * dfx - fx) >= 0;
      const bool too_slow = std::abs(2 * fx) > std::abs(step_before * dfx);
      step_before = step;
      double next;
      if (leaves_bracket || too_slow) {
        step = 0.5 * (xh - xl);
        next = xl + step;
      } else {
        step = fx / dfx;
        next = x - step;
        // A step below float resolution would evaluate x again: take the
        // neighbouring float instead (where the sign is likely to flip,
        // closing the bracket), as Brent's method steps at least its
        // tolerance.
        if (float(next) == float(x))
          next = std::nextafter(float(x), step > 0 ? -HUGE_VALF : HUGE_VALF);
      }
      if (std::abs(step) < tolerance) return {next, iterations};
      // A Newton step within half a float of an end learns nothing there:
      // bisect instead; when even the middle is an end, f cannot say more.
      if (!inside(double(float(next)))) {
        step = 0.5 * (xh - xl);
        next = xl + step;
        if (!inside(double(float(next)))) return {next, iterations};
      }
      if (iterations == max_iterations) throw not_converged();
      x = double(float(next));
      evaluate_at(x);
      ++iterations;
    }
  }
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Newton>(registrar, "newton", "1.0.0",
                         "Root of a function and its derivative: Newton-Raphson safeguarded by "
                         "bisection");
}
