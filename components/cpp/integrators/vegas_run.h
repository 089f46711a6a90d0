// The iterations vegas and vegas_plus share: Lepage's stratification of
// y-space into hypercubes, the allocation of each iteration's points among
// them (the same number each for β = 0, his classic algorithm; by the
// hypercubes' spread for β > 0, VEGAS+), the estimate of an iteration and
// the refinement of the map after it. vegas.cc and vegas_plus.cc say what
// they compute and where yarf differs from Lepage.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <span>
#include <string>
#include <vector>

#include "integration_box.h"
#include "vegas_map.h"
#include "yarf/math.h"

namespace yarf {

// Bounds the memory of the per-hypercube spreads.
constexpr uint64_t kMaxHypercubes = uint64_t(1) << 20;
// Lepage's neval_frac: with β > 0, the share of an iteration's points
// allocated by the hypercubes' spreads; the rest is spread evenly.
constexpr double kAllocatedFraction = 0.75;

// Strata per axis for n points per iteration in d dimensions, as Lepage
// chooses them: as many equal hypercubes as leave 2 points each from the
// evenly spread points (all of them for β = 0, a quarter for β > 0), M per
// axis and M + 1 on the leading axes while the count stays within that.
inline std::vector<uint32_t> ChooseStrata(uint64_t n, uint32_t d, double beta) {
  const double even = beta > 0 ? 1 - kAllocatedFraction : 1;
  const uint64_t limit = std::clamp<uint64_t>(uint64_t(even * double(n) / 2), 1, kMaxHypercubes);
  const uint64_t m = CellsPerAxis(limit, d);
  std::vector<uint32_t> strata(d, uint32_t(m));
  uint64_t total = PowerCapped(m, d, limit);
  for (uint32_t j = 0; j < d && total / m * (m + 1) <= limit; ++j) {
    strata[j] = uint32_t(m + 1);
    total = total / m * (m + 1);
  }
  return strata;
}

// Shares n points among the hypercubes as Lepage does: for β > 0 each gets
// max(2, ⌊(1 - 0.75) n / H⌋) plus ⌊0.75 n · weight_h / Σ weight⌋; for β = 0
// (or weights all 0) each gets ⌊n / H⌋. Lepage leaves the points the
// rounding drops unspent; yarf spreads them one by one evenly over the
// hypercubes, so that an iteration spends exactly its n points.
inline void Allocate(const std::vector<double>& weight, double beta, uint64_t n, std::vector<uint64_t>& out) {
  const uint64_t count = weight.size();
  out.assign(count, 0);
  double total = 0;
  for (double w : weight) total += w;
  const bool adaptive = beta > 0 && count > 1 && total > 0 && std::isfinite(total);
  const uint64_t even = adaptive ? std::max<uint64_t>(2, uint64_t((1 - kAllocatedFraction) * double(n) / double(count)))
                                 : n / count;
  // Slightly under 0.75 n / Σ weight, so that rounding cannot overspend.
  const double scale = adaptive ? kAllocatedFraction * double(n) / total * (1 - 1e-12) : 0;
  uint64_t assigned = 0;
  for (uint64_t h = 0; h < count; ++h) {
    out[h] = even + uint64_t(weight[h] * scale);
    assigned += out[h];
  }
  const uint64_t left = n - assigned;
  for (uint64_t h = 0; h < count; ++h) out[h] += (h + 1) * left / count - h * left / count;
}

// ∫ f over [lower, upper]: settings.iterations iterations of stratified
// sampling in y through a map refined after each, the points of hypercube
// h in the next iteration chosen by allocation weights σ_h^β (β = 0: the
// same number everywhere). `name` names the integrator in messages.
inline IntegrationResult IntegrateVegas(const std::string& name, const VegasSettings& settings, double beta,
                                        Function& f, std::span<const double> lower, std::span<const double> upper,
                                        uint64_t evaluations, uint64_t seed, const Sampler& sampler) {
  const uint32_t d = f.InputDimensions(), k = f.OutputDimensions();
  CheckVegasJob(name, d, k, lower, upper, evaluations);

  const uint64_t iterations = settings.IterationsFor(evaluations);
  const uint64_t discard = settings.DiscardOf(iterations);
  const uint64_t per_iteration = evaluations / iterations;
  const std::vector<uint32_t> strata = ChooseStrata(per_iteration, d, beta);
  const size_t hypercubes = std::accumulate(strata.begin(), strata.end(), size_t(1), std::multiplies<size_t>());
  const double volume = 1.0 / double(hypercubes);  // of one hypercube, in y
  std::vector<double> stratum_width(d);
  for (uint32_t j = 0; j < d; ++j) stratum_width[j] = 1.0 / strata[j];

  AdaptiveMap map(lower, upper, settings.BinsFor(per_iteration, *std::max_element(strata.begin(), strata.end())));
  std::vector<Combination> combined(k);
  // Allocation weights; all equal before the first iteration has measured.
  std::vector<double> weight(hypercubes, 1.0);
  std::vector<uint64_t> share;
  VegasBatch batch(d, k);
  std::vector<double> y(d);
  std::vector<uint64_t> cube_of;
  std::vector<uint32_t> corner(d);
  std::vector<Moments> moments(k);
  std::vector<double> estimate(k), variance(k);
  std::vector<double> previous(k);  // the variances of the iteration before
  uint64_t first = 0;  // sampler index of the iteration's first point
  for (uint64_t t = 0; t < iterations; ++t) {
    const uint64_t n = PointsOfIteration(evaluations, iterations, t);
    Allocate(weight, beta, n, share);

    // Adds hypercube h's points to the iteration's estimate and variance
    // (V_h mean_h(J f) and V_h² s_h² / n_h) and sets its allocation weight
    // to Lepage's (V_h² s_h² / n_h)^(β/2), of the first output; V_h is the
    // same for every h, so it is left out.
    std::fill(estimate.begin(), estimate.end(), 0.0);
    std::fill(variance.begin(), variance.end(), 0.0);
    const auto close = [&](size_t h) {
      const double m = double(moments[0].count);
      for (uint32_t c = 0; c < k; ++c) {
        estimate[c] += volume * moments[c].Mean();
        variance[c] += volume * volume * moments[c].SquaredDeviations() / (m - 1) / m;
      }
      if (beta > 0) weight[h] = std::pow(moments[0].SquaredDeviations() / (m - 1) / m, beta / 2);
      std::fill(moments.begin(), moments.end(), Moments{});
    };

    // Points go out hypercube after hypercube, each hypercube's points
    // contiguous; `next`/`used` walk the allocation while generating,
    // `open` is the hypercube whose points are being accumulated.
    size_t next = 0, open = 0;
    uint64_t used = 0;
    double point_weight = volume / double(share[0]);  // inverse density of a point of `open`
    std::fill(corner.begin(), corner.end(), 0u);
    ForEachBatch(n, [&](uint64_t begin, uint32_t count) {
      batch.Draw(sampler, first + begin, count, seed);
      cube_of.resize(count);
      for (uint32_t i = 0; i < count; ++i) {
        while (used == share[next]) {
          ++next;
          used = 0;
          // Mixed-radix increment: the corner of the next hypercube.
          for (uint32_t j = 0; j < d && ++corner[j] == strata[j]; ++j) corner[j] = 0;
        }
        ++used;
        cube_of[i] = next;
        for (uint32_t j = 0; j < d; ++j)
          y[j] = (corner[j] + double(batch.u[size_t(i) * d + j])) * stratum_width[j];
        batch.Place(map, i, y.data());
      }
      f.Evaluate(batch.points, batch.values);
      for (uint32_t i = 0; i < count; ++i) {
        if (cube_of[i] != open) {
          close(open);
          open = cube_of[i];
          point_weight = volume / double(share[open]);
        }
        batch.Accumulate(i, moments, map, point_weight);
      }
    });
    close(open);
    first += n;
    if (beta > 0) {
      // A constant integrand: no spread anywhere, points spread evenly.
      double total = 0;
      for (double w : weight) total += w;
      if (!(total > 0) || !std::isfinite(total)) std::fill(weight.begin(), weight.end(), 1.0);
    }
    if (t >= discard)
      for (uint32_t c = 0; c < k; ++c) combined[c].Add(estimate[c], variance[c], t == 0 ? variance[c] : previous[c]);
    previous = variance;
    if (t + 1 < iterations && settings.alpha > 0) map.Refine(settings.alpha);
  }
  return CombinedResult(combined, first);
}

}  // namespace yarf
