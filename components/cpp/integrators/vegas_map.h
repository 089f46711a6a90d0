// What vegas and vegas_plus share: the adaptive VEGAS map, the weighting of
// iterations by inverse variance with its χ² and Q, the statistics of J f,
// the properties that tune them and the iteration budget (see vegas.cc).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "integration_box.h"
#include "yarf/math.h"
#include "yarf/parameters.h"
#include "yarf/properties.h"

namespace yarf {

constexpr uint32_t kMinPointsPerIteration = 1000;
constexpr uint32_t kMaxBatch = 16384;
// What Lepage adds to every normalised bin weight before damping: a bin
// that saw no point (f vanished there) keeps a small width instead of
// collapsing for good, so a later iteration can still find f there.
constexpr double kTinyWeight = 1e-257;
// Where yarf departs from Lepage: after refinement the map's density along
// every axis stays at least this fraction of the uniform density, so that
// no bin is wider than 1 / kMinDensity uniform bins and J gains at most
// that factor per axis. Lepage lets the region where f vanishes collapse
// into a few bins; the bin that straddles a jump of f (Genz's
// discontinuous family) then grows wide and mostly empty, its rare points
// with f ≠ 0 carry huge J f, and the variance of an iteration is
// underestimated: his vegas falls within 2σ in a quarter of the runs on
// exp(x·a) cut at x_0 < 0.6, x_1 < 0.35 at 10⁴ points, yarf's in over 90%.
// The floor costs at most that fraction of the points per axis where f is
// small (a defensive mixture with the uniform density, as Hesterberg's
// defensive importance sampling).
constexpr double kMinDensity = 0.05;

// The separable piecewise-linear map y -> x of the box and the statistics
// that refine it.
class AdaptiveMap {
 public:
  // The map keeps three numbers per bin of every axis: at most this many bins.
  static constexpr uint64_t kMaxMapBins = uint64_t(1) << 22;

  AdaptiveMap(std::span<const double> lower, std::span<const double> upper, uint32_t bins)
      : dims_(uint32_t(CheckedBins(lower.size(), bins))), bins_(bins), edges_(size_t(dims_) * (bins + 1)),
        sums_(size_t(dims_) * bins, 0.0), mass_(size_t(dims_) * bins, 0.0) {
    for (uint32_t j = 0; j < dims_; ++j)
      for (uint32_t i = 0; i <= bins_; ++i)
        edges_[size_t(j) * (bins_ + 1) + i] = lower[j] + (upper[j] - lower[j]) * i / bins_;
  }

  // The number of axes, once their bins are known to fit kMaxMapBins.
  static size_t CheckedBins(size_t axes, uint32_t bins) {
    if (uint64_t(axes) * bins > kMaxMapBins)
      throw Error(std::to_string(bins) + " bins on each of " + std::to_string(axes) + " axes are " +
                  std::to_string(uint64_t(axes) * bins) + " bins, above " + std::to_string(kMaxMapBins));
    return axes;
  }

  // x(y) for one point; returns the Jacobian and notes each axis's bin.
  double Map(const double* y, float* x, uint32_t* bin) const {
    double jacobian = 1;
    for (uint32_t j = 0; j < dims_; ++j) {
      double xj;
      jacobian *= MapAxis(j, y[j], xj, bin[j]);
      x[j] = float(xj);
    }
    return jacobian;
  }

  // One axis alone: x_j(y_j), its bin, and its factor of the Jacobian.
  double MapAxis(uint32_t j, double y, double& x, uint32_t& bin) const {
    const double t = y * bins_;
    const uint32_t i = std::min(uint32_t(t), bins_ - 1);
    const double* e = &edges_[size_t(j) * (bins_ + 1)];
    const double width = e[i + 1] - e[i];
    x = e[i] + (t - i) * width;
    bin = i;
    return bins_ * width;
  }

  // Adds value = (J f)² of one point, with the weight of the point (the
  // inverse of its sampling density), to the averages of the bins it fell in.
  void Accumulate(const uint32_t* bin, double weight, double value) {
    for (uint32_t j = 0; j < dims_; ++j) AccumulateAxis(j, bin[j], weight, value);
  }
  void AccumulateAxis(uint32_t j, uint32_t bin, double weight, double value) {
    sums_[size_t(j) * bins_ + bin] += weight * value;
    mass_[size_t(j) * bins_ + bin] += weight;
  }
  // Adds another map's statistics (collected by another thread) to these.
  void Merge(const AdaptiveMap& other) {
    for (size_t b = 0; b < sums_.size(); ++b) {
      sums_[b] += other.sums_[b];
      mass_[b] += other.mass_[b];
    }
  }
  // Forgets the statistics, keeping the edges.
  void ClearStatistics() {
    std::fill(sums_.begin(), sums_.end(), 0.0);
    std::fill(mass_.begin(), mass_.end(), 0.0);
  }
  uint32_t dimensions() const { return dims_; }

