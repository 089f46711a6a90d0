// vegas — adaptive importance-sampling Monte Carlo (G. P. Lepage, "A new
// algorithm for adaptive multidimensional integration", J. Comput. Phys.
// 27 (1978) 192).
//
// Integrate: a map x(y) from the unit cube onto the box is built one axis
// at a time. Along each axis [0, 1) is cut into `bins` equal steps in y and
// step i is stretched linearly onto the interval [x_i, x_{i+1}] of that
// axis, so ∫ f dx = ∫ J(y) f(x(y)) dy with J = Π_axes bins · (x_{i+1} - x_i).
// The integral is estimated by plain Monte Carlo in y: points uniform in
// the unit cube (from the job's sampler) give J f, whose mean is the
// estimate of one iteration and whose variance over the points, divided
// by their number, is that estimate's variance σ_t².
//
// After every iteration the grid adapts to the first output of f: bin i of
// an axis collects d_i, the mean of (J f)² over the points that fell in it,
// an estimate of the average of J² f² over that slab of the cube (the
// slabs are equally wide in y, so Σ_i d_i / bins estimates ∫ J² f² dy,
// the second moment that the map should minimise). A mean, rather than a
// sum, leaves out the noise of how many points each bin happened to get,
// so that a flat integrand leaves the grid where it is. The
// d_i are smoothed with their neighbours (weights 1:6:1, 7:1 at the ends)
// so that one lucky sample does not pull the whole grid, normalised to
// r_i = d_i / Σ d, and damped to w_i = ((1 - r_i) / ln(1/r_i))^α, which
// keeps the ordering of the r_i but compresses their range so that the
// grid moves gradually. New edges are placed so that every bin holds an
// equal share of Σ w, the weight being spread evenly inside an old bin.
// Bins shrink where |f| is large: the sampling density in x follows |f|
// as closely as a product of one-axis densities can.
//
// Iterations are combined weighted by their inverse variances, every
// output of f separately: estimate = Σ_t I_t/σ_t² / Σ_t 1/σ_t², standard
// error = 1 / √(Σ_t 1/σ_t²). The first `discard` iterations only train the
// grid: their points are spent (and counted in `evaluations`) but their
// estimates are left out, because a grid that has not found the integrand's
// peaks yet tends to under-estimate both the integral and its variance,
// and an iteration with a small σ_t has a large weight (with none left
// out, on a peak of width 0.02 in four dimensions 30% of runs end more
// than 2σ from the exact value, against 4% with one or two left out; two
// leave a margin for harder integrands). The consistency of the kept iterations,
// χ²/dof = Σ_t (I_t - I)²/σ_t² / (T - 1), is available to in-process
// diagnostics; IntegrationResult has no field for it yet.
//
// Each iteration spends evaluations / iterations points (the remainder
// goes to the first iterations, so the total is exactly the budget). An
// iteration is one or more calls to f.Evaluate of up to 16384 points;
// when the budget would leave fewer than 1000 points per iteration, fewer
// iterations are run (at least one), so that every call still carries
// 1000 points and every iteration's variance is well estimated; `discard`
// is then lowered to keep at least one iteration. Iteration t uses the
// sampler's points after those of the earlier iterations, so a result is
// a pure function of the seed.
//
// Properties:
//   int   "bins"       grid bins per axis, >= 2 (default 50)
//   int   "iterations" adaptation iterations, >= 1 (default 10)
//   float "alpha"      damping exponent of the refinement, >= 0; 0 freezes
//                      the grid (uniform plain Monte Carlo) (default 1.5)
//   int   "discard"    leading iterations left out of the result, in
//                      [0, iterations - 1] (default 2, or iterations - 1
//                      when that is smaller)

#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

#include "vegas_image.h"
#include "vegas_map.h"
#include "yarf/plugin.h"

namespace yarf {
namespace {

// The damping exponent when "alpha" is not given.
constexpr double kDefaultAlpha = 1.5;

class VegasIntegrator final : public Integrator {
 public:
  explicit VegasIntegrator(const Properties& props) : settings_(props, kDefaultAlpha) {
    settings_.CheckDiscard();
  }

  IntegrationResult Integrate(Function& f, std::span<const double> lower,
                              std::span<const double> upper, uint64_t evaluations, uint64_t seed,
                              const Sampler& sampler) override {
    const uint32_t d = f.InputDimensions(), k = f.OutputDimensions();
    CheckVegasJob("vegas", d, k, lower, upper, evaluations);

    const uint64_t iterations = settings_.IterationsFor(evaluations);
    const uint64_t discard = settings_.DiscardOf(iterations);
    AdaptiveMap map(lower, upper, uint32_t(settings_.bins));
    std::vector<Combination> combined(k);
    VegasBatch batch(d, k);
    std::vector<double> y(d);
    std::vector<Moments> moments(k);
    uint64_t first = 0;  // sampler index of the iteration's first point
    for (uint64_t t = 0; t < iterations; ++t) {
      const uint64_t n = PointsOfIteration(evaluations, iterations, t);
      std::fill(moments.begin(), moments.end(), Moments{});
      ForEachBatch(n, [&](uint64_t begin, uint32_t count) {
        batch.Draw(sampler, first + begin, count, seed);
        for (uint32_t i = 0; i < count; ++i) {
          for (uint32_t j = 0; j < d; ++j) y[j] = batch.u[size_t(i) * d + j];
          batch.Place(map, i, y.data());
        }
        f.Evaluate(batch.points, batch.values);
        for (uint32_t i = 0; i < count; ++i) batch.Accumulate(i, moments, map, 1);
      });
      first += n;
      if (t >= discard)
        for (uint32_t c = 0; c < k; ++c) {
          const double variance = n > 1 ? moments[c].SquaredDeviations() / double(n - 1) / double(n) : 0;
          combined[c].Add(moments[c].Mean(), variance);
        }
      if (t + 1 < iterations && settings_.alpha > 0) map.Refine(settings_.alpha);
    }
    return CombinedResult(combined, evaluations);
  }

  void Render(Transport& transport, const SceneView& scene, const Sampler& sampler,
              RenderTarget& target) override {
    RenderWithVegasMap(transport, scene, sampler, target, uint32_t(settings_.bins), settings_.alpha);
  }

 private:
  VegasSettings settings_;
};

}  // namespace
}  // namespace yarf

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::VegasIntegrator>(registrar, "vegas", "1.0.0",
                                        "VEGAS adaptive importance-sampling Monte Carlo (Lepage 1978)");
}
