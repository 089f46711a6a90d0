// adaptive_hierarchical — Kajiya's adaptive hierarchical integration ("The
// rendering equation", 1986): the box is cut into a k-d tree of cells,
// refined where f varies most, and each cell is sampled in proportion to
// how much it can still add to the error — stratified sampling on strata
// that the samples themselves chose.
//
// Integrate, in T = "iterations" iterations of about N / T points each:
//
// 1. Allocate: leaf c, of volume v_c (a share of the box) and spread s_c
//    (the standard deviation of f over it, from the last iteration's
//    points, and never below 0.8 of the one before, so that a leaf whose
//    points all missed a feature once keeps most of its share), gets
//      n_c = 4 + ⌊free · (floor · v_c + (1 − floor) · v_c s_c / Σ v·s)⌋,
//    Neyman's allocation ∝ v·s with a defensive share ∝ v ("floor"), so
//    that a cell whose last points all missed a feature is not starved.
//    The first iteration has one leaf, the box: plain Monte Carlo.
// 2. Sample: fresh points, uniform in each leaf. The iteration's estimate
//    is Σ v_c · mean_c and its variance Σ v_c² s_c² / n_c: stratified
//    sampling on a tree fixed before its points were drawn, so unbiased
//    with an honest error bar.
// 3. Refine: the leaf of largest v·s is cut in two at the middle of the
//    axis whose halves' spreads s_a + s_b (from the leaf's points) are
//    least, the longest axis among equals; its points go to the halves,
//    and a half's spread is at least half its parent's, so that a half
//    whose few points missed the feature its parent saw keeps a share.
//    Cuts go on while the largest has ≥ 2 · "cell_points" points and every
//    leaf can still get its 4 points next iteration.
//
// The iterations after the first "discard" (default 1, the plain Monte
// Carlo one) are averaged with equal weights, the variance of the average
// being Σ σ_t² / T'², with χ²/dof and Q saying whether they agree (about
// their inverse-variance-weighted mean: see EqualWeights). Unlike vegas, yarf does not weight them by their inverse
// variances: on a feature smaller than the leaves, an iteration that
// missed part of it is low and has a small σ together, and weighting by
// 1/σ² would pull the average down and shrink its error bar (on a 4-D
// peak of width 0.02 at 10⁵ points this halves the runs within 2σ).
// With several outputs a cell's spread is the root of the sum of their
// variances. Points are independent ("independent" sampler): leaf c's
// points in iteration t are the sampler's sequence for the seed
// Hash(seed, t, c's bounds), so a result depends only on (seed, budget).
//
// Parameters: AdaptiveHierarchicalIntegrator::Parameters() below.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <queue>
#include <string>
#include <vector>

#include "integration_box.h"
#include "vegas_map.h"
#include "yarf/support/hash.h"
#include "yarf/plugin.h"

namespace yarf {
namespace {

// Points per Evaluate call: large, since f may live in another process.
constexpr uint64_t kBatch = 8192;
// Fewest points per leaf and iteration: enough for a variance.
constexpr uint64_t kMinLeafPoints = 4;
// The share of a leaf's last spread that its next one keeps at least.
constexpr double kSpreadMemory = 0.8;

// The average of the kept iterations' estimates, with equal weights.
class EqualWeights {
 public:
  void Add(double estimate, double variance) {
    estimates_.push_back(estimate);
    variances_.push_back(variance);
  }
  double Estimate() const {
    double sum = 0;
    for (double e : estimates_) sum += e;
    return sum / double(estimates_.size());
  }
  double Error() const {
    double sum = 0;
    for (double v : variances_) sum += v;
    return std::sqrt(sum) / double(estimates_.size());
  }
  // Σ_t (I_t − c)² / σ_t² about c = Σ I_t/σ_t² / Σ 1/σ_t², the centre
  // that makes it χ² of T − 1 degrees of freedom when the iterations
  // agree; about the equal-weight average it is larger, by the early
  // iterations' noise over the later ones' small σ_t (Q < 0.05 in 12 to 18
  // of 20 runs on a step whose errors were right). Iterations without
  // spread (a constant f) count as agreeing.
  double ChiSquare() const {
    double weights = 0, weighted = 0;
    for (size_t t = 0; t < estimates_.size(); ++t)
      if (variances_[t] > 0) {
        weights += 1 / variances_[t];
        weighted += estimates_[t] / variances_[t];
      }
    if (weights == 0) return 0;
    const double mean = weighted / weights;
    double chi2 = 0;
    for (size_t t = 0; t < estimates_.size(); ++t)
      if (variances_[t] > 0) chi2 += (estimates_[t] - mean) * (estimates_[t] - mean) / variances_[t];
    return chi2;
  }
  double ChiSquarePerDof() const {
    return estimates_.size() < 2 ? std::numeric_limits<double>::quiet_NaN()
                                 : ChiSquare() / double(estimates_.size() - 1);
  }
  double Q() const {
    return estimates_.size() < 2 ? std::numeric_limits<double>::quiet_NaN()
                                 : ChiSquareQ(ChiSquare(), double(estimates_.size() - 1));
  }

