// The image mode integrators share: sample passes over the film in tiles,
// each tile's pixels one batch of primary-sample points.
#pragma once

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdint>
#include <deque>
#include <unordered_map>
#include <vector>

#include "yarf/support/hash.h"
#include "yarf/math.h"
#include "yarf/transport.h"

namespace yarf {

// The points of one tile's pixels for `samples` consecutive sample
// indices from `first_index`, of `samples_per_pixel` in the job, produced
// lazily: the sampler's points where it places each pixel's samples
// (Sampler::AtPixel), with coordinates 0 and 1 placed inside the pixel.
// Point i is sample first_index + i % samples of pixel i / samples.
// Warp() lets an integrator remap the other coordinates.
class TilePoints : public PrimarySamples {
 public:
  TilePoints(const Sampler& sampler, uint64_t first_index, uint32_t width, uint32_t height,
             uint32_t samples_per_pixel, uint32_t samples = 1)
      : sampler_(sampler), first_index_(first_index), samples_(samples), samples_per_pixel_(samples_per_pixel),
        width_(width), height_(height), inv_width_(1.0f / width), inv_height_(1.0f / height) {}
  virtual ~TilePoints() = default;

  virtual void Reset(uint32_t x0, uint32_t y0, uint32_t x1, uint32_t y1, uint64_t seed) {
    pixels_.clear();
    indices_.clear();
    seeds_.clear();
    pairs_.clear();
    deep_pairs_.clear();
    deep_order_.clear();
    for (uint32_t y = y0; y < y1; ++y)
      for (uint32_t x = x0; x < x1; ++x) {
        pixels_.push_back({x, y});
        for (uint32_t s = 0; s < samples_; ++s) {
          const Sampler::FilmPoint point =
              sampler_.AtPixel(x, y, width_, height_, first_index_ + s, samples_per_pixel_, seed);
          indices_.push_back(point.index);
          seeds_.push_back(point.seed);
        }
      }
  }

  size_t Count() const override { return indices_.size(); }
  uint64_t SampleIndex(size_t i) const override { return first_index_ + i % samples_; }
  float Get(size_t i, uint32_t dimension) const override {
    std::vector<float>& values = Pair(dimension / 2);
    if (values[2 * i] == kUnmade) MakeBlock(values, dimension / 2, i);
    return Place(i, dimension, values[2 * i + dimension % 2]);
  }
  void Gather(std::span<const uint32_t> points, uint32_t dimension, std::span<float> out) const override {
    std::vector<float>& values = Pair(dimension / 2);
    MakePoints(values, dimension / 2, points);
    for (size_t k = 0; k < points.size(); ++k)
      out[k] = Place(points[k], dimension, values[2 * points[k] + dimension % 2]);
  }

 protected:
  virtual float Warp(size_t i, uint32_t dimension, float u) const { return u; }

 private:
  // The sampler's coordinates (2k, 2k + 1) of every point, made at the
  // first use of either and kept (kUnmade until then): the two share the
  // sampler's work on the index, and a coordinate asked for twice (the
  // film position) is made once.
  // The first kKeptPairs pairs are kept for the whole batch; of the deeper
  // ones only the kDeepPairs made last, the oldest dropped (and made
  // again, the same, if asked for again): a path that never ends, between
  // mirrors without roulette, would otherwise keep a pair per bounce.
  std::vector<float>& Pair(uint32_t pair) const {
    if (pair >= kKeptPairs) return DeepPair(pair);
    if (pair >= pairs_.size()) pairs_.resize(pair + 1);
    std::vector<float>& values = pairs_[pair];
    if (values.empty()) values.assign(2 * indices_.size(), kUnmade);
    return values;
  }
  std::vector<float>& DeepPair(uint32_t pair) const {
    if (const auto it = deep_pairs_.find(pair); it != deep_pairs_.end()) return it->second;
    std::vector<float> values;
    if (deep_pairs_.size() >= kDeepPairs) {
      values = std::move(deep_pairs_.extract(deep_order_.front()).mapped());
      deep_order_.pop_front();
    }
    values.assign(2 * indices_.size(), kUnmade);
    deep_order_.push_back(pair);
    return deep_pairs_.emplace(pair, std::move(values)).first->second;
  }
  // Makes pair `pair` of the aligned block of points around point i at
  // once, one call the sampler can vectorise; a block whose paths have all
  // ended never pays.
  void MakeBlock(std::vector<float>& values, uint32_t pair, size_t i) const {
    const size_t first = i - i % kBlock, count = std::min(kBlock, indices_.size() - first);
    sampler_.SamplePairs({&indices_[first], count}, {&seeds_[first], count}, pair, {&values[2 * first], 2 * count});
  }
  // Makes pair `pair` of those of `points` that lack it, in one call: a
  // wavefront's later bounces ask for scattered survivors, and making
  // only theirs spares the sampler the coordinates of ended paths.
  void MakePoints(std::vector<float>& values, uint32_t pair, std::span<const uint32_t> points) const {
    Missing& missing = missing_;
    missing.points.clear();
    missing.indices.clear();
    missing.seeds.clear();
    for (const uint32_t i : points)
      if (values[2 * i] == kUnmade) {
        missing.points.push_back(i);
        missing.indices.push_back(indices_[i]);
        missing.seeds.push_back(seeds_[i]);
      }
    if (missing.points.empty()) return;
    missing.values.resize(2 * missing.points.size());
    sampler_.SamplePairs(missing.indices, missing.seeds, pair, missing.values);
    for (size_t k = 0; k < missing.points.size(); ++k) {
      values[2 * missing.points[k]] = missing.values[2 * k];
      values[2 * missing.points[k] + 1] = missing.values[2 * k + 1];
    }
  }
  // Uniform coordinate u of point i where it lands: the film position in
  // its pixel, the rest through Warp.
  float Place(size_t i, uint32_t dimension, float u) const {
    if (dimension >= 2) return Warp(i, dimension, u);
    // Only the film position needs the point's pixel (a division).
    const Pixel& pixel = pixels_[i / samples_];
    return dimension == 0 ? (pixel.x + u) * inv_width_ : (pixel.y + u) * inv_height_;
  }
  // Marks a pair not made yet: samplers give values in [0, 1).
  static constexpr float kUnmade = -1;
  static constexpr size_t kBlock = 16;
  static constexpr uint32_t kKeptPairs = 64;
  static constexpr size_t kDeepPairs = 16;

