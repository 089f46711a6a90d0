// bisection — root of f by halving a bracket
//
// Keeps an interval [a, b] on whose ends f has opposite signs and halves it
// at every step, keeping the half where the sign changes. Slow (one bit of
// the root per evaluation) but certain: it needs nothing of f but its sign,
// so it converges for any continuous f, and for a discontinuous one finds
// the point where the sign flips.
//
// FindRoot(f, lower, upper, tolerance, max_iterations): f is a Function of
// one input; its first output is f(x) (further outputs are ignored).
// Converges when the bracket is narrower than tolerance, or when no float
// lies strictly inside it (a Function's points are float32, so f can tell
// the root no closer), and returns its middle. Iterations are the
// evaluations of f after the two at the ends; a root exactly at an end is
// returned after none.
// Errors: f(lower) and f(upper) of the same sign ("no root bracketed"),
// the bracket still too wide after max_iterations ("did not converge"),
// tolerance ≤ 0, lower ≥ upper, f not of one variable, f not finite.
//
// Parameters: none (Bisection::Parameters() below).
#include <cstdint>
#include <string>
#include <vector>

#include "bracket.h"
#include "yarf/plugin.h"

namespace {

class Bisection final : public yarf::BracketingRootFinder {
 public:
  static yarf::ParameterSchema Parameters() { return {}; }

  explicit Bisection(const yarf::Properties&) {}

 private:
  yarf::RootResult Search(yarf::Function& f, double lower, double upper, yarf::EndValues ends,
                          double tolerance, uint32_t max_iterations, std::vector<float>& values) override {
    double a = lower, b = upper, fa = ends.lower;
    for (uint32_t iterations = 0;; ++iterations) {
      // The middle as f sees it, so that the sign found is the sign there.
      const double mid = double(float(a + 0.5 * (b - a)));
      if (b - a < tolerance || !(a < mid && mid < b)) return {a + 0.5 * (b - a), iterations};
      if (iterations == max_iterations)
        throw yarf::NotConverged(max_iterations, a, b, "wider than the tolerance " + yarf::Str(tolerance));
      const double fm = yarf::ValueAt(f, mid, values);
      if (fm == 0) return {mid, iterations + 1};
      if ((fm < 0) == (fa < 0)) {
        a = mid;
        fa = fm;
      } else {
        b = mid;
      }
    }
  }
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Bisection>(registrar, "bisection", "1.0.0",
                            "Root of a function by bisection of a bracket");
}