 private:
  std::vector<double> estimates_, variances_;
};

// A leaf of the tree, in unit-cube coordinates of the box.
struct Cell {
  std::vector<double> lower, upper;
  std::vector<uint32_t> points;  // its points of the last iteration
  double volume = 1;             // share of the box
  double spread = 0;             // s: of its points, or half its parent's if more
};

// The iteration's points: unit-cube coordinates and f's values, in order.
struct Samples {
  std::vector<float> unit, values;
};

// The standard deviation of f over some of the samples: the root of the
// sum of the outputs' sample variances; 0 below two points.
double Spread(const std::vector<uint32_t>& points, const Samples& samples, uint32_t k) {
  if (points.size() < 2) return 0;
  RunningMoments moments(k);
  for (uint32_t p : points) moments.Add(&samples.values[size_t(p) * k]);
  double variance = 0;
  for (uint32_t c = 0; c < k; ++c) variance += moments.VarianceOfMean(c) * double(points.size());
  return std::sqrt(variance);
}

// A cell's identity for its random sequence: its bounds, hashed.
uint64_t CellId(const Cell& cell) {
  uint64_t id = 0;
  for (size_t j = 0; j < cell.lower.size(); ++j)
    id = Hash(id, uint64_t(std::ldexp(cell.lower[j], 52)), uint64_t(std::ldexp(cell.upper[j], 52)));
  return id;
}

class AdaptiveHierarchicalIntegrator final : public Integrator {
 public:
  static ParameterSchema Parameters() {
    using P = Parameter;
    return {
        P::Int("iterations").Default(8).Range(2, 1000).Doc("iterations T, each refining the tree"),
        P::Int("discard").Default(1).Min(0).Doc("leading iterations left out of the average, fewer than T"),
        P::Int("cell_points").Default(16).Range(4, 4096).Doc("a leaf is cut while it holds twice this many"),
        P::Float("floor").Default(0.2).Range(0, 1).Doc("defensive share of the points given by volume"),
    };
  }

  explicit AdaptiveHierarchicalIntegrator(const Properties& props)
      : iterations_(props.Int("iterations", 8)),
        discard_(props.Int("discard", 1)),
        cell_points_(props.Int("cell_points", 16)),
        floor_(props.Float("floor", 0.2)) {
    if (iterations_ < 2 || iterations_ > 1000) throw Error("property 'iterations' must be in [2, 1000]");
    if (discard_ < 0 || discard_ >= iterations_)
      throw Error("property 'discard' must be in [0, iterations - 1]");
    if (cell_points_ < 4 || cell_points_ > 4096) throw Error("property 'cell_points' must be in [4, 4096]");
    if (!(floor_ >= 0 && floor_ <= 1)) throw Error("property 'floor' must be in [0, 1]");
  }