  // A bin no point fell in (points are uniform in y, so a bin gets none
  // by chance when there are few per bin) has its neighbours' average
  // rather than 0: scored 0 it would shrink for nothing, and bend the map
  // of a constant integrand.
  static constexpr double kUnseen = -1;
  static void FillUnseenBins(std::vector<double>& d) {
    const size_t n = d.size();
    std::vector<double> left(n, kUnseen), right(n, kUnseen);
    for (size_t i = 1; i < n; ++i) left[i] = d[i - 1] != kUnseen ? d[i - 1] : left[i - 1];
    for (size_t i = n - 1; i-- > 0;) right[i] = d[i + 1] != kUnseen ? d[i + 1] : right[i + 1];
    for (size_t i = 0; i < n; ++i) {
      if (d[i] != kUnseen) continue;
      const bool l = left[i] != kUnseen, r = right[i] != kUnseen;
      d[i] = l && r ? (left[i] + right[i]) / 2 : l ? left[i] : r ? right[i] : 0;
    }
  }

  // Moves the edges of every axis so that each bin holds an equal share of
  // the smoothed, damped weights, then starts collecting afresh.
  void Refine(double alpha) {
    std::vector<double> d(bins_), smooth(bins_), damped(bins_), edges(bins_ + 1);
    for (uint32_t j = 0; j < dims_; ++j) {
      for (uint32_t i = 0; i < bins_; ++i) {
        const size_t b = size_t(j) * bins_ + i;
        d[i] = mass_[b] > 0 ? sums_[b] / mass_[b] : kUnseen;
      }
      FillUnseenBins(d);
      smooth[0] = (7 * d[0] + d[1]) / 8;
      smooth[bins_ - 1] = (d[bins_ - 2] + 7 * d[bins_ - 1]) / 8;
      for (uint32_t i = 1; i + 1 < bins_; ++i) smooth[i] = (d[i - 1] + 6 * d[i] + d[i + 1]) / 8;
      double total = 0;
      for (double s : smooth) total += s;
      // Nothing seen on this axis (f vanished at every point): keep the grid.
      if (!(total > 0) || !std::isfinite(total)) continue;
      double sum = 0;
      for (uint32_t i = 0; i < bins_; ++i) {
        const double r = smooth[i] / total + kTinyWeight;
        damped[i] = r > 0.99999999 ? r : std::pow((1 - r) / -std::log(r), alpha);
        sum += damped[i];
      }
      double* e = &edges_[size_t(j) * (bins_ + 1)];
      // The density floor (kMinDensity): every old bin holds at least its
      // share of the floor's weight by width.
      const double range = e[bins_] - e[0], floor = kMinDensity * sum / range;
      sum = 0;
      for (uint32_t i = 0; i < bins_; ++i) {
        damped[i] = std::max(damped[i], floor * (e[i + 1] - e[i]));
        sum += damped[i];
      }
      const double step = sum / bins_;
      edges[0] = e[0];
      edges[bins_] = e[bins_];
      uint32_t i = 0;
      double below = 0;  // damped weight of the old bins before bin i
      for (uint32_t k = 1; k < bins_; ++k) {
        const double target = k * step;
        while (i + 1 < bins_ && below + damped[i] < target) below += damped[i++];
        const double fraction = damped[i] > 0 ? std::clamp((target - below) / damped[i], 0.0, 1.0) : 1.0;
        edges[k] = e[i] + fraction * (e[i + 1] - e[i]);
      }
      std::copy(edges.begin(), edges.end(), e);
    }
    ClearStatistics();
  }

