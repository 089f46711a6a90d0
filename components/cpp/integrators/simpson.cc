// simpson — composite Simpson's rule, in one dimension and as a tensor
// product in d dimensions.
//
// Integrate: each axis of the box is cut into n equal intervals (n even)
// and f is evaluated at the (n+1)^d grid nodes; the estimate is the sum of
// f times the product of the per-axis Simpson weights (h/3)·(1 4 2 4 … 2 4 1).
// It is exact for polynomials of degree ≤ 3 in each variable, and its error
// falls as h^4 for smooth f. The sampler and seed are not used: the rule is
// deterministic.
//
// Error estimate (reported as standard_error, per output): Richardson's,
// |S(n) − S(n/2)| / 15, where S(n/2) is the rule on the nodes of even
// index only (no extra evaluations). It estimates the error of S(n) when f
// is smooth and h small; it is not a statistical σ. When n/2 is odd the
// coarse rule ends with Simpson's 3/8 rule on its last three intervals
// (a larger error constant, so the estimate errs on the large side); with
// n = 2 the coarse rule is the trapezoid on one interval and the estimate
// is |S(2) − T(1)|, a loose upper bound.
//
// The number of intervals per axis is the largest even n with
// (n+1)^d ≤ evaluations, unless "intervals" sets it; `evaluations` in the
// result is (n+1)^d, the points actually used.
//
// Parameters: SimpsonIntegrator::Parameters() below.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "integration_box.h"
#include "yarf/plugin.h"

namespace yarf {
namespace {

// Past this many grid nodes a run would take hours: a mistake, not a job.
constexpr uint64_t kMaxNodes = uint64_t(1) << 40;
// Points per Evaluate call: large, since f may live in another process.
constexpr uint64_t kBatch = 8192;

// base^exponent, or kMaxNodes + 1 when it exceeds kMaxNodes.
uint64_t NodesCapped(uint64_t base, uint32_t exponent) {
  return PowerCapped(base, exponent, kMaxNodes);
}

// Composite Simpson weights on n+1 nodes (n even), without the factor h.
std::vector<double> SimpsonWeights(uint64_t n) {
  std::vector<double> w(n + 1, 0.0);
  for (uint64_t i = 0; i <= n; ++i) w[i] = (i == 0 || i == n) ? 1.0 / 3 : (i % 2 ? 4.0 / 3 : 2.0 / 3);
  return w;
}

// The coarse rule on the even nodes of the fine grid (spacing 2h), as
// weights on the fine grid's n+1 nodes, without the factor h.
std::vector<double> CoarseWeights(uint64_t n) {
  const uint64_t m = n / 2;  // coarse intervals
  std::vector<double> w(n + 1, 0.0);
  if (m == 1) {  // trapezoid, H/2·(1 1) with H = 2h
    w[0] = w[n] = 1.0;
    return w;
  }
  // Simpson on the first `simpson` coarse intervals, 3/8 on the rest (0 or 3).
  const uint64_t simpson = m % 2 == 0 ? m : m - 3;
  for (uint64_t i = 0; i <= simpson && simpson > 0; ++i)
    w[2 * i] += 2.0 * ((i == 0 || i == simpson) ? 1.0 / 3 : (i % 2 ? 4.0 / 3 : 2.0 / 3));
  if (simpson != m) {
    const double three_eighths[] = {3.0 / 8, 9.0 / 8, 9.0 / 8, 3.0 / 8};
    for (uint64_t i = 0; i < 4; ++i) w[2 * (simpson + i)] += 2.0 * three_eighths[i];
  }
  return w;
}

class SimpsonIntegrator final : public Integrator {
 public:
  static ParameterSchema Parameters() {
    using P = Parameter;
    return {
        P::Int("intervals").Default(0).Range(0, 1 << 24).Doc("intervals per axis, even; 0: the most the budget allows"),
    };
  }

