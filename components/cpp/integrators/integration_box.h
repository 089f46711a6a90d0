// What the integrators share about the box they cover: the checks of its
// shape, its volume, the map of unit-cube points onto it, the size of a
// grid of equal cells over it, and running statistics of f.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "yarf/error.h"

namespace yarf {

// Throws unless the box has one bound per input of the function.
inline void CheckBoxDimensions(std::span<const double> lower, std::span<const double> upper,
                               uint32_t dimensions) {
  if (lower.size() != dimensions || upper.size() != dimensions)
    throw Error("integration box has " + std::to_string(lower.size()) + " dimensions, the function " +
                std::to_string(dimensions));
}

// Throws unless every bound is finite (lower > upper is allowed: the
// signed integral, for the rules that give it).
inline void CheckFiniteBounds(std::span<const double> lower, std::span<const double> upper) {
  for (size_t j = 0; j < lower.size(); ++j)
    if (!std::isfinite(lower[j]) || !std::isfinite(upper[j])) throw Error("integration box bounds must be finite");
}

// The checks of a rule that needs a proper box: the dimension, at least
// one input, and finite bounds with lower ≤ upper.
inline void CheckProperBox(std::span<const double> lower, std::span<const double> upper,
                           uint32_t dimensions) {
  CheckBoxDimensions(lower, upper, dimensions);
  if (dimensions == 0) throw Error("the function has no input dimensions");
  for (uint32_t j = 0; j < dimensions; ++j)
    if (!std::isfinite(lower[j]) || !std::isfinite(upper[j]) || !(lower[j] <= upper[j]))
      throw Error("integration box must be finite with lower ≤ upper in every dimension");
}

inline double BoxVolume(std::span<const double> lower, std::span<const double> upper) {
  double volume = 1;
  for (size_t j = 0; j < lower.size(); ++j) volume *= upper[j] - lower[j];
  return volume;
}

// Maps points of the unit cube, rows of lower.size() coordinates, onto the
// box in place.
inline void MapToBox(std::span<float> points, std::span<const double> lower,
                     std::span<const double> upper) {
  const size_t d = lower.size();
  for (size_t row = 0; row < points.size(); row += d)
    for (size_t j = 0; j < d; ++j) {
      float& x = points[row + j];
      x = float(lower[j] + (upper[j] - lower[j]) * x);
    }
}

// base^exponent, or limit + 1 when that exceeds limit (base ≥ 1): grid
// sizes that would overflow are only compared with a limit.
inline uint64_t PowerCapped(uint64_t base, uint32_t exponent, uint64_t limit) {
  uint64_t p = 1;
  for (uint32_t i = 0; i < exponent; ++i) {
    if (p > limit / base) return limit + 1;
    p *= base;
  }
  return p;
}

// The most cells per axis of a grid of at most `limit` cells in d
// dimensions: the largest m ≥ 1 with m^d ≤ limit (limit ≥ 1).
inline uint64_t CellsPerAxis(uint64_t limit, uint32_t d) {
  // Start from the floating-point root and correct it in integers.
  uint64_t m = std::max<uint64_t>(1, uint64_t(std::pow(double(limit), 1.0 / d)));
  while (m > 1 && PowerCapped(m, d, limit) > limit) --m;
  while (PowerCapped(m + 1, d, limit) <= limit) ++m;
  return m;
}

// Mean and sum of squared deviations of every output of f over a stream
// of points, by Welford's update: stable when the mean is large beside the
// spread.
class RunningMoments {
 public:
  explicit RunningMoments(uint32_t outputs) : mean_(outputs, 0.0), m2_(outputs, 0.0) {}

  void Clear() {
    count_ = 0;
    std::fill(mean_.begin(), mean_.end(), 0.0);
    std::fill(m2_.begin(), m2_.end(), 0.0);
  }
  // Adds the outputs of one point.
  void Add(const float* values) {
    ++count_;
    for (size_t c = 0; c < mean_.size(); ++c) {
      const double v = values[c], delta = v - mean_[c];
      mean_[c] += delta / double(count_);
      m2_[c] += delta * (v - mean_[c]);
    }
  }
  uint64_t Count() const { return count_; }
  double Mean(size_t c) const { return mean_[c]; }
  // The variance of the mean, s² / n; 0 below two points.
  double VarianceOfMean(size_t c) const {
    const double n = double(count_);
    return n > 1 ? m2_[c] / (n - 1) / n : 0.0;
  }

 private:
  uint64_t count_ = 0;
  std::vector<double> mean_, m2_;
};

}  // namespace yarf
