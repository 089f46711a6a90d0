// A piecewise-constant density over [0, 1]², one cell per weight on a
// width × height grid (rows from v = 0): rows are chosen by their sums,
// then a cell within the row, then a point uniform in the cell. Sampling
// inverts the two cumulative sums, so stratified numbers stay stratified.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "yarf/error.h"

namespace yarf {

class PiecewiseConstant2D {
 public:
  PiecewiseConstant2D() = default;

  // Weights ≥ 0, row by row. All zero: uniform.
  PiecewiseConstant2D(std::vector<float> weights, int width, int height) : width_(width), height_(height) {
    if (width < 1 || height < 1 || weights.size() != size_t(width) * size_t(height))
      throw Error("a piecewise-constant distribution needs width x height weights");
    double total = 0;
    for (float& w : weights) total += w = w > 0 ? w : 0.0f;
    if (!(total > 0)) std::fill(weights.begin(), weights.end(), 1.0f);
    row_cdf_.assign(size_t(height) + 1, 0.0);
    cell_cdf_.assign(size_t(height) * (size_t(width) + 1), 0.0);
    for (int y = 0; y < height; ++y) {
      double* cdf = &cell_cdf_[size_t(y) * (size_t(width) + 1)];
      for (int x = 0; x < width; ++x) cdf[x + 1] = cdf[x] + weights[size_t(y) * size_t(width) + size_t(x)];
      row_cdf_[size_t(y) + 1] = row_cdf_[size_t(y)] + cdf[width];
    }
    total_ = row_cdf_.back();
    density_.resize(weights.size());
    // A cell's density over the square: its share of the weight over its area.
    for (size_t i = 0; i < weights.size(); ++i) density_[i] = float(weights[i] / total_ * double(width) * height);
  }

  // A point of [0, 1)² and its density.
  std::array<float, 2> Sample(float u0, float u1, float& pdf) const {
    const auto [y, fy] = Invert(std::span<const double>(row_cdf_), u0);
    const auto [x, fx] = Invert(std::span<const double>(&cell_cdf_[size_t(y) * (size_t(width_) + 1)], size_t(width_) + 1), u1);
    pdf = density_[size_t(y) * size_t(width_) + size_t(x)];
    return {std::min((float(x) + fx) / float(width_), 0x1.fffffep-1f),
            std::min((float(y) + fy) / float(height_), 0x1.fffffep-1f)};
  }

  float Pdf(float u, float v) const {
    if (density_.empty() || !(u >= 0 && u <= 1 && v >= 0 && v <= 1)) return 0;
    const int x = std::min(int(u * float(width_)), width_ - 1), y = std::min(int(v * float(height_)), height_ - 1);
    return density_[size_t(y) * size_t(width_) + size_t(x)];
  }

 private:
  // The interval of `cdf` (increasing, from 0) that u picks, among those of
  // positive width, and u's place within it.
  static std::pair<int, float> Invert(std::span<const double> cdf, float u) {
    const double target = double(std::clamp(u, 0.0f, 1.0f)) * cdf.back();
    const int last = int(cdf.size()) - 2;
    int i = int(std::upper_bound(cdf.begin(), cdf.end(), target) - cdf.begin()) - 1;
    i = std::clamp(i, 0, last);
    while (i > 0 && cdf[size_t(i) + 1] <= cdf[size_t(i)]) --i;  // u = 1 lands past the last non-empty one
    while (i < last && cdf[size_t(i) + 1] <= cdf[size_t(i)]) ++i;
    const double width = cdf[size_t(i) + 1] - cdf[size_t(i)];
    const float f = width > 0 ? float((target - cdf[size_t(i)]) / width) : 0.5f;
    return {i, std::clamp(f, 0.0f, 0x1.fffffep-1f)};
  }

  int width_ = 0, height_ = 0;
  double total_ = 0;
  std::vector<double> row_cdf_, cell_cdf_;
  std::vector<float> density_;
};

}  // namespace yarf
