// Pearson's χ² goodness-of-fit test for the tests that check samplers
// against their pdfs (warps, surface models): callers bin the samples and
// integrate the pdf over the same cells, this decides whether they agree.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>
#include <vector>

namespace yarf::testing_support {

// P(X ≥ statistic) for X ~ χ²(dof), by Wilson & Hilferty's cube-root
// normal approximation: (X/k)^(1/3) is close to normal with mean
// 1 - 2/(9k) and variance 2/(9k). Accurate to ~1e-3 in p for the hundreds
// of degrees of freedom these tests have.
inline double ChiSquareSurvival(double statistic, double dof) {
  const double variance = 2.0 / (9.0 * dof);
  const double z = (std::cbrt(statistic / dof) - (1.0 - variance)) / std::sqrt(variance);
  return 0.5 * std::erfc(z / std::sqrt(2.0));
}

// Pearson's χ² test of observed cell counts against expected ones (same
// length). Cells expecting fewer than 5 samples are pooled, as the
// statistic is χ²-distributed only for moderately large expected counts;
// a sample in a cell where the pdf is 0 fails at once. Fails when
// p < significance or nothing is left to test.
inline ::testing::AssertionResult PearsonChiSquareTest(const std::vector<double>& observed,
                                                       const std::vector<double>& expected,
                                                       double significance) {
  constexpr double kMinExpected = 5;
  std::vector<int> order(observed.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int x, int y) { return expected[x] < expected[y]; });
  double statistic = 0, pooled_observed = 0, pooled_expected = 0;
  int dof = -1;  // the counts' total is fixed
  for (int cell : order) {
    if (expected[cell] <= 0) {
      if (observed[cell] > 0)
        return ::testing::AssertionFailure()
               << observed[cell] << " samples in cell " << cell << " where the pdf is 0";
      continue;
    }
    if (expected[cell] < kMinExpected || (pooled_expected > 0 && pooled_expected < kMinExpected)) {
      pooled_observed += observed[cell];
      pooled_expected += expected[cell];
      continue;
    }
    const double diff = observed[cell] - expected[cell];
    statistic += diff * diff / expected[cell];
    ++dof;
  }
  if (pooled_expected > 0) {
    const double diff = pooled_observed - pooled_expected;
    statistic += diff * diff / pooled_expected;
    ++dof;
  }
  const double p = ChiSquareSurvival(statistic, dof);
  std::ostringstream summary;
  summary << "χ² = " << statistic << ", dof = " << dof << ", p = " << p;
  if (dof < 1 || p < significance) return ::testing::AssertionFailure() << summary.str();
  return ::testing::AssertionSuccess() << summary.str();
}

}  // namespace yarf::testing_support
