// What the root finders share: the checks of a call, f at the ends of the
// bracket, and the messages of their errors.
#pragma once

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "yarf/math.h"

namespace yarf {

// Shortest text that reads back as the same number; values of f are
// floats, and shown as such.
template <typename T>
std::string Str(T v) {
  char buffer[32];
  const auto end = std::to_chars(buffer, buffer + sizeof buffer, v).ptr;
  return std::string(buffer, end);
}

// The value of f at x, which must be a finite number.
inline double Checked(double x, float value) {
  if (!std::isfinite(value)) throw Error("f(" + Str(x) + ") = " + Str(value) + " is not a finite number");
  return value;
}

// The first output of f at x, evaluated alone into the first row of `values`.
inline double ValueAt(Function& f, double x, std::vector<float>& values) {
  const float point = float(x);
  f.Evaluate(std::span<const float>(&point, 1), std::span<float>(values).first(f.OutputDimensions()));
  return Checked(x, values[0]);
}

// The error of a finder that ran out of iterations with the root in [a, b]
// (either order); `reason` says why it had not converged.
inline Error NotConverged(uint32_t max_iterations, double a, double b, const std::string& reason) {
  return Error("did not converge in " + std::to_string(max_iterations) + " iterations: the root lies in [" +
               Str(std::min(a, b)) + ", " + Str(std::max(a, b)) + "], " + reason);
}

// f at the ends of the bracket.
struct EndValues {
  double lower, upper;
};

// A root finder that narrows a bracket. FindRoot checks the call and
// evaluates f at both ends in one batch: an end where f vanishes is the
// root, otherwise f must change sign between them, and Search takes over.
class BracketingRootFinder : public RootFinder {
 public:
  // f must have one input and at least `outputs` outputs; `needs` says so
  // in the error when it has not.
  explicit BracketingRootFinder(
      uint32_t outputs = 1,
      std::string needs = "root finding needs a function of one variable with at least one output")
      : outputs_(outputs), needs_(std::move(needs)) {}

  RootResult FindRoot(Function& f, double lower, double upper, double tolerance,
                      uint32_t max_iterations) final {
    if (f.InputDimensions() != 1 || f.OutputDimensions() < outputs_)
      throw Error(needs_ + ", not " + std::to_string(f.InputDimensions()) + " -> " +
                  std::to_string(f.OutputDimensions()));
    if (!(std::isfinite(lower) && std::isfinite(upper) && lower < upper))
      throw Error("bracket [" + Str(lower) + ", " + Str(upper) + "] must be finite with lower < upper");
    if (!(tolerance > 0)) throw Error("tolerance must be positive, not " + Str(tolerance));
    const size_t k = f.OutputDimensions();
    // Rows of f's outputs: two for the ends, then one per evaluation.
    std::vector<float> values(2 * k);
    const float points[2] = {float(lower), float(upper)};
    f.Evaluate(points, values);
    const EndValues ends{Checked(lower, values[0]), Checked(upper, values[k])};
    if (ends.lower == 0) return {lower, 0};
    if (ends.upper == 0) return {upper, 0};
    if ((ends.lower < 0) == (ends.upper < 0))
      throw Error("no root bracketed in [" + Str(lower) + ", " + Str(upper) + "]: f(" + Str(lower) +
                  ") = " + Str(float(ends.lower)) + ", f(" + Str(upper) + ") = " + Str(float(ends.upper)));
    return Search(f, lower, upper, ends, tolerance, max_iterations, values);
  }

 protected:
  // The search from a checked bracket, f having opposite signs at its ends;
  // `values` has room for a row of f's outputs.
  virtual RootResult Search(Function& f, double lower, double upper, EndValues ends, double tolerance,
                            uint32_t max_iterations, std::vector<float>& values) = 0;

 private:
  uint32_t outputs_;
  std::string needs_;
};

}  // namespace yarf
