// vegas_plus — VEGAS with adaptive stratified sampling (G. P. Lepage,
// "Adaptive multidimensional integration: VEGAS enhanced", J. Comput.
// Phys. 439 (2021) 110386).
//
// Integrate: the VEGAS map of the `vegas` integrator (a separable,
// piecewise-linear x(y) from the unit cube onto the box, `bins` bins per
// axis, refined after every iteration with the damping exponent α from
// the smoothed bin averages d_i of J² f² of the first output; see
// vegas.cc), and on top of it a stratification of y-space: the unit cube
// is cut into a grid of equal hypercubes, and each iteration samples every
// hypercube h with n_h >= 2 points uniform inside it. The estimate of an
// iteration is Σ_h V_h · mean_h(J f) and its variance Σ_h V_h² s_h² / n_h,
// with V_h the hypercube's volume in y and s_h² the sample variance of J f
// among its points; every output of f is estimated this way.
//
// The map alone can only follow a product of one-axis densities, so an
// integrand with several peaks off the diagonal of that product (two peaks
// on the diagonal of the cube give 2^d crossings of the map's dense
// regions, of which only two hold a peak) wastes points on empty regions.
// The stratification corrects this: the points of the next iteration are
// shared among the hypercubes in proportion to σ_h^β, where σ_h is the
// standard deviation of J f measured in h by the last iteration,
//   n_h = max(2, c · σ_h^β),  c such that Σ_h n_h = points of the iteration
// (rounded so that the sum is exact). β = 1 is the allocation that
// minimises the variance when the σ_h are known; β < 1 hedges against
// σ_h estimated from few points; β = 0 is plain uniform stratification.
// The first iteration samples the hypercubes uniformly. Because points are
// no longer uniform in y, each point enters the map's bin averages of
// (J f)² with the weight V_h / n_h, the inverse of its sampling density,
// so that they still estimate the averages of J² f² over the slabs of the
// cube whatever the allocation.
//
// Strata: with n points per iteration the number of strata per axis is
// M = ⌊(n/4)^(1/d)⌋, so that hypercubes receive 4 points on average
// (at least 2, the rest left for the allocation to move); then, while the
// total stays within n/4, the leading axes get M + 1 strata, which matters
// in high dimension where M is 1 (the unstratified limit is plain VEGAS).
// The number of hypercubes is capped at 2^20 to bound memory.
//
// Iterations, their weighting by inverse variance, the discarded warm-up
// iterations, the per-iteration budget (evaluations / iterations, fewer
// iterations when that leaves under 1000 points each) and the batches of
// up to 16384 points per call to f.Evaluate are as in `vegas`.
//
// Properties:
//   int   "bins"       map bins per axis, >= 2 (default 50)
//   int   "iterations" adaptation iterations, >= 1 (default 10)
//   float "alpha"      damping exponent of the map refinement, >= 0; 0
//                      freezes the map (default 0.5: the stratification
//                      makes up for what the map has not learnt yet, so the
//                      map can move more cautiously than in plain VEGAS,
//                      as in Lepage 2021)
//   float "beta"       exponent of the sample allocation, in [0, 1]
//                      (default 0.75)
//   int   "discard"    leading iterations left out of the result, in
//                      [0, iterations - 1] (default 2, or iterations - 1
//                      when that is smaller)

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <span>
#include <vector>

#include "integration_box.h"
#include "vegas_image.h"
#include "vegas_map.h"
#include "yarf/plugin.h"

namespace yarf {
namespace {

constexpr uint64_t kMaxHypercubes = uint64_t(1) << 20;
// The damping exponent of the map when "alpha" is not given.
constexpr double kDefaultAlpha = 0.5;

// Strata per axis for n points per iteration in d dimensions.
std::vector<uint32_t> ChooseStrata(uint64_t n, uint32_t d) {
  const uint64_t limit = std::clamp<uint64_t>(n / 4, 1, kMaxHypercubes);
  const uint64_t m = CellsPerAxis(limit, d);
  std::vector<uint32_t> strata(d, uint32_t(m));
  uint64_t total = PowerCapped(m, d, limit);
  for (uint32_t j = 0; j < d && total / m * (m + 1) <= limit; ++j) {
    strata[j] = uint32_t(m + 1);
    total = total / m * (m + 1);
  }
  return strata;
}

// Shares n points among the hypercubes: n_h = max(2, c · weight_h) with c
// fixed by Σ n_h = n (needs n >= 2 · hypercubes), rounded along the
// running sum so that the total is exact and no share drops below 2.
void Allocate(const std::vector<double>& weight, uint64_t n, std::vector<uint32_t>& out) {
  const size_t count = weight.size();
  out.resize(count);
  std::vector<double> target(count, double(n) / double(count));
  double total = 0;
  for (double w : weight) total += w;
  if (total > 0 && std::isfinite(total)) {
    // g(c) = Σ max(2, c w_h) - n is convex, piecewise linear and increasing;
    // Newton's method from c = n / Σ w (where g >= 0) steps down to its
    // root, each step clamping the hypercubes that fell below 2.
    double c = double(n) / total;
    for (int step = 0; step < 100; ++step) {
      double free_weight = 0;
      uint64_t clamped = 0;
      for (double w : weight) {
        if (c * w < 2) ++clamped;
        else free_weight += w;
      }
      if (!(free_weight > 0)) break;
      const double next = (double(n) - 2.0 * double(clamped)) / free_weight;
      if (!(next < c)) break;
      c = next;
    }
    // Rescale the shares above 2 so the targets add up to n exactly even
    // if the iteration stopped early.
    double above = 0;
    for (size_t h = 0; h < count; ++h) {
      target[h] = std::max(2.0, c * weight[h]);
      above += target[h] - 2;
    }
    const double spare = double(n) - 2.0 * double(count);
    for (double& t : target) t = above > 0 ? 2 + (t - 2) * (spare / above) : double(n) / double(count);
  }
  double running = 0;
  uint64_t assigned = 0;
  for (size_t h = 0; h < count; ++h) {
    running += target[h];
    const uint64_t upto = h + 1 == count ? n : std::min<uint64_t>(n, uint64_t(std::llround(running)));
    out[h] = uint32_t(std::max<uint64_t>(2, upto > assigned ? upto - assigned : 0));
    assigned += out[h];
  }
}

class VegasPlusIntegrator final : public Integrator {
 public:
  explicit VegasPlusIntegrator(const Properties& props)
      : settings_(props, kDefaultAlpha), beta_(props.Float("beta", 0.75)) {
    if (!(beta_ >= 0 && beta_ <= 1)) throw Error("property 'beta' must be in [0, 1]");
    settings_.CheckDiscard();
  }

