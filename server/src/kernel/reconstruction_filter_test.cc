// The reconstruction filters' shapes, and the film's averages under those
// with negative lobes.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "kernel/film.h"

namespace yarf {
namespace {

using Kind = v1::ReconstructionFilter::Kind;

v1::ReconstructionFilter Filter(Kind kind, double radius = 0) {
  v1::ReconstructionFilter f;
  f.set_kind(kind);
  f.set_radius(radius);
  return f;
}

v1::ReconstructionFilter Mitchell(double b, double c) {
  v1::ReconstructionFilter f = Filter(v1::ReconstructionFilter::MITCHELL);
  f.set_b(b);
  f.set_c(c);
  return f;
}

// Mitchell and Netravali's cubic as their paper writes it, over |x| in [0, 2).
double MitchellNetravali(double x, double b, double c) {
  x = std::abs(x);
  if (x < 1) return ((12 - 9 * b - 6 * c) * x * x * x + (-18 + 12 * b + 6 * c) * x * x + (6 - 2 * b)) / 6;
  if (x < 2)
    return ((-b - 6 * c) * x * x * x + (6 * b + 30 * c) * x * x + (-12 * b - 48 * c) * x + (8 * b + 24 * c)) / 6;
  return 0;
}

double NormalisedSinc(double x) { return x == 0 ? 1 : std::sin(std::numbers::pi * x) / (std::numbers::pi * x); }

TEST(ReconstructionFilter, MitchellIsTheCubicStretchedOverItsRadius) {
  for (auto [b, c] : {std::pair{1.0 / 3, 1.0 / 3}, std::pair{0.0, 0.5}, std::pair{0.2, 0.4}, std::pair{1.0, 0.0}})
    for (double radius : {2.0, 1.5, 3.0}) {
      v1::ReconstructionFilter spec = Mitchell(b, c);
      spec.set_radius(radius);
      const ReconstructionFilter filter(spec);
      for (double d = -radius - 0.25; d <= radius + 0.25; d += 0.0625)
        EXPECT_NEAR(filter.x().Weight(float(d)), MitchellNetravali(2 * d / radius, b, c), 2e-6)
            << "b " << b << " c " << c << " radius " << radius << " at " << d;
    }
  // B and C default to 1/3 each, the radius to 2: Mitsuba 3.9.1's own
  // `mitchell` evaluates 0.888889 at 0, 0.055556 at 1, -0.034722 at 1.5.
  const ReconstructionFilter standard(Filter(v1::ReconstructionFilter::MITCHELL));
  EXPECT_FLOAT_EQ(standard.radius(), 2);
  EXPECT_NEAR(standard.x().Weight(0), 0.888889, 1e-6);
  EXPECT_NEAR(standard.x().Weight(1), 0.055556, 1e-6);
  EXPECT_NEAR(standard.x().Weight(1.5f), -0.034722, 1e-6);
  // Catmull-Rom interpolates: 1 at the sample, 0 one pixel away.
  const ReconstructionFilter catmull_rom(Mitchell(0, 0.5));
  EXPECT_FLOAT_EQ(catmull_rom.x().Weight(0), 1);
  EXPECT_NEAR(catmull_rom.x().Weight(1), 0, 1e-6);
}

TEST(ReconstructionFilter, LanczosIsTheSincWindowedByAWiderSinc) {
  for (double lobes : {3.0, 2.0, 4.5}) {
    v1::ReconstructionFilter spec = Filter(v1::ReconstructionFilter::LANCZOS);
    spec.set_lobes(lobes);
    const ReconstructionFilter filter(spec);
    EXPECT_FLOAT_EQ(filter.radius(), float(lobes));  // Mitsuba's rule: as many lobes as the radius
    for (double d = 0; d <= lobes + 0.5; d += 0.05)
      EXPECT_NEAR(filter.x().Weight(float(d)), d < lobes ? NormalisedSinc(d) * NormalisedSinc(d / lobes) : 0, 2e-6)
          << lobes << " lobes at " << d;
  }
  // pbrt's sinc filter: radius 4 with a window of 3.
  v1::ReconstructionFilter pbrt = Filter(v1::ReconstructionFilter::LANCZOS, 4);
  pbrt.set_lobes(3);
  const ReconstructionFilter filter(pbrt);
  EXPECT_NEAR(filter.x().Weight(3.5f), NormalisedSinc(3.5) * NormalisedSinc(3.5 / 3), 1e-6);
  EXPECT_LT(filter.x().Weight(1.5f), 0);
}

TEST(ReconstructionFilter, AGaussiansStandardDeviationSetsItsShapeAndDefaultRadius) {
  for (double stddev : {0.5, 1.0, 0.25}) {
    v1::ReconstructionFilter spec = Filter(v1::ReconstructionFilter::GAUSSIAN);
    spec.set_stddev(stddev);
    const ReconstructionFilter filter(spec);
    const double radius = 4 * stddev, offset = std::exp(-radius * radius / (2 * stddev * stddev));
    EXPECT_FLOAT_EQ(filter.radius(), float(radius));
    for (double d = 0; d < radius; d += 0.1)
      EXPECT_NEAR(filter.x().Weight(float(d)), std::exp(-d * d / (2 * stddev * stddev)) - offset, 1e-6) << d;
  }
  // pbrt's: σ 0.5 cut at 1.5, shifted to reach 0 there.
  v1::ReconstructionFilter pbrt = Filter(v1::ReconstructionFilter::GAUSSIAN, 1.5);
  EXPECT_NEAR(ReconstructionFilter(pbrt).x().Weight(1.4999f), 0, 1e-4);
}

TEST(ReconstructionFilter, EachAxisHasItsOwnRadius) {
  v1::ReconstructionFilter spec = Filter(v1::ReconstructionFilter::TENT, 0.5);
  spec.set_radius_y(2);
  const ReconstructionFilter filter(spec);
  EXPECT_FLOAT_EQ(filter.radius(), 2);
  EXPECT_FLOAT_EQ(filter.Weight(0.25f, 1), 0.5f * 0.5f);
  EXPECT_FLOAT_EQ(filter.Weight(1, 0.25f), 0);
  // On the film: a sample at a pixel's centre reaches two rows up and
  // down, no other column.
  Film film(5, 5, spec);
  film.Add(2.5f, 2.5f, {1, 1, 1});
  const std::vector<float> pixels = film.Pixels();
  for (uint32_t y = 0; y < 5; ++y)
    for (uint32_t x = 0; x < 5; ++x)
      EXPECT_EQ(pixels[3 * (5 * y + x)], x == 2 && y >= 1 && y <= 3 ? 1.0f : 0.0f) << x << ", " << y;
}

TEST(ReconstructionFilter, ParametersOutOfRangeAreRefusedWithTheirName) {
  const auto refused = [](const v1::ReconstructionFilter& spec, const std::string& named) {
    try {
      ReconstructionFilter{spec};
    } catch (const Error& e) {
      return std::string(e.what()).find(named) != std::string::npos;
    }
    return false;
  };
  for (double bad : {std::nan(""), -1.0, 1e30}) {
    v1::ReconstructionFilter gaussian = Filter(v1::ReconstructionFilter::GAUSSIAN, 2);
    gaussian.set_stddev(bad);
    EXPECT_TRUE(refused(gaussian, "stddev")) << bad;
    v1::ReconstructionFilter lanczos = Filter(v1::ReconstructionFilter::LANCZOS, 3);
    lanczos.set_lobes(bad);
    EXPECT_TRUE(refused(lanczos, "lobes")) << bad;
    v1::ReconstructionFilter tall = Filter(v1::ReconstructionFilter::BOX);
    tall.set_radius_y(bad == -1.0 ? 17 : bad);
    EXPECT_TRUE(refused(tall, "radius_y")) << bad;
  }
  EXPECT_TRUE(refused(Mitchell(std::nan(""), 0.5), "film.filter.b"));
  EXPECT_TRUE(refused(Mitchell(0, 1e9), "film.filter.c"));
  // A centre that weighs less than nothing (B = 4: (6 − 2B)/6 < 0).
  EXPECT_TRUE(refused(Mitchell(4, 0), "not positive"));
  // A Gaussian whose default radius, 4σ, reaches past 16 pixels.
  v1::ReconstructionFilter wide = Filter(v1::ReconstructionFilter::GAUSSIAN);
  wide.set_stddev(5);
  EXPECT_TRUE(refused(wide, "give a radius"));
  wide.set_radius(16);
  EXPECT_NO_THROW(ReconstructionFilter{wide});
}

// The mean of radiance L(x) = 1 right of `edge`, 0 left of it, under one
// axis of a filter around `centre`: ∫ w L / ∫ w, by the midpoint rule.
double StepUnderFilter(const FilterAxis& axis, double centre, double edge, double film_width) {
  const double lo = std::max(0.0, centre - axis.radius()), hi = std::min(film_width, centre + axis.radius());
  constexpr int kSteps = 200000;
  double weighted = 0, mass = 0;
  for (int i = 0; i < kSteps; ++i) {
    const double x = lo + (i + 0.5) * (hi - lo) / kSteps, w = axis.Weight(float(x - centre));
    mass += w;
    if (x >= edge) weighted += w;
  }
  return weighted / mass;
}

TEST(Film, NegativeLobesRingAtAnEdgeAsTheFiltersAverageDoes) {
  // A vertical edge at x = 8 on a 16×3 film, samples spread evenly: each
  // pixel converges to the filter's average of the step, below 0 just left
  // of the edge and above 1 just right of it.
  for (const v1::ReconstructionFilter& spec :
       {Filter(v1::ReconstructionFilter::MITCHELL), Mitchell(0, 0.5), Filter(v1::ReconstructionFilter::LANCZOS)}) {
    constexpr uint32_t kWidth = 16, kHeight = 3;
    constexpr double kEdge = 8;
    Film film(kWidth, kHeight, spec);
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> x(0, kWidth), y(0, kHeight);
    for (int i = 0; i < 400000; ++i) {
      const float at = x(rng);
      const float value = at >= kEdge ? 1.0f : 0.0f;
      film.Add(at, y(rng), {value, value, value});
    }
    const ReconstructionFilter filter(spec);
    const std::vector<float> pixels = film.Pixels(), variances = film.Variances();
    bool rings = false;
    for (uint32_t px = 0; px < kWidth; ++px) {
      const double expected = StepUnderFilter(filter.x(), px + 0.5, kEdge, kWidth);
      const size_t k = 3 * (kWidth * 1 + px);  // the middle row
      EXPECT_NEAR(pixels[k], expected, 5 * std::sqrt(variances[k]) + 1e-4) << spec.kind() << " pixel " << px;
      rings |= expected < -1e-3 || expected > 1 + 1e-3;
    }
    EXPECT_TRUE(rings) << spec.kind();
  }
}

}  // namespace
}  // namespace yarf