 private:
  uint32_t dims_, bins_;
  std::vector<double> edges_;    // [dims, bins + 1]
  std::vector<double> sums_, mass_;  // [dims, bins]
};

// Q(a, x) = Γ(a, x) / Γ(a), the regularised upper incomplete gamma
// function: by its power series below x = a + 1, by its continued fraction
// (evaluated by Lentz's method) above, where each converges fast.
inline double GammaQ(double a, double x) {
  if (!(x > 0)) return 1;
  const double prefactor = std::exp(a * std::log(x) - x - std::lgamma(a));
  if (x < a + 1) {
    double term = 1 / a, sum = term;
    for (int n = 1; n < 1000 && std::abs(term) > 1e-16 * std::abs(sum); ++n) {
      term *= x / (a + n);
      sum += term;
    }
    return std::clamp(1 - sum * prefactor, 0.0, 1.0);
  }
  constexpr double kFloor = 1e-300;
  double b = x + 1 - a, c = 1 / kFloor, d = 1 / b, h = d;
  for (int i = 1; i < 1000; ++i) {
    const double an = -i * (i - a);
    b += 2;
    d = an * d + b;
    if (std::abs(d) < kFloor) d = kFloor;
    c = b + an / c;
    if (std::abs(c) < kFloor) c = kFloor;
    d = 1 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1) < 1e-16) break;
  }
  return std::clamp(prefactor * h, 0.0, 1.0);
}

// The probability that χ² of `dof` degrees of freedom is at least chi2.
inline double ChiSquareQ(double chi2, double dof) { return GammaQ(dof / 2, chi2 / 2); }

// Iteration estimates of one output, combined by inverse variances.
//
// The variance an iteration is weighed by is its predecessor's (that of
// the iteration before it, kept or discarded; the first iteration of all
// has only its own). An iteration's own σ_t correlates with its estimate
// where J f has a heavy tail (an integrable singularity such as x^-½:
// the iterations whose points came near the pole have both the larger
// estimate and the larger σ_t), and weighing each by its own 1/σ_t² biased
// the average low by about 10 of its σ on ∫₀¹ x^-½. The predecessor's
// variance is measured on other points with nearly the same map, so it
// estimates the same precision without that correlation. The error is
// that of the weighted mean, √(Σ w_t² σ_t²) / Σ w_t, with the iterations'
// own variances.
//
// An iteration whose points agreed within every hypercube has a sample
// variance of 0: it measured nothing of its own precision (a step whose
// pairs of points each fell on one side, a small peak missed), and weighed
// by 1/0 it would be the answer, thousands of its σ off. Such a variance
// counts as missing: as a weight, the mean weight of the iterations that
// have one, as GSL's VEGAS does; in the error, that weight's variance.
// When no iteration measured a spread, all weigh the same and the error
// is their spread about the mean (0 for a constant integrand).
class Combination {
 public:
  // `weighing_variance`: the predecessor's variance (see above).
  void Add(double estimate, double variance, double weighing_variance) {
    estimates_.push_back(estimate);
    variances_.push_back(variance);
    weighing_.push_back(weighing_variance);
  }
  double Estimate() const {
    const std::vector<double> w = Weights();
    double sum = 0, weighted = 0;
    for (size_t t = 0; t < estimates_.size(); ++t) {
      sum += w[t];
      weighted += w[t] * estimates_[t];
    }
    return weighted / sum;
  }
  double Error() const {
    if (!Measured(variances_)) {
      // The standard error of the mean of the iterations' estimates.
      const double n = double(estimates_.size()), mean = Estimate();
      if (n < 2) return 0;
      double squares = 0;
      for (double e : estimates_) squares += (e - mean) * (e - mean);
      return std::sqrt(squares / (n - 1) / n);
    }
    const std::vector<double> w = Weights(), own = Fill(variances_);
    double sum = 0, variance = 0;
    for (size_t t = 0; t < w.size(); ++t) {
      sum += w[t];
      variance += w[t] * w[t] / own[t];
    }
    return std::sqrt(variance) / sum;
  }
  // Σ_t (I_t - I)² / σ_t² over the iterations, about their weighted mean,
  // with their own variances; 0 when no iteration measured a spread.
  double ChiSquare() const {
    if (!Measured(variances_)) return 0;
    const std::vector<double> own = Fill(variances_);
    const double mean = Estimate();
    double chi2 = 0;
    for (size_t t = 0; t < estimates_.size(); ++t)
      chi2 += (estimates_[t] - mean) * (estimates_[t] - mean) * own[t];
    return chi2;
  }
  double DegreesOfFreedom() const { return double(estimates_.size()) - 1; }
  // Near 1 when the iterations agree within their errors; much larger
  // means the per-iteration errors are not to be trusted. NaN for one
  // iteration.
  double ChiSquarePerDof() const {
    return estimates_.size() < 2 ? std::numeric_limits<double>::quiet_NaN() : ChiSquare() / DegreesOfFreedom();
  }
  // Lepage's Q: the probability of a χ² at least this large by chance.
  double Q() const {
    return estimates_.size() < 2 ? std::numeric_limits<double>::quiet_NaN()
                                  : ChiSquareQ(ChiSquare(), DegreesOfFreedom());
  }

