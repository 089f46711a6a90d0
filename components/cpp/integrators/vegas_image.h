// The image mode of vegas and vegas_plus: one VEGAS map over the
// transport's primary sample space (all pixels share it), adapted between
// sample passes to where the film's luminance comes from.
//
// Coordinates 0 and 1 stay stratified within the pixel; coordinates 2 ..
// 2 + kMappedDimensions - 1 go through the map; higher ones pass through.
// A point's contribution is weighted by the Jacobian of the map over the
// coordinates its path actually asked for: a coordinate it never read
// integrates to 1 whatever the map does there, so leaving it out keeps
// the estimate unbiased with less variance. Each pass uses one fixed map,
// so every pass is an unbiased estimate and the film averages them. The
// map is refined after passes 1, 2, 4, 8 ... up to half of the passes,
// then frozen.
#pragma once

#include <cmath>
#include <vector>

#include "image_passes.h"
#include "vegas_map.h"

namespace yarf {

constexpr uint32_t kMappedDimensions = 16;
constexpr uint32_t kFirstMappedDimension = 2;

// Tile points whose coordinates from 2 on go through the map; remembers,
// per point, the Jacobian and the bins of the coordinates it was asked for.
class MappedTilePoints final : public TilePoints {
 public:
  MappedTilePoints(const Sampler& sampler, const AdaptiveMap& map, uint64_t index, uint32_t width,
                   uint32_t height, uint32_t samples_per_pixel)
      : TilePoints(sampler, index, width, height, samples_per_pixel), map_(map) {}

  void Reset(uint32_t x0, uint32_t y0, uint32_t x1, uint32_t y1, uint64_t seed) override {
    TilePoints::Reset(x0, y0, x1, y1, seed);
    jacobian_.assign(Count(), 1.0);
    used_.assign(Count(), 0);
    bins_.resize(Count() * kMappedDimensions);
  }

  double Jacobian(size_t i) const { return jacobian_[i]; }
  // Adds (J f)² of point i to the map statistics of the coordinates it read.
  void Train(size_t i, double value, AdaptiveMap& statistics) const {
    for (uint64_t used = used_[i]; used != 0; used &= used - 1) {
      const uint32_t j = uint32_t(__builtin_ctzll(used));
      statistics.AccumulateAxis(j, bins_[i * kMappedDimensions + j], 1.0, value);
    }
  }

 protected:
  float Warp(size_t i, uint32_t dimension, float u) const override {
    const uint32_t j = dimension - kFirstMappedDimension;
    if (j >= kMappedDimensions) return u;
    double x;
    uint32_t bin;
    const double jacobian = map_.MapAxis(j, u, x, bin);
    if (!(used_[i] & (uint64_t(1) << j))) {  // a coordinate read twice counts once
      used_[i] |= uint64_t(1) << j;
      jacobian_[i] *= jacobian;
      bins_[i * kMappedDimensions + j] = bin;
    }
    return std::min(float(x), 0x1.fffffep-1f);
  }

 private:
  const AdaptiveMap& map_;
  mutable std::vector<double> jacobian_;
  mutable std::vector<uint64_t> used_;
  mutable std::vector<uint32_t> bins_;
};

inline void RenderWithVegasMap(Transport& transport, const SceneView& scene, const Sampler& sampler,
                               RenderTarget& target, uint32_t bins, double alpha) {
  constexpr uint32_t kTileSize = 32;
  const std::vector<double> lower(kMappedDimensions, 0.0), upper(kMappedDimensions, 1.0);
  AdaptiveMap map(lower, upper, bins);
  // Statistics per tile, merged in tile order: the same job refines the
  // same map however the tiles were shared among threads.
  const uint32_t tiles_x = (scene.FilmWidth() + kTileSize - 1) / kTileSize;
  const uint32_t tiles_y = (scene.FilmHeight() + kTileSize - 1) / kTileSize;
  std::vector<AdaptiveMap> statistics;
  const uint32_t last_refinement = alpha > 0 ? target.SamplesPerPixel() / 2 : 0;
  if (last_refinement > 0) {
    map.ClearStatistics();
    statistics.assign(size_t(tiles_x) * tiles_y, map);
  }
  RenderPasses(
      scene, target, kTileSize, 1,
      [&](uint32_t pass, uint32_t, uint32_t x0, uint32_t y0, uint32_t x1, uint32_t y1, FilmSamples& out) {
        MappedTilePoints points(sampler, map, pass, scene.FilmWidth(), scene.FilmHeight(), target.SamplesPerPixel());
        points.Reset(x0, y0, x1, y1, target.Seed());
        transport.Evaluate(scene, points, out);
        std::vector<double> luminance(points.Count(), 0.0);
        for (size_t k = 0; k < out.Count(); ++k) {
          const uint32_t i = out.point[k];
          out.rgb[k] *= float(points.Jacobian(i));
          luminance[i] += Luminance(out.rgb[k]);
        }
        target.Accumulate(out);
        if (pass + 1 <= last_refinement) {  // the map still learns
          AdaptiveMap& tile = statistics[size_t(y0 / kTileSize) * tiles_x + x0 / kTileSize];
          for (size_t i = 0; i < points.Count(); ++i) points.Train(i, luminance[i] * luminance[i], tile);
        }
      },
      [&](uint32_t pass) {
        const uint32_t done = pass + 1;
        if (done > last_refinement || (done & (done - 1)) != 0) return;  // after 1, 2, 4, 8...
        for (AdaptiveMap& tile : statistics) {
          map.Merge(tile);
          tile.ClearStatistics();
        }
        map.Refine(alpha);
      });
}

}  // namespace yarf