  IntegrationResult Integrate(Function& f, std::span<const double> lower, std::span<const double> upper,
                              uint64_t evaluations, uint64_t seed, const Sampler& sampler) override {
    const uint32_t d = f.InputDimensions(), k = f.OutputDimensions();
    CheckProperBox(lower, upper, d);
    const uint64_t iterations = uint64_t(iterations_);
    if (evaluations / iterations < 2 * kMinLeafPoints)
      throw Error("adaptive_hierarchical needs at least " + std::to_string(2 * kMinLeafPoints) +
                  " evaluations per iteration");

    std::vector<Cell> cells(1);
    cells[0].lower.assign(d, 0.0);
    cells[0].upper.assign(d, 1.0);
    const double volume = BoxVolume(lower, upper);
    std::vector<EqualWeights> combined(k);
    Samples samples;
    for (uint64_t t = 0; t < iterations; ++t) {
      const uint64_t n = PointsOfIteration(evaluations, iterations, t);
      const std::vector<uint64_t> counts = Allocate(cells, n);
      Draw(cells, counts, Hash(seed, t), f, sampler, lower, upper, samples);
      const Stratified estimate = Estimate(cells, samples, k);
      if (t >= uint64_t(discard_))
        for (uint32_t c = 0; c < k; ++c)
          combined[c].Add(volume * estimate.mean[c], volume * volume * estimate.variance[c]);
      if (t + 1 < iterations) Refine(cells, samples, PointsOfIteration(evaluations, iterations, t + 1), d, k);
    }
    IntegrationResult result;
    result.evaluations = evaluations;
    for (const EqualWeights& c : combined) {
      result.estimate.push_back(c.Estimate());
      result.standard_error.push_back(c.Error());
      result.chi2_per_dof.push_back(c.ChiSquarePerDof());
      result.q.push_back(c.Q());
    }
    return result;
  }

 private:
  // Points per leaf for an iteration of n points: the defensive Neyman
  // allocation, rounding leftovers one each to the first leaves.
  std::vector<uint64_t> Allocate(const std::vector<Cell>& cells, uint64_t n) const {
    double total = 0;
    for (const Cell& cell : cells) total += cell.volume * cell.spread;
    const uint64_t free = n - kMinLeafPoints * cells.size();
    std::vector<uint64_t> counts(cells.size());
    uint64_t given = 0;
    for (size_t c = 0; c < cells.size(); ++c) {
      const double v = cells[c].volume;
      const double share = total > 0 ? floor_ * v + (1 - floor_) * v * cells[c].spread / total : v;
      counts[c] = kMinLeafPoints + uint64_t(std::floor(share * double(free)));
      given += counts[c];
    }
    for (size_t c = 0; given < n; c = (c + 1) % cells.size(), ++given) ++counts[c];
    return counts;
  }

  // Draws each leaf's points, uniform in it, and evaluates f on them in
  // calls of up to kBatch points; leaves' `points` name them.
  static void Draw(std::vector<Cell>& cells, const std::vector<uint64_t>& counts, uint64_t seed, Function& f,
                   const Sampler& sampler, std::span<const double> lower, std::span<const double> upper,
                   Samples& out) {
    const uint32_t d = f.InputDimensions(), k = f.OutputDimensions();
    uint64_t total = 0;
    for (uint64_t n : counts) total += n;
    out.unit.resize(total * d);
    out.values.resize(total * k);
    uint64_t first = 0;
    for (size_t c = 0; c < cells.size(); ++c) {
      Cell& cell = cells[c];
      const std::span<float> unit = std::span<float>(out.unit).subspan(first * d, counts[c] * d);
      sampler.Generate(0, uint32_t(counts[c]), d, Hash(seed, CellId(cell)), unit);
      for (uint64_t i = 0; i < counts[c]; ++i)
        for (uint32_t j = 0; j < d; ++j) {
          float& u = unit[i * d + j];
          u = float(cell.lower[j] + (cell.upper[j] - cell.lower[j]) * u);
        }
      cell.points.resize(counts[c]);
      for (uint64_t i = 0; i < counts[c]; ++i) cell.points[i] = uint32_t(first + i);
      first += counts[c];
    }
    std::vector<float> box;
    for (uint64_t begin = 0; begin < total; begin += kBatch) {
      const uint64_t n = std::min(kBatch, total - begin);
      box.assign(out.unit.begin() + begin * d, out.unit.begin() + (begin + n) * d);
      MapToBox(box, lower, upper);
      f.Evaluate(box, std::span<float>(out.values).subspan(begin * k, n * k));
    }
  }

  struct Stratified {
    std::vector<double> mean, variance;  // of the unit-cube mean of f
  };