  IntegrationResult Integrate(Function& f, std::span<const double> lower,
                              std::span<const double> upper, uint64_t evaluations, uint64_t seed,
                              const Sampler& sampler) override {
    const uint32_t d = f.InputDimensions(), k = f.OutputDimensions();
    CheckVegasJob("vegas_plus", d, k, lower, upper, evaluations);

    const uint64_t iterations = settings_.IterationsFor(evaluations);
    const uint64_t discard = settings_.DiscardOf(iterations);
    const std::vector<uint32_t> strata = ChooseStrata(evaluations / iterations, d);
    const size_t hypercubes =
        std::accumulate(strata.begin(), strata.end(), size_t(1), std::multiplies<size_t>());
    const double volume = 1.0 / double(hypercubes);  // of one hypercube, in y
    std::vector<double> stratum_width(d);
    for (uint32_t j = 0; j < d; ++j) stratum_width[j] = 1.0 / strata[j];

    AdaptiveMap map(lower, upper, uint32_t(settings_.bins));
    std::vector<Combination> combined(k);
    std::vector<double> sigma(hypercubes, 1.0), weight(hypercubes);
    std::vector<uint32_t> share;
    VegasBatch batch(d, k);
    std::vector<double> y(d);
    std::vector<uint32_t> cube_of, corner(d);
    std::vector<Moments> moments(k);
    std::vector<double> estimate(k), variance(k);
    uint64_t first = 0;  // sampler index of the iteration's first point
    for (uint64_t t = 0; t < iterations; ++t) {
      const uint64_t n = PointsOfIteration(evaluations, iterations, t);
      for (size_t h = 0; h < hypercubes; ++h) weight[h] = std::pow(sigma[h], beta_);
      Allocate(weight, n, share);
      const uint64_t spent = std::accumulate(share.begin(), share.end(), uint64_t(0));

      // Adds hypercube h's points to the iteration and notes its σ_h.
      std::fill(estimate.begin(), estimate.end(), 0.0);
      std::fill(variance.begin(), variance.end(), 0.0);
      const auto close = [&](size_t h) {
        const double m = double(moments[0].count);
        for (uint32_t c = 0; c < k; ++c) {
          estimate[c] += volume * moments[c].Mean();
          variance[c] += volume * volume * moments[c].SquaredDeviations() / (m - 1) / m;
        }
        sigma[h] = std::sqrt(moments[0].SquaredDeviations() / (m - 1));
        std::fill(moments.begin(), moments.end(), Moments{});
      };

      // Points go out hypercube after hypercube, each hypercube's points
      // contiguous; `next`/`used` walk the allocation while generating,
      // `open` is the hypercube whose points are being accumulated.
      size_t next = 0, open = 0;
      uint32_t used = 0;
      double share_weight = volume / share[0];  // of one point of `open`
      std::fill(corner.begin(), corner.end(), 0u);
      ForEachBatch(spent, [&](uint64_t begin, uint32_t count) {
        batch.Draw(sampler, first + begin, count, seed);
        cube_of.resize(count);
        for (uint32_t i = 0; i < count; ++i) {
          if (used == share[next]) {
            ++next;
            used = 0;
            // Mixed-radix increment: the corner of the next hypercube.
            for (uint32_t j = 0; j < d && ++corner[j] == strata[j]; ++j) corner[j] = 0;
          }
          ++used;
          cube_of[i] = uint32_t(next);
          for (uint32_t j = 0; j < d; ++j)
            y[j] = (corner[j] + double(batch.u[size_t(i) * d + j])) * stratum_width[j];
          batch.Place(map, i, y.data());
        }
        f.Evaluate(batch.points, batch.values);
        for (uint32_t i = 0; i < count; ++i) {
          if (cube_of[i] != open) {
            close(open);
            open = cube_of[i];
            share_weight = volume / share[open];
          }
          batch.Accumulate(i, moments, map, share_weight);
        }
      });
      close(open);
      first += spent;
      if (t >= discard)
        for (uint32_t c = 0; c < k; ++c) combined[c].Add(estimate[c], variance[c]);
      if (t + 1 < iterations && settings_.alpha > 0) map.Refine(settings_.alpha);
    }
    return CombinedResult(combined, first);
  }

  void Render(Transport& transport, const SceneView& scene, const Sampler& sampler,
              RenderTarget& target) override {
    RenderWithVegasMap(transport, scene, sampler, target, uint32_t(settings_.bins), settings_.alpha);
  }

 private:
  VegasSettings settings_;
  double beta_;
};

}  // namespace
}  // namespace yarf

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::VegasPlusIntegrator>(
      registrar, "vegas_plus", "1.0.0",
      "VEGAS+ adaptive importance and stratified sampling Monte Carlo (Lepage 2021)");
}
