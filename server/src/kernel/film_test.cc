#include "kernel/film.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace yarf {
namespace {

v1::ReconstructionFilter Filter(v1::ReconstructionFilter::Kind kind) {
  v1::ReconstructionFilter f;
  f.set_kind(kind);
  return f;
}

// Every kind at its defaults, and a Lanczos wider along x than along y:
// negative lobes and unequal radii.
std::vector<v1::ReconstructionFilter> EveryFilter() {
  std::vector<v1::ReconstructionFilter> filters;
  for (auto kind : {v1::ReconstructionFilter::BOX, v1::ReconstructionFilter::TENT, v1::ReconstructionFilter::GAUSSIAN,
                    v1::ReconstructionFilter::MITCHELL, v1::ReconstructionFilter::LANCZOS})
    filters.push_back(Filter(kind));
  filters.push_back(Filter(v1::ReconstructionFilter::LANCZOS));
  filters.back().set_radius(4);
  filters.back().set_radius_y(2);
  return filters;
}

TEST(Film, BoxFilterAveragesTheSamplesInsideEachPixel) {
  Film film(4, 2, Filter(v1::ReconstructionFilter::BOX));
  film.Add(1.2f, 0.7f, {1, 2, 3});
  film.Add(1.9f, 0.1f, {3, 2, 1});
  film.Add(2.1f, 0.5f, {10, 10, 10});  // the next pixel
  const std::vector<float> pixels = film.Pixels();
  EXPECT_FLOAT_EQ(pixels[3 * 1 + 0], 2.0f);
  EXPECT_FLOAT_EQ(pixels[3 * 1 + 2], 2.0f);
  EXPECT_FLOAT_EQ(pixels[3 * 2 + 1], 10.0f);
  EXPECT_FLOAT_EQ(pixels[3 * 0], 0.0f);
}

TEST(Film, SplatsAreSummedPerPassAndAveragedOverPasses) {
  // One pass of width×height uniformly placed splats of value L estimates
  // L in every pixel under any filter, at the border too (where part of a
  // pixel's filter lies off the film).
  for (auto kind : {v1::ReconstructionFilter::BOX, v1::ReconstructionFilter::TENT,
                    v1::ReconstructionFilter::GAUSSIAN}) {
    Film film(16, 16, Filter(kind));
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0, 16);
    constexpr int kPasses = 400;
    for (int pass = 0; pass < kPasses; ++pass) {
      for (int i = 0; i < 16 * 16; ++i) film.Splat(u(rng), u(rng), {2, 2, 2});
      film.EndPass();
    }
    const std::vector<float> pixels = film.Pixels(), variances = film.Variances();
    double sum = 0, within = 0;
    int count = 0;
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 16; ++x) {
        const size_t k = 3 * (size_t(y) * 16 + x);
        sum += pixels[k];
        // Each pass is a Poisson-like count: variance of the mean ≈ 2²·1/passes.
        within += std::abs(pixels[k] - 2) < 5 * std::sqrt(variances[k]);
        ++count;
      }
    EXPECT_NEAR(sum / count, 2.0, 0.05) << kind;
    EXPECT_EQ(within, count) << kind;
    EXPECT_NEAR(variances[3 * (8 * 16 + 8)], 4.0 / kPasses, 4.0 / kPasses) << kind;
  }
}

TEST(Film, CameraSamplesAndSplatsAdd) {
  Film film(1, 1, Filter(v1::ReconstructionFilter::BOX));
  film.Add(0.5f, 0.5f, {1, 1, 1});
  film.Splat(0.5f, 0.5f, {3, 3, 3});
  film.EndPass();
  film.Splat(0.5f, 0.5f, {1, 1, 1});
  film.EndPass();
  // 1 from the camera sample, (3 + 1)/2 passes from the splats.
  EXPECT_FLOAT_EQ(film.Pixels()[0], 3.0f);
  // The passes gave 3 and 1: sample variance 2, variance of their mean 1.
  EXPECT_FLOAT_EQ(film.Variances()[0], 2.0f / 2.0f);
}

