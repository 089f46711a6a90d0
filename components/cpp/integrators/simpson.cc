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
// Error estimate (reported as standard_error, per output): from the same
// nodes, the rule at spacings 2h, 4h and 8h too (no extra evaluations).
// Richardson's |S(n) − S(n/2)| / 15 is the error of S(n) once it falls as
// h^4, which is checked: both |S(n/2) − S(n/4)| / |S(n) − S(n/2)| and the
// next ratio must be near 16 (10 to 26). Where f has a jump, a kink or an
// integrable singularity they are not, and S(n)'s error is often larger
// than |S(n) − S(n/2)| itself (Richardson's estimate was 5–30 times too
// small on a step); the estimate is then the sum of the first two
// differences: above the error at 99% or more of the places of a step, a
// kink or √|x − c|, not so often near 1/√|x − c| (88%), where the nodes
// nearest the pole decide. It is at least the rounding of
// float32 values, 2^-24 of the rule applied to |f|. It is not a
// statistical σ. Coarse grids of an odd number of intervals end with
// Simpson's 3/8 rule on their last three; a single interval is the
// trapezoid.
//
// The number of intervals per axis is the largest even n with
// (n+1)^d ≤ evaluations (a multiple of 8, for the error estimate, when
// that keeps at least half the nodes), unless "intervals" sets it;
// `evaluations` in the result is (n+1)^d, the points actually used.
//
// Parameters: SimpsonIntegrator::Parameters() below.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
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

// The rule on the nodes of index a multiple of `step` (n / step intervals
// of step·h), as weights on the grid's n+1 nodes, without the factor h:
// Simpson's on an even number of intervals; on an odd number, Simpson's
// then the 3/8 rule on the last three; the trapezoid on one. Step 1 is
// the composite Simpson rule itself (n even).
std::vector<double> NestedWeights(uint64_t n, uint64_t step) {
  const uint64_t m = n / step;
  const double H = double(step);  // the coarse spacing, in units of h
  std::vector<double> w(n + 1, 0.0);
  if (m == 1) {
    w[0] = w[n] = H / 2;
    return w;
  }
  // Simpson on the first `simpson` intervals, 3/8 on the rest (0 or 3).
  const uint64_t simpson = m % 2 == 0 ? m : m - 3;
  for (uint64_t i = 0; i <= simpson && simpson > 0; ++i)
    w[step * i] += H * ((i == 0 || i == simpson) ? 1.0 / 3 : (i % 2 ? 4.0 / 3 : 2.0 / 3));
  if (simpson != m) {
    const double three_eighths[] = {3.0 / 8, 9.0 / 8, 9.0 / 8, 3.0 / 8};
    for (uint64_t i = 0; i < 4; ++i) w[step * (simpson + i)] += H * three_eighths[i];
  }
  return w;
}

// Spacings h, 2h, 4h, 8h: the levels of the error estimate.
constexpr int kLevels = 4;

// The levels the grid of n intervals nests: step 2^k while it divides n.
int NestedLevels(uint64_t n) {
  int levels = 1;
  while (levels < kLevels && n % (uint64_t(1) << levels) == 0) ++levels;
  return levels;
}

// S(n)'s error from the rule at each nested level (sums[0] the finest),
// n and the rounding of the values (see the top of the file). The ratios
// are trusted only when every level has two intervals or more: the
// trapezoid's error falls as h².
double ErrorEstimate(std::span<const double> sums, uint64_t n, double rounding) {
  std::vector<double> d;  // |S(h) − S(2h)|, |S(2h) − S(4h)|, …
  for (size_t k = 0; k + 1 < sums.size(); ++k) d.push_back(std::abs(sums[k] - sums[k + 1]));
  if (d.empty()) return rounding;
  const auto near_sixteen = [](double coarse, double fine) { return coarse >= 10 * fine && coarse <= 26 * fine; };
  if (d.size() == kLevels - 1 && n >= 16 && near_sixteen(d[1], d[0]) && near_sixteen(d[2], d[1]))
    return std::max(d[0] / 15, rounding);
  return std::max(d[0] + (d.size() > 1 ? d[1] : 0.0), rounding);
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
    const int levels = NestedLevels(n);
    std::vector<std::vector<double>> weights;  // per level, per node
    for (int k = 0; k < levels; ++k) weights.push_back(NestedWeights(n, uint64_t(1) << k));
    double cell = 1;  // h_1 · … · h_d, the factor left out of the weights
    for (uint32_t j = 0; j < d; ++j) cell *= (upper[j] - lower[j]) / double(n);

    // Per output: the rule's sum at each level, and the finest rule on |f|.
    std::vector<double> sums(size_t(k) * levels, 0.0), magnitude(k, 0.0);
    std::vector<float> points, values;
    std::vector<double> node_w;  // per point, per level
    std::vector<uint64_t> digit(d, 0);  // node index per axis, axis 0 fastest
    for (uint64_t first = 0; first < total; first += kBatch) {
      const uint64_t count = std::min(kBatch, total - first);
      points.resize(count * d);
      values.resize(count * k);
      node_w.assign(count * levels, 1.0);
      for (uint64_t i = 0; i < count; ++i) {
        for (uint32_t j = 0; j < d; ++j) {
          const uint64_t a = digit[j];
          const double x = a == n ? upper[j] : lower[j] + (upper[j] - lower[j]) * (double(a) / double(n));
          points[i * d + j] = float(x);
          for (int l = 0; l < levels; ++l) node_w[i * levels + l] *= weights[l][a];
        }
        for (uint32_t j = 0; j < d && ++digit[j] == nodes_per_axis; ++j) digit[j] = 0;
      }
      f.Evaluate(points, values);
      for (uint64_t i = 0; i < count; ++i)
        for (uint32_t c = 0; c < k; ++c) {
          const double v = values[i * k + c];
          for (int l = 0; l < levels; ++l) sums[c * levels + l] += node_w[i * levels + l] * v;
          magnitude[c] += node_w[i * levels] * std::abs(v);
        }
    }

    IntegrationResult result;
    result.evaluations = total;
    for (uint32_t c = 0; c < k; ++c) {
      std::vector<double> level_sums(levels);
      for (int l = 0; l < levels; ++l) level_sums[l] = cell * sums[c * levels + l];
      result.estimate.push_back(level_sums[0]);
      result.standard_error.push_back(ErrorEstimate(level_sums, n, std::ldexp(cell * magnitude[c], -24)));
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
    // One less than the nodes per axis of the largest grid within the
    // budget, even; a multiple of 8 (all four levels of the error estimate
    // nest) when that keeps at least half its nodes.
    const uint64_t n = CellsPerAxis(std::min(evaluations, kMaxNodes), d) - 1;
    const uint64_t nested = n - n % 8;
    return nested >= 16 && 2 * NodesCapped(nested + 1, d) >= NodesCapped(n + 1, d) ? nested : n - n % 2;
  }

  int64_t intervals_;
};

}  // namespace
}  // namespace yarf

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::SimpsonIntegrator>(registrar, "simpson", "1.0.0",
                                          "composite Simpson's rule (tensor product in d dimensions)");
}
