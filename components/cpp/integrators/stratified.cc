// stratified_mc — stratified Monte Carlo with equal strata.
//
// Integrate: the box is cut into a grid of m^d equal cells and p points are
// drawn uniformly in each. m is the largest number of cells per axis with
// m^d · points_per_cell ≤ evaluations, and p = ⌊evaluations / m^d⌋ (so
// p ≥ points_per_cell); `evaluations` in the result is m^d · p.
// With V the box's volume and M = m^d cells,
//   estimate = (V / M) Σ_c mean_c,   σ² = (V / M)² Σ_c s_c² / p,
// where mean_c and s_c² are the sample mean and (unbiased) sample variance
// of f in cell c: the variance of the estimate counts only the variation of
// f within cells, which is what stratification removes from plain Monte
// Carlo's. Point i of the sampler's sequence (for the job's seed) is the
// (i mod p)-th point of cell ⌊i / p⌋, placed by its first d coordinates.
//
// Parameters: StratifiedIntegrator::Parameters() below; a cell's variance
// needs two points.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "integration_box.h"
#include "yarf/plugin.h"

namespace yarf {
namespace {

// Points per Evaluate call: large, since f may live in another process.
constexpr uint64_t kBatch = 8192;

class StratifiedIntegrator final : public Integrator {
 public:
  static ParameterSchema Parameters() {
    using P = Parameter;
    return {
        P::Int("points_per_cell").Default(2).Range(2, double(int64_t(1) << 32)).Doc("fewest points per cell"),
    };
  }

  explicit StratifiedIntegrator(const Properties& props)
      : points_per_cell_(props.Int("points_per_cell", 2)) {
    if (points_per_cell_ < 2 || points_per_cell_ > (int64_t(1) << 32))
      throw Error("property 'points_per_cell' must be in [2, 2^32]");
  }

  IntegrationResult Integrate(Function& f, std::span<const double> lower,
                              std::span<const double> upper, uint64_t evaluations, uint64_t seed,
                              const Sampler& sampler) override {
    const uint32_t d = f.InputDimensions(), k = f.OutputDimensions();
    CheckProperBox(lower, upper, d);
    const uint64_t min_points = uint64_t(points_per_cell_);
    if (evaluations < min_points)
      throw Error("stratified_mc needs at least points_per_cell = " + std::to_string(min_points) +
                  " evaluations");

    // The largest m with m^d cells of min_points each within the budget.
    const uint64_t max_cells = evaluations / min_points;
    const uint64_t m = CellsPerAxis(max_cells, d);
    const uint64_t cells = PowerCapped(m, d, max_cells);
    const uint64_t p = evaluations / cells;
    const uint64_t total = cells * p;

    const double volume = BoxVolume(lower, upper);

    // Running statistics of the current cell, folded into the totals when full.
    RunningMoments cell_moments(k);
    std::vector<double> sum_of_means(k, 0.0), sum_of_variances(k, 0.0);

    std::vector<float> points, values;
    for (uint64_t first = 0; first < total; first += kBatch) {
      const uint32_t count = uint32_t(std::min(kBatch, total - first));
      points.resize(size_t(count) * d);
      values.resize(size_t(count) * k);
      sampler.Generate(first, count, d, seed, points);
      for (uint32_t i = 0; i < count; ++i) {
        uint64_t cell = (first + i) / p;
        for (uint32_t j = 0; j < d; ++j) {
          const uint64_t a = cell % m;
          cell /= m;
          float& x = points[size_t(i) * d + j];
          x = float(lower[j] + (upper[j] - lower[j]) * ((double(a) + x) / double(m)));
        }
      }
      f.Evaluate(points, values);
      for (uint32_t i = 0; i < count; ++i) {
        cell_moments.Add(&values[size_t(i) * k]);
        if (cell_moments.Count() == p) {
          for (uint32_t c = 0; c < k; ++c) {
            sum_of_means[c] += cell_moments.Mean(c);
            sum_of_variances[c] += cell_moments.VarianceOfMean(c);
          }
          cell_moments.Clear();
        }
      }
    }

    IntegrationResult result;
    result.evaluations = total;
    const double cell_volume = volume / double(cells);
    for (uint32_t c = 0; c < k; ++c) {
      result.estimate.push_back(cell_volume * sum_of_means[c]);
      result.standard_error.push_back(cell_volume * std::sqrt(sum_of_variances[c]));
    }
    return result;
  }

 private:
  int64_t points_per_cell_;
};

}  // namespace
}  // namespace yarf

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::StratifiedIntegrator>(registrar, "stratified_mc", "1.0.0",
                                             "stratified Monte Carlo on a grid of equal cells");
}
