// TileIntegrand integrated over the unit cube gives each pixel of its tile
// the value the film's camera samples converge to, under every filter; it
// refuses splats and points outside the cube, naming the transport.
#include "components/tile_integrand.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <string>
#include <vector>

#include "kernel/film_target.h"

namespace yarf {
namespace {

constexpr uint32_t kWidth = 12, kHeight = 10, kSide = 4;

// Radiance varying smoothly over the film (raster position in pixels).
Vec3 Radiance(float x, float y) {
  return {1 + 0.5f * std::sin(0.7f * x), 2 + std::cos(0.4f * y), 0.5f + 0.05f * x * y};
}

// Camera samples of Radiance at their film position, or splats.
TileIntegrand::Evaluator Samples(bool splats = false) {
  return [splats](const PrimarySamples& points, FilmSamples& out) {
    out.splats = splats;
    for (size_t i = 0; i < points.Count(); ++i) {
      const float x = points.Get(i, kFilmDimension) * kWidth, y = points.Get(i, kFilmDimension + 1) * kHeight;
      out.Add(uint32_t(i), x, y, Radiance(x, y));
    }
  };
}

v1::ReconstructionFilter Filter(v1::ReconstructionFilter::Kind kind) {
  v1::ReconstructionFilter f;
  f.set_kind(kind);
  return f;
}

// A FilmTarget over a film of its own.
struct Target {
  explicit Target(v1::ReconstructionFilter::Kind kind)
      : film(kWidth, kHeight, Filter(kind)), target(film, lock, 16, 1, {}, cancel, [](uint32_t) {}) {}
  Film film;
  FilmLock lock;
  std::atomic<bool> cancel{false};
  FilmTarget target;
};

// ∫ of every output over the unit square by the midpoint rule on a
// steps × steps grid.
std::vector<double> Integral(TileIntegrand& f, int steps) {
  const uint32_t k = f.OutputDimensions();
  std::vector<double> sum(k, 0.0);
  std::vector<float> points, values;
  for (int j = 0; j < steps; ++j) {
    points.clear();
    for (int i = 0; i < steps; ++i) {
      points.push_back((i + 0.5f) / steps);
      points.push_back((j + 0.5f) / steps);
    }
    values.resize(size_t(steps) * k);
    f.Evaluate(points, values);
    for (int i = 0; i < steps; ++i)
      for (uint32_t c = 0; c < k; ++c) sum[c] += values[size_t(i) * k + c];
  }
  for (double& s : sum) s /= double(steps) * steps;
  return sum;
}

std::string ErrorOf(const std::function<void()>& call) {
  try {
    call();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(TileIntegrand, ItsIntegralIsEachPixelsFilteredValueUnderEveryFilter) {
  for (auto kind : {v1::ReconstructionFilter::BOX, v1::ReconstructionFilter::TENT, v1::ReconstructionFilter::GAUSSIAN,
                    v1::ReconstructionFilter::MITCHELL, v1::ReconstructionFilter::LANCZOS}) {
    // What camera samples converge to: a fine grid of them over the film.
    Film reference(kWidth, kHeight, Filter(kind));
    constexpr int kPerPixel = 64;
    for (uint32_t j = 0; j < kHeight * kPerPixel; ++j)
      for (uint32_t i = 0; i < kWidth * kPerPixel; ++i) {
        const float x = (i + 0.5f) / kPerPixel, y = (j + 0.5f) / kPerPixel;
        reference.Add(x, y, Radiance(x, y));
      }
    const std::vector<float> expected = reference.Pixels();
    Target target(kind);
    TileIntegrand f("camera", 2, Samples(), kWidth, kHeight, target.target, kSide);
    EXPECT_EQ(f.OutputDimensions(), 1 + 3 * kSide * kSide);
    // A corner tile (the film cuts its pixels' filters), an inner one, and
    // one cut short by the film's bottom edge.
    for (const PixelWindow tile : {PixelWindow{0, 0, 4, 4}, PixelWindow{4, 4, 8, 8}, PixelWindow{8, 8, 12, 10}}) {
      f.SetTile(tile);
      const std::vector<double> integral = Integral(f, 800);
      double luminance = 0;
      for (uint32_t y = tile.y0; y < tile.y1; ++y)
        for (uint32_t x = tile.x0; x < tile.x1; ++x) {
          const size_t slot = f.Slot(x, y), pixel = 3 * (size_t(y) * kWidth + x);
          for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(integral[slot + c], expected[pixel + c], 2e-3 * expected[pixel + c])
                << kind << " pixel " << x << ", " << y << " channel " << c;
          luminance += Luminance(Vec3(float(integral[slot]), float(integral[slot + 1]), float(integral[slot + 2])));
        }
      // The first output: the mean luminance of the tile's pixels.
      EXPECT_NEAR(integral[0], luminance / ((tile.x1 - tile.x0) * (tile.y1 - tile.y0)), 1e-4 * integral[0]) << kind;
      // The slots of pixels past the film's edge stay 0.
      if (tile.y1 - tile.y0 < kSide) {
        EXPECT_EQ(integral[f.Slot(tile.x0, tile.y0 + kSide - 1)], 0.0);
      }
    }
  }
}

TEST(TileIntegrand, RefusesSplatsNamingTheTransport) {
  Target target(v1::ReconstructionFilter::BOX);
  TileIntegrand f("light", 2, Samples(true), kWidth, kHeight, target.target, kSide);
  f.SetTile({0, 0, 4, 4});
  std::vector<float> points = {0.5f, 0.5f}, values(f.OutputDimensions());
  const std::string error = ErrorOf([&] { f.Evaluate(points, values); });
  EXPECT_NE(error.find("transport 'light' splats its contributions"), std::string::npos) << error;
  EXPECT_EQ(f.Failure(), error);
}

TEST(TileIntegrand, RefusesPointsOutsideTheUnitCube) {
  Target target(v1::ReconstructionFilter::BOX);
  TileIntegrand f("camera", 2, Samples(), kWidth, kHeight, target.target, kSide);
  f.SetTile({0, 0, 4, 4});
  std::vector<float> points = {0.5f, 0.5f, 0.25f, 1.5f}, values(2 * f.OutputDimensions());
  const std::string error = ErrorOf([&] { f.Evaluate(points, values); });
  EXPECT_NE(error.find("point 1 has coordinate 1 = 1.5"), std::string::npos) << error;
}

TEST(TileIntegrand, StopsOnceTheRenderIsCancelled) {
  Target target(v1::ReconstructionFilter::BOX);
  TileIntegrand f("camera", 2, Samples(), kWidth, kHeight, target.target, kSide);
  f.SetTile({0, 0, 4, 4});
  target.cancel = true;
  std::vector<float> points = {0.5f, 0.5f}, values(f.OutputDimensions());
  EXPECT_NE(ErrorOf([&] { f.Evaluate(points, values); }).find("cancelled"), std::string::npos);
}

TEST(TileIntegrand, GivesCoordinatesPastItsDimensionsFromThePoint) {
  // A path longer than the transport said still gets uniform numbers, the
  // same for the same point.
  Target target(v1::ReconstructionFilter::BOX);
  std::vector<float> seen;
  TileIntegrand f(
      "camera", 2,
      [&](const PrimarySamples& points, FilmSamples& out) {
        for (size_t i = 0; i < points.Count(); ++i) seen.push_back(points.Get(i, 7));
      },
      kWidth, kHeight, target.target, kSide);
  f.SetTile({0, 0, 4, 4});
  std::vector<float> points = {0.5f, 0.5f, 0.25f, 0.5f, 0.5f, 0.5f}, values(3 * f.OutputDimensions());
  f.Evaluate(points, values);
  ASSERT_EQ(seen.size(), 3u);
  EXPECT_EQ(seen[0], seen[2]);
  EXPECT_NE(seen[0], seen[1]);
  for (float u : seen) EXPECT_TRUE(u >= 0 && u < 1);
}

}  // namespace
}  // namespace yarf