  struct Pixel {
    uint32_t x, y;
  };
  const Sampler& sampler_;
  uint64_t first_index_;
  uint32_t samples_, samples_per_pixel_;
  uint32_t width_, height_;
  float inv_width_, inv_height_;
  std::vector<Pixel> pixels_;
  // Per point: its index in its pixel's sequence and the pixel's seed.
  std::vector<uint64_t> indices_, seeds_;
  // Per pair of dimensions asked for: [Count(), 2] coordinates, kUnmade
  // until made.
  mutable std::vector<std::vector<float>> pairs_;
  // Pairs from kKeptPairs on, and the order they were made in.
  mutable std::unordered_map<uint32_t, std::vector<float>> deep_pairs_;
  mutable std::deque<uint32_t> deep_order_;
  // MakePoints' points lacking a pair, their sampler inputs and values,
  // kept from call to call.
  struct Missing {
    std::vector<uint32_t> points;
    std::vector<uint64_t> indices, seeds;
    std::vector<float> values;
  };
  mutable Missing missing_;
};

// Runs passes from target.FirstSample() until target.SamplesPerPixel()
// samples per pixel, each of (at most) `samples_per_pass`, over the
// target's crop window: in each, every tile (in parallel) calls
// render_tile(first_sample, samples, x0, y0, x1, y1, out) with an emptied
// FilmSamples to fill and accumulate, then end_pass(pass) runs on this
// thread. Larger passes make larger batches (fewer calls to components in
// other processes). Stops early, between tiles, when the target is
// cancelled.
template <typename RenderTile, typename EndPass>
void RenderPasses(const SceneView& scene, RenderTarget& target, uint32_t tile_size, uint32_t samples_per_pass,
                  RenderTile&& render_tile, EndPass&& end_pass) {
  const PixelWindow window = target.Crop().value_or(PixelWindow{0, 0, scene.FilmWidth(), scene.FilmHeight()});
  const uint32_t tiles_x = (window.x1 - window.x0 + tile_size - 1) / tile_size;
  const uint32_t tiles_y = (window.y1 - window.y0 + tile_size - 1) / tile_size;
  tbb::enumerable_thread_specific<FilmSamples> outputs;
  const uint32_t spp = target.SamplesPerPixel();
  for (uint32_t pass = 0, done = target.FirstSample(); done < spp; ++pass) {
    if (target.Cancelled()) return;
    const uint32_t samples = std::min(samples_per_pass, spp - done);
    tbb::parallel_for(uint32_t(0), tiles_x * tiles_y, [&](uint32_t tile) {
      if (target.Cancelled()) return;
      const uint32_t x0 = window.x0 + (tile % tiles_x) * tile_size, y0 = window.y0 + (tile / tiles_x) * tile_size;
      FilmSamples& out = outputs.local();
      out.Clear();
      render_tile(done, samples, x0, y0, std::min(window.x1, x0 + tile_size), std::min(window.y1, y0 + tile_size),
                  out);
    });
    if (target.Cancelled()) return;
    end_pass(pass);
    done += samples;
    target.PassDone(done);
  }
}

}  // namespace yarf