 private:
  // Whether variance t measured a spread: beyond what rounding leaves of a
  // constant integrand's.
  bool Spread(const std::vector<double>& variances, size_t t) const {
    const double variance = variances[t];
    return variance > 1e-24 * estimates_[t] * estimates_[t] && std::isfinite(1 / variance);
  }
  bool Measured(const std::vector<double>& variances) const {
    for (size_t t = 0; t < variances.size(); ++t)
      if (Spread(variances, t)) return true;
    return false;
  }
  // 1/variance, the mean of those for a variance without spread; all 1
  // when none has one.
  std::vector<double> Fill(const std::vector<double>& variances) const {
    std::vector<double> w(variances.size(), 1.0);
    double sum = 0;
    size_t measured = 0;
    for (size_t t = 0; t < w.size(); ++t)
      if (Spread(variances, t)) {
        w[t] = 1 / variances[t];
        sum += w[t];
        ++measured;
      }
    if (measured > 0)
      for (size_t t = 0; t < w.size(); ++t)
        if (!Spread(variances, t)) w[t] = sum / double(measured);
    return w;
  }
  std::vector<double> Weights() const { return Fill(weighing_); }

  std::vector<double> estimates_, variances_, weighing_;
};

// The result of the iterations kept, every output of f combined apart.
inline IntegrationResult CombinedResult(const std::vector<Combination>& combined, uint64_t evaluations) {
  IntegrationResult result;
  result.evaluations = evaluations;
  for (const Combination& c : combined) {
    result.estimate.push_back(c.Estimate());
    result.standard_error.push_back(c.Error());
    result.chi2_per_dof.push_back(c.ChiSquarePerDof());
    result.q.push_back(c.Q());
  }
  return result;
}

// Mean and sum of squared deviations of a stream. The sums are of values
// shifted by the first one, which keeps them precise when the spread is
// small beside the mean (J f of a nearly constant f) without a division
// per value.
struct Moments {
  uint64_t count = 0;
  double shift = 0, sum = 0, sum_sq = 0;
  void Add(double v) {
    if (count++ == 0) shift = v;
    const double s = v - shift;
    sum += s;
    sum_sq += s * s;
  }
  double Mean() const { return shift + sum / double(count); }
  double SquaredDeviations() const { return std::max(0.0, sum_sq - sum * sum / double(count)); }
};

// Splits n points into equal batches of at most kMaxBatch, calling
// visit(begin, count) for each in turn.
template <typename Visit>
void ForEachBatch(uint64_t n, Visit visit) {
  const uint64_t batches = (n + kMaxBatch - 1) / kMaxBatch;
  for (uint64_t b = 0; b < batches; ++b) {
    const uint64_t begin = n * b / batches, end = n * (b + 1) / batches;
    visit(begin, uint32_t(end - begin));
  }
}

// The buffers of one call to f: the sampler's points u in the unit cube,
// the points x of the box that the map makes of them with its Jacobian and
// bins, and f(x).
struct VegasBatch {
  VegasBatch(uint32_t d, uint32_t k) : d(d), k(k) {}

  // Draws `count` points from the sampler, from index `first` on.
  void Draw(const Sampler& sampler, uint64_t first, uint32_t count, uint64_t seed) {
    u.resize(size_t(count) * d);
    points.resize(size_t(count) * d);
    values.resize(size_t(count) * k);
    jacobian.resize(count);
    bins.resize(size_t(count) * d);
    sampler.Generate(first, count, d, seed, u);
  }
  // Point i: y, placed in the unit cube from u, mapped onto the box.
  void Place(const AdaptiveMap& map, uint32_t i, const double* y) {
    jacobian[i] = map.Map(y, &points[size_t(i) * d], &bins[size_t(i) * d]);
  }
  // Adds J f of point i to the moments of every output, and (J f)² of the
  // first output, with the point's weight, to the map's statistics.
  void Accumulate(uint32_t i, std::vector<Moments>& moments, AdaptiveMap& map, double weight) const {
    for (uint32_t c = 0; c < k; ++c) moments[c].Add(jacobian[i] * values[size_t(i) * k + c]);
    const double driver = jacobian[i] * values[size_t(i) * k];
    map.Accumulate(&bins[size_t(i) * d], weight, driver * driver);
  }

  uint32_t d, k;
  std::vector<float> u, points, values;
  std::vector<double> jacobian;
  std::vector<uint32_t> bins;
};

