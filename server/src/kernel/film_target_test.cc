#include "kernel/film_target.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <vector>

namespace yarf {
namespace {

constexpr uint32_t kWidth = 75, kHeight = 45;  // blocks cut at the right and bottom edges
constexpr int kThreads = 8;
constexpr float kCameraWeight = 3.14159265f;

v1::ReconstructionFilter Filter(v1::ReconstructionFilter::Kind kind, float radius) {
  v1::ReconstructionFilter f;
  f.set_kind(kind);
  f.set_radius(radius);
  return f;
}

// A box filter reaches one pixel; a Gaussian of radius 6 reaches the blocks
// around a sample's own.
std::vector<v1::ReconstructionFilter> Filters() {
  return {Filter(v1::ReconstructionFilter::BOX, 0), Filter(v1::ReconstructionFilter::GAUSSIAN, 6)};
}

// What thread `thread` adds in one pass: camera samples in its own strip of
// columns, camera samples anywhere (some off the film, one not finite) and
// splats anywhere.
std::vector<FilmSamples> Batches(int thread, int pass) {
  std::mt19937 rng(1000 * pass + thread);
  std::uniform_real_distribution<float> u(0, 1);
  const float strip = float(kWidth) / kThreads;
  std::vector<FilmSamples> batches;
  for (int b = 0; b < 12; ++b) {
    FilmSamples batch;
    batch.splats = b % 3 == 2;
    for (uint32_t i = 0; i < 300; ++i) {
      const Vec3 value{u(rng), 2 * u(rng), 0.25f + u(rng)};
      if (b % 3 == 0)
        batch.Add(i, (thread + u(rng)) * strip, u(rng) * kHeight, value);
      else
        batch.Add(i, -3 + u(rng) * (kWidth + 6), -3 + u(rng) * (kHeight + 6), value);
    }
    batch.Add(300, NAN, 1, {1, 1, 1});
    batches.push_back(std::move(batch));
  }
  return batches;
}

// Everything a film holds, as Save writes it: its header and then doubles.
struct Accumulators {
  std::string header;
  std::vector<double> values;
};

Accumulators AccumulatorsOf(const Film& film) {
  const std::string bytes = film.Save();
  // Magic, seven u32 (the last the filter's size), the filter, the doubles.
  uint32_t filter_size;
  std::memcpy(&filter_size, bytes.data() + 32, sizeof filter_size);
  const size_t start = 36 + filter_size;
  Accumulators out{bytes.substr(0, start), std::vector<double>((bytes.size() - start) / sizeof(double))};
  std::memcpy(out.values.data(), bytes.data() + start, out.values.size() * sizeof(double));
  return out;
}

TEST(FilmTarget, BatchesFromManyThreadsAddUpAsTheSameBatchesOneByOne) {
  for (const v1::ReconstructionFilter& filter : Filters()) {
    SCOPED_TRACE(filter.ShortDebugString());
    Film serial(kWidth, kHeight, filter), concurrent(kWidth, kHeight, filter);
    FilmLock lock;
    const std::atomic<bool> cancel{false};
    int passes_done = 0;
    FilmTarget target(concurrent, lock, 2, 1, {}, cancel, [&](uint32_t) { ++passes_done; });
    target.WeighCameraSamples(kCameraWeight);
    for (int pass = 0; pass < 2; ++pass) {
      for (int thread = 0; thread < kThreads; ++thread)
        for (const FilmSamples& batch : Batches(thread, pass))
          for (size_t i = 0; i < batch.Count(); ++i) {
            const float x = batch.xy[2 * i], y = batch.xy[2 * i + 1];
            if (batch.splats)
              serial.Splat(x, y, batch.rgb[i]);
            else
              serial.Add(x, y, batch.rgb[i] * kCameraWeight);
          }
      serial.EndPass(1);
      {
        std::vector<std::jthread> threads;
        for (int thread = 0; thread < kThreads; ++thread)
          threads.emplace_back([&, thread] {
            for (const FilmSamples& batch : Batches(thread, pass)) target.Accumulate(batch);
          });
      }
      target.PassDone(pass + 1);
    }
    EXPECT_EQ(passes_done, 2);
    const Accumulators expected = AccumulatorsOf(serial), actual = AccumulatorsOf(concurrent);
    EXPECT_EQ(actual.header, expected.header);
    ASSERT_EQ(actual.values.size(), expected.values.size());
    size_t nonzero = 0;
    for (size_t i = 0; i < expected.values.size(); ++i) {
      nonzero += expected.values[i] != 0;
      EXPECT_NEAR(actual.values[i], expected.values[i], 1e-12 * std::abs(expected.values[i])) << "double " << i;
    }
    EXPECT_GT(nonzero, expected.values.size() / 2);
    const std::vector<float> pixels = concurrent.Pixels(), expected_pixels = serial.Pixels();
    for (size_t i = 0; i < pixels.size(); ++i)
      EXPECT_NEAR(pixels[i], expected_pixels[i], 1e-6f * std::abs(expected_pixels[i])) << "value " << i;
  }
}

TEST(FilmTarget, AReaderHoldingTheLockSeesNoSampleHalfAdded) {
  // Every camera sample has the same radiance: a pixel reads that radiance
  // or, before its first sample, 0; a sample half added would read neither.
  const Vec3 radiance{0.5f, 1, 2};
  for (const v1::ReconstructionFilter& filter : Filters()) {
    SCOPED_TRACE(filter.ShortDebugString());
    Film film(kWidth, kHeight, filter);
    FilmLock lock;
    const std::atomic<bool> cancel{false};
    FilmTarget target(film, lock, 1, 1, {}, cancel, [](uint32_t) {});
    std::atomic<bool> done{false};
    {
      std::vector<std::jthread> writers;
      for (int thread = 0; thread < kThreads; ++thread)
        writers.emplace_back([&, thread] {
          std::mt19937 rng(thread);
          std::uniform_real_distribution<float> u(0, 1);
          FilmSamples camera, splats;
          splats.splats = true;
          for (uint32_t i = 0; i < 200; ++i) {
            camera.Add(i, u(rng) * kWidth, u(rng) * kHeight, radiance);
            splats.Add(i, u(rng) * kWidth, u(rng) * kHeight, {1, 1, 1});
          }
          // Until the reader has had its snapshots: a reader that waited for
          // the writers to pause would wait for ever.
          while (!done.load(std::memory_order_relaxed)) {
            target.Accumulate(camera);
            target.Accumulate(splats);
          }
        });
      size_t half_added = 0;
      for (int snapshot = 0; snapshot < 200; ++snapshot) {
        std::vector<float> pixels;
        {
          std::lock_guard alone(lock);
          pixels = film.Pixels();
        }
        for (size_t k = 0; k < pixels.size(); k += 3)
          for (int c = 0; c < 3; ++c)
            if (const float value = pixels[k + c]; value != 0 && !(std::abs(value - radiance[c]) <= 1e-5f * radiance[c]))
              ++half_added;
        std::this_thread::yield();
      }
      done = true;
      EXPECT_EQ(half_added, 0u);
    }
    // Splats count once their pass ends.
    target.PassDone(1);
    for (float value : film.Pixels()) EXPECT_TRUE(std::isfinite(value));
  }
}

TEST(FilmTarget, PixelEstimatesAreWeighedAsCameraSamples) {
  Film film(kWidth, kHeight, Filter(v1::ReconstructionFilter::BOX, 0));
  FilmLock lock;
  const std::atomic<bool> cancel{false};
  FilmTarget target(film, lock, 8, 1, {}, cancel, [](uint32_t) {});
  target.WeighCameraSamples(kCameraWeight);
  // A window across four locking blocks, row by row.
  const PixelWindow window{14, 14, 18, 17};
  std::vector<Vec3> values, variances;
  for (uint32_t y = window.y0; y < window.y1; ++y)
    for (uint32_t x = window.x0; x < window.x1; ++x) {
      values.emplace_back(float(x), float(y), 1);
      variances.emplace_back(0.5f, 0.25f, 0);
    }
  target.AddPixelEstimates(window, 8, values, variances);
  const std::vector<float> pixels = film.Pixels(), variance = film.Variances();
  for (uint32_t y = 0; y < kHeight; ++y)
    for (uint32_t x = 0; x < kWidth; ++x) {
      const size_t k = 3 * (size_t(y) * kWidth + x);
      const bool inside = x >= window.x0 && x < window.x1 && y >= window.y0 && y < window.y1;
      EXPECT_FLOAT_EQ(pixels[k], inside ? x * kCameraWeight : 0) << x << ", " << y;
      EXPECT_FLOAT_EQ(pixels[k + 1], inside ? y * kCameraWeight : 0) << x << ", " << y;
      EXPECT_NEAR(variance[k], inside ? 0.5f * kCameraWeight * kCameraWeight : 0, 1e-5f) << x << ", " << y;
    }
  // A window that leaves the film (x1 > 75), of as many values.
  EXPECT_THROW(target.AddPixelEstimates({70, 40, 76, 42}, 8, values, variances), Error);
}

TEST(FilmTarget, TheFilmRecordsSamplesExposedThenScaledDownToTheLargestComponent) {
  Film film(3, 1, Filter(v1::ReconstructionFilter::BOX, 0));
  FilmLock lock;
  const std::atomic<bool> cancel{false};
  FilmTarget target(film, lock, 8, 1, {}, cancel, [](uint32_t) {});
  target.WeighCameraSamples(2);
  target.Expose(1.5f, 6);
  FilmSamples camera;
  camera.Add(0, 0.5f, 0.5f, {1, 0.5f, 0.25f});  // × 2 × 1.5: (3, 1.5, 0.75), below 6
  camera.Add(1, 1.5f, 0.5f, {4, 2, 1});         // (12, 6, 3), scaled by 6/12
  target.Accumulate(camera);
  FilmSamples splats;
  splats.splats = true;
  splats.Add(0, 2.5f, 0.5f, {8, 1, 0});  // × 1.5 (no camera weight): (12, 1.5, 0), scaled by 1/2
  target.Accumulate(splats);
  target.PassDone(1);
  const std::vector<float> pixels = film.Pixels();
  const std::vector<float> expected{3, 1.5f, 0.75f, 6, 3, 1.5f, 6, 0.75f, 0};
  for (size_t k = 0; k < expected.size(); ++k) EXPECT_FLOAT_EQ(pixels[k], expected[k]) << k;
  // Whole-pixel estimates are exposed, never scaled down: an estimate is
  // a mean, not a sample.
  Film estimated(1, 1, Filter(v1::ReconstructionFilter::BOX, 0));
  FilmTarget estimates(estimated, lock, 8, 1, {}, cancel, [](uint32_t) {});
  estimates.Expose(2, 1);
  const std::vector<Vec3> value{{10, 1, 0}}, variance{{4, 0, 0}};
  estimates.AddPixelEstimates({0, 0, 1, 1}, 8, value, variance);
  EXPECT_FLOAT_EQ(estimated.Pixels()[0], 20);
  EXPECT_FLOAT_EQ(estimated.Variances()[0], 16);
}

TEST(FilmTarget, NoExposureGivenRecordsSamplesAsTheyCome) {
  Film film(kWidth, kHeight, Filter(v1::ReconstructionFilter::BOX, 0));
  FilmLock lock;
  const std::atomic<bool> cancel{false};
  FilmTarget target(film, lock, 8, 1, {}, cancel, [](uint32_t) {});
  target.Expose(1, 0);  // 0: no largest component
  FilmSamples camera;
  camera.Add(0, 0.5f, 0.5f, {1e30f, 1, 0});
  target.Accumulate(camera);
  EXPECT_FLOAT_EQ(film.Pixels()[0], 1e30f);
}

}  // namespace
}  // namespace yarf