TEST(Film, ConstantRadianceGivesThatRadianceUnderEveryFilter) {
  for (const v1::ReconstructionFilter& filter : EveryFilter()) {
    const auto kind = filter.kind();
    Film film(8, 8, filter);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0, 8);
    for (int i = 0; i < 20000; ++i) film.Add(u(rng), u(rng), {0.25f, 0.5f, 1});
    for (float v : film.Variances()) EXPECT_NEAR(v, 0.0f, 1e-6f);
    const std::vector<float> pixels = film.Pixels();
    for (size_t k = 0; k < pixels.size(); k += 3) EXPECT_NEAR(pixels[k + 2], 1.0f, 1e-5f) << kind;
  }
}

TEST(Film, VarianceIsThatOfThePixelMean) {
  // Box filter: n samples of a uniform [0, 1) value have mean variance 1/(12 n).
  constexpr int kSamples = 4000;
  Film film(1, 1, Filter(v1::ReconstructionFilter::BOX));
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0, 1);
  for (int i = 0; i < kSamples; ++i) {
    const float value = u(rng);
    film.Add(u(rng), u(rng), {value, value, value});
  }
  EXPECT_NEAR(film.Variances()[0], 1.0 / (12.0 * kSamples), 0.1 / (12.0 * kSamples));
  EXPECT_NEAR(film.Pixels()[0], 0.5f, 4 * std::sqrt(1.0 / (12.0 * kSamples)));
}

TEST(Film, IgnoresNonFiniteSamples) {
  Film film(1, 1, Filter(v1::ReconstructionFilter::BOX));
  film.Add(0.5f, 0.5f, {1, 1, 1});
  film.Add(0.5f, 0.5f, {NAN, 1, 1});
  film.Add(0.5f, 0.5f, {INFINITY, 1, 1});
  EXPECT_FLOAT_EQ(film.Pixels()[0], 1.0f);
}

TEST(Film, APixelEstimateShowsItsValueAndVarianceAndEstimatesAverageBySamples) {
  Film film(2, 1, Filter(v1::ReconstructionFilter::GAUSSIAN));
  film.AddEstimate(1, 0, {0.5f, 1, 2}, {0.01f, 0.04f, 0}, 16);
  std::vector<float> pixels = film.Pixels(), variances = film.Variances();
  EXPECT_FLOAT_EQ(pixels[3], 0.5f);
  EXPECT_FLOAT_EQ(pixels[5], 2.0f);
  EXPECT_FLOAT_EQ(variances[3], 0.01f);
  EXPECT_FLOAT_EQ(variances[4], 0.04f);
  EXPECT_NEAR(variances[5], 0.0f, 1e-6f);
  // The filter spreads nothing: the other pixel has no estimate.
  EXPECT_EQ(pixels[0], 0.0f);
  // Another estimate of 48 samples: the mean by samples, 0.5·¼ + 1.5·¾.
  film.AddEstimate(1, 0, {1.5f, 1, 2}, {0.01f, 0.04f, 0}, 48);
  pixels = film.Pixels();
  EXPECT_FLOAT_EQ(pixels[3], 1.25f);
  EXPECT_FLOAT_EQ(pixels[4], 1.0f);
  // Not finite, or off the film: left out.
  film.AddEstimate(0, 0, {NAN, 1, 1}, {0, 0, 0}, 4);
  film.AddEstimate(2, 0, {1, 1, 1}, {0, 0, 0}, 4);
  EXPECT_EQ(film.Pixels()[0], 0.0f);
}

TEST(Film, PixelWeightsIntegrateToOneOverTheFilmUnderEveryFilter) {
  for (const v1::ReconstructionFilter& filter : EveryFilter()) {
    const auto kind = filter.kind();
    Film film(6, 5, filter);
    film.PrepareMasses();
    // A corner pixel, whose filter the film cuts, and an inner one.
    for (auto [px, py] : {std::pair{0u, 0u}, std::pair{3u, 2u}}) {
      constexpr int kSteps = 600;
      double sum = 0;
      for (int j = 0; j < kSteps; ++j)
        for (int i = 0; i < kSteps; ++i)
          sum += film.PixelWeight(px, py, (i + 0.5f) * 6 / kSteps, (j + 0.5f) * 5 / kSteps);
      EXPECT_NEAR(sum * 6 * 5 / (double(kSteps) * kSteps), 1.0, 2e-3) << kind << " pixel " << px << ", " << py;
    }
  }
}

}  // namespace
}  // namespace yarf