// The properties of the map and the iterations.
struct VegasSettings {
  // Lepage's damping exponent of the map refinement.
  static constexpr double kDefaultAlpha = 0.5;
  // Bins of the image mode's map when "bins" is not given.
  static constexpr uint32_t kImageBins = 50;
  // Bounds of "bins" and "iterations": beyond them a job is a mistake.
  static constexpr int64_t kMaxBins = 1 << 20, kMaxIterations = 100000;

  // The parameters read here, which vegas and vegas_plus declare. "bins"
  // and "discard" have no declared default: theirs depend on the job.
  static ParameterSchema Parameters() {
    using P = Parameter;
    return {
        P::Int("bins").Range(2, kMaxBins).Doc(
            "map bins per axis; default: points per iteration / 10 (≤ 1000), 50 in renders"),
        P::Int("iterations").Default(10).Range(1, kMaxIterations).Doc("iterations, Lepage's nitn"),
        P::Float("alpha").Default(kDefaultAlpha).Min(0).Doc("damping exponent of the map refinement; 0 freezes it"),
        P::Int("discard").Min(0).Doc("leading iterations left out, < iterations; default min(2, iterations − 1)"),
    };
  }

  explicit VegasSettings(const Properties& props)
      : bins(props.Int("bins", 0)), iterations(props.Int("iterations", 10)),
        alpha(props.Float("alpha", kDefaultAlpha)),
        // The default shrinks with `iterations` so that one iteration alone is valid.
        discard(props.Int("discard", std::clamp<int64_t>(iterations - 1, 0, 2))) {
    if (props.Has("bins") && (bins < 2 || bins > kMaxBins))
      throw Error("property 'bins' must be in [2, " + std::to_string(kMaxBins) + "]");
    if (iterations < 1 || iterations > kMaxIterations)
      throw Error("property 'iterations' must be in [1, " + std::to_string(kMaxIterations) + "]");
    if (!(alpha >= 0) || !std::isfinite(alpha)) throw Error("property 'alpha' must be a finite number >= 0");
  }

  // Separate from the checks above so that an integrator can check its own
  // properties (vegas_plus's beta) before this one.
  void CheckDiscard() const {
    if (discard < 0 || discard >= iterations)
      throw Error("property 'discard' must be in [0, iterations - 1]");
  }

  // Iterations run for a budget: fewer than asked when each would get
  // under kMinPointsPerIteration points, but at least one.
  uint64_t IterationsFor(uint64_t evaluations) const {
    return std::clamp<uint64_t>(evaluations / kMinPointsPerIteration, 1, uint64_t(iterations));
  }
  // Leading iterations left out, lowered to keep at least one.
  uint64_t DiscardOf(uint64_t iterations_run) const {
    return std::min<uint64_t>(uint64_t(discard), iterations_run - 1);
  }
  // Map bins per axis for n points per iteration, `strata` strata on the
  // most stratified axis: the "bins" given, else Lepage's choice, a tenth
  // of the points up to 1000, rounded down to a multiple of the strata so
  // that stratum walls are bin edges (at least one bin per stratum).
  uint32_t BinsFor(uint64_t n, uint32_t strata) const {
    if (bins > 0) return uint32_t(bins);
    const uint64_t tenth = std::min<uint64_t>(n / 10, 1000);
    const uint64_t chosen = tenth >= strata ? tenth / strata * strata : strata;
    return uint32_t(std::clamp<uint64_t>(chosen, 2, 1 << 20));
  }
  uint32_t ImageBins() const { return bins > 0 ? uint32_t(bins) : kImageBins; }

  int64_t bins;  // 0: chosen from the points per iteration (BinsFor)
  int64_t iterations;
  double alpha;
  int64_t discard;
};

// Points of iteration t: the budget shared evenly, the remainder going to
// the first iterations.
inline uint64_t PointsOfIteration(uint64_t evaluations, uint64_t iterations, uint64_t t) {
  return evaluations / iterations + (t < evaluations % iterations ? 1 : 0);
}

// The checks on a job; `name` names the integrator in the messages.
inline void CheckVegasJob(const std::string& name, uint32_t d, uint32_t k, std::span<const double> lower,
                          std::span<const double> upper, uint64_t evaluations) {
  CheckBoxDimensions(lower, upper, d);
  CheckFiniteBounds(lower, upper);
  if (d == 0 || k == 0) throw Error(name + " needs a function with at least one input and one output");
  if (evaluations < 2) throw Error("need at least 2 evaluations");
}

}  // namespace yarf