  // The iteration's stratified estimate; sets each leaf's spread.
  static Stratified Estimate(std::vector<Cell>& cells, const Samples& samples, uint32_t k) {
    Stratified out{std::vector<double>(k, 0.0), std::vector<double>(k, 0.0)};
    RunningMoments moments(k);
    for (Cell& cell : cells) {
      moments.Clear();
      for (uint32_t p : cell.points) moments.Add(&samples.values[size_t(p) * k]);
      double variance = 0;
      for (uint32_t c = 0; c < k; ++c) {
        out.mean[c] += cell.volume * moments.Mean(c);
        out.variance[c] += cell.volume * cell.volume * moments.VarianceOfMean(c);
        variance += moments.VarianceOfMean(c) * double(moments.Count());
      }
      cell.spread = std::max(std::sqrt(variance), kSpreadMemory * cell.spread);
    }
    return out;
  }

  // Cuts the leaf of largest v·s while it has ≥ 2 · cell_points points and
  // every leaf can still get its minimum from the next iteration's n.
  void Refine(std::vector<Cell>& cells, const Samples& samples, uint64_t next_n, uint32_t d, uint32_t k) const {
    const uint64_t max_leaves = next_n / (2 * kMinLeafPoints);
    const auto weight = [&](size_t c) { return cells[c].volume * cells[c].spread; };
    const auto lighter = [&](size_t a, size_t b) { return weight(a) < weight(b); };
    std::priority_queue<size_t, std::vector<size_t>, decltype(lighter)> heaviest(lighter);
    for (size_t c = 0; c < cells.size(); ++c) heaviest.push(c);
    while (!heaviest.empty() && cells.size() < max_leaves) {
      const size_t c = heaviest.top();
      heaviest.pop();
      if (!(weight(c) > 0) && cells.size() > 1) break;
      if (cells[c].points.size() < 2 * uint64_t(cell_points_)) continue;
      Split(cells, c, samples, d, k);
      heaviest.push(c);
      heaviest.push(cells.size() - 1);
    }
  }

  // Cuts cells[c] at the middle of its best axis; the upper half goes to
  // the end of `cells`.
  static void Split(std::vector<Cell>& cells, size_t c, const Samples& samples, uint32_t d, uint32_t k) {
    uint32_t best_axis = 0;
    double best_cost = std::numeric_limits<double>::infinity(), best_extent = 0;
    std::vector<uint32_t> low, high;
    {
      const Cell& cell = cells[c];
      for (uint32_t j = 0; j < d; ++j) {
        const double middle = 0.5 * (cell.lower[j] + cell.upper[j]), extent = cell.upper[j] - cell.lower[j];
        low.clear();
        high.clear();
        for (uint32_t p : cell.points) (samples.unit[size_t(p) * d + j] < middle ? low : high).push_back(p);
        const double cost = low.size() < 2 || high.size() < 2 ? std::numeric_limits<double>::max()
                                                               : Spread(low, samples, k) + Spread(high, samples, k);
        const bool better = cost < best_cost * (1 - 1e-9), equal = !better && cost <= best_cost * (1 + 1e-9);
        if (better || (equal && extent > best_extent)) {
          best_cost = std::min(cost, best_cost);
          best_axis = j;
          best_extent = extent;
        }
      }
    }
    Cell upper_half;
    {
      Cell& cell = cells[c];
      const double middle = 0.5 * (cell.lower[best_axis] + cell.upper[best_axis]);
      upper_half.lower = cell.lower;
      upper_half.upper = cell.upper;
      upper_half.lower[best_axis] = middle;
      cell.upper[best_axis] = middle;
      cell.volume *= 0.5;
      upper_half.volume = cell.volume;
      low.clear();
      for (uint32_t p : cell.points)
        (samples.unit[size_t(p) * d + best_axis] < middle ? low : upper_half.points).push_back(p);
      cell.points = low;
      const double inherited = 0.5 * cell.spread;
      cell.spread = std::max(Spread(cell.points, samples, k), inherited);
      upper_half.spread = std::max(Spread(upper_half.points, samples, k), inherited);
    }
    cells.push_back(std::move(upper_half));
  }

  int64_t iterations_, discard_, cell_points_;
  double floor_;
};

}  // namespace
}  // namespace yarf

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::AdaptiveHierarchicalIntegrator>(
      registrar, "adaptive_hierarchical", "1.0.0",
      "Kajiya's adaptive hierarchical integration: stratified sampling on a k-d tree refined where f varies");
}