  // The weights are a vector of intervals + 1: bounded before they are made.
  explicit SimpsonIntegrator(const Properties& props) : intervals_(props.Int("intervals", 0, 0, 1 << 24)) {
    if (intervals_ != 0 && (intervals_ < 2 || intervals_ % 2 != 0))
      throw Error("property 'intervals' must be 0 (from the budget) or an even number ≥ 2");
  }

  IntegrationResult Integrate(Function& f, std::span<const double> lower,
                              std::span<const double> upper, uint64_t evaluations, uint64_t,
                              const Sampler&) override {
    const uint32_t d = f.InputDimensions(), k = f.OutputDimensions();
    CheckProperBox(lower, upper, d);

    const uint64_t n = Intervals(d, evaluations);
    const uint64_t nodes_per_axis = n + 1;
    const uint64_t total = NodesCapped(nodes_per_axis, d);
    const std::vector<double> fine = SimpsonWeights(n), coarse = CoarseWeights(n);
    double cell = 1;  // h_1 · … · h_d, the factor left out of the weights
    for (uint32_t j = 0; j < d; ++j) cell *= (upper[j] - lower[j]) / double(n);

    std::vector<double> fine_sum(k, 0.0), coarse_sum(k, 0.0);
    std::vector<float> points, values;
    std::vector<double> fine_w, coarse_w;
    std::vector<uint64_t> digit(d, 0);  // node index per axis, axis 0 fastest
    for (uint64_t first = 0; first < total; first += kBatch) {
      const uint64_t count = std::min(kBatch, total - first);
      points.resize(count * d);
      values.resize(count * k);
      fine_w.resize(count);
      coarse_w.resize(count);
      for (uint64_t i = 0; i < count; ++i) {
        double wf = 1, wc = 1;
        for (uint32_t j = 0; j < d; ++j) {
          const uint64_t a = digit[j];
          const double x = a == n ? upper[j] : lower[j] + (upper[j] - lower[j]) * (double(a) / double(n));
          points[i * d + j] = float(x);
          wf *= fine[a];
          wc *= coarse[a];
        }
        fine_w[i] = wf;
        coarse_w[i] = wc;
        for (uint32_t j = 0; j < d && ++digit[j] == nodes_per_axis; ++j) digit[j] = 0;
      }
      f.Evaluate(points, values);
      for (uint64_t i = 0; i < count; ++i)
        for (uint32_t c = 0; c < k; ++c) {
          const double v = values[i * k + c];
          fine_sum[c] += fine_w[i] * v;
          coarse_sum[c] += coarse_w[i] * v;
        }
    }

    IntegrationResult result;
    result.evaluations = total;
    for (uint32_t c = 0; c < k; ++c) {
      const double s = cell * fine_sum[c], s_coarse = cell * coarse_sum[c];
      result.estimate.push_back(s);
      result.standard_error.push_back(std::abs(s - s_coarse) / (n == 2 ? 1.0 : 15.0));
    }
    return result;
  }

 private:
  // Intervals per axis: the property, or the largest even n whose grid
  // fits the budget.
  uint64_t Intervals(uint32_t d, uint64_t evaluations) const {
    if (intervals_ != 0) {
      if (NodesCapped(uint64_t(intervals_) + 1, d) > kMaxNodes)
        throw Error("property 'intervals' gives more than 2^40 grid nodes in " + std::to_string(d) +
                    " dimensions");
      return uint64_t(intervals_);
    }
    if (NodesCapped(3, d) > evaluations)
      throw Error("simpson needs at least 3^d = " +
                  (NodesCapped(3, d) > kMaxNodes ? std::string("more than 2^40")
                                                 : std::to_string(NodesCapped(3, d))) +
                  " evaluations in " + std::to_string(d) + " dimensions");
    // One less than the nodes per axis of the largest grid within the budget.
    const uint64_t n = CellsPerAxis(std::min(evaluations, kMaxNodes), d) - 1;
    return n - n % 2;
  }

  int64_t intervals_;
};

}  // namespace
}  // namespace yarf

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::SimpsonIntegrator>(registrar, "simpson", "1.0.0",
                                          "composite Simpson's rule (tensor product in d dimensions)");
}
