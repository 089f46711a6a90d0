// A tile of a job's film as a Function over its transport's primary
// sample space: what Remote<Integrator>::Render lends a numerical
// integrator in another process, one tile at a time, so that the
// integrator estimates every pixel of the tile at once.
//
// Input: points of [0,1]^d, d = the transport's Dimensions(). Coordinates
// 0 and 1 span the tile's reach on the film, its pixels widened by the
// filter's radius less half a pixel (the tile itself for the box filter),
// cut at the film's edges; the others go to the transport as they are.
//
// Output, per point: first the luminance over the tile, then R, G, B of
// each pixel of a side × side tile, row by row (a smaller tile at the
// film's edge leaves the rest 0). A contribution L the transport makes
// at raster position (x, y) adds A·w_p(x, y)·L to pixel p, with A the
// reach's area in pixels and w_p the film's RenderTarget::PixelWeight, so
// that the integral over the unit cube is each pixel's value under the
// film's filter (for the box filter: L times the tile's pixel count in
// the pixel the point falls in, whose integral is the pixel's mean
// radiance), the value its camera samples converge to. The first output
// integrates to the mean luminance of the tile's pixels: an integrator
// that adapts to its first output (vegas) follows the whole tile.
//
// Only camera samples can be integrated pixel by pixel: a transport whose
// contributions are splats (light paths, FilmSamples::splats) fails the
// evaluation.
#pragma once

#include <tbb/task_arena.h>

#include <functional>
#include <mutex>
#include <string>

#include "yarf/math.h"
#include "yarf/transport.h"

namespace yarf {

class TileIntegrand final : public Function {
 public:
  // The transport's Evaluate on the job's scene; safe to call from many
  // threads at once.
  using Evaluator = std::function<void(const PrimarySamples&, FilmSamples&)>;
  // The transport by its class name (for errors) and its Dimensions(),
  // over a film_width × film_height film whose target takes the
  // estimates. Evaluates with as many threads as the arena of the
  // constructing thread allows (the job's), whichever thread calls Evaluate.
  TileIntegrand(std::string transport, uint32_t dimensions, Evaluator evaluate, uint32_t film_width,
                uint32_t film_height, const RenderTarget& target, uint32_t side);

  // The pixels the next integration estimates, at most side × side.
  void SetTile(const PixelWindow& tile);
  // Where R, G, B of pixel (px, py) of the tile are among the outputs.
  size_t Slot(uint32_t px, uint32_t py) const { return 1 + 3 * (size_t(py - tile_.y0) * side_ + (px - tile_.x0)); }

  uint32_t InputDimensions() const override { return dimensions_; }
  uint32_t OutputDimensions() const override { return 1 + 3 * side_ * side_; }
  // Throws Error for a point outside the unit cube, a splat, a transport's
  // own error, or once the target is cancelled.
  void Evaluate(std::span<const float> points, std::span<float> values) override;

  // The first error an evaluation threw, empty if none did: the cause of a
  // failed integration, which the component reports only second-hand.
  std::string Failure() const;

 private:
  void EvaluateChunk(std::span<const float> points, std::span<float> values) const;

  const std::string transport_;
  const uint32_t dimensions_;
  const Evaluator evaluate_;
  const uint32_t film_width_, film_height_;
  const RenderTarget& target_;
  const uint32_t side_;
  tbb::task_arena arena_;
  PixelWindow tile_{0, 0, 0, 0};
  // The tile's reach in raster coordinates, its area and pixel count.
  float reach_x0_ = 0, reach_y0_ = 0, reach_width_ = 0, reach_height_ = 0;
  float area_ = 0;
  float pixels_ = 0;
  mutable std::mutex failure_mutex_;
  std::string failure_;
};

}  // namespace yarf
