#include "components/tile_integrand.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <utility>

#include "yarf/error.h"

namespace yarf {
namespace {

constexpr float kBelowOne = 0x1.fffffep-1f;
// Points per transport call at least: a wavefront's batches stay large
// (a surface model in another process costs one call per bounce of each).
constexpr size_t kMinChunk = 256;

// A batch of the integrator's points as the transport's primary samples:
// coordinates 0 and 1 moved into the tile's reach, as film coordinates of
// the whole image. A path longer than the transport's Dimensions() said
// gets its further coordinates from a hash of the point and the dimension.
class BatchPoints final : public PrimarySamples {
 public:
  BatchPoints(std::span<const float> points, uint32_t dimensions, float x0, float y0, float width, float height,
              float film_width, float film_height)
      : points_(points), dimensions_(dimensions), x0_(x0), y0_(y0), width_(width), height_(height),
        film_width_(film_width), film_height_(film_height) {}

  size_t Count() const override { return points_.size() / dimensions_; }
  float Get(size_t i, uint32_t dimension) const override {
    const float* point = &points_[i * dimensions_];
    if (dimension >= dimensions_)
      return ToUnitFloat(uint32_t(Hash(std::bit_cast<uint32_t>(point[0]), std::bit_cast<uint32_t>(point[1]),
                                       std::bit_cast<uint32_t>(point[dimensions_ - 1]), dimension)));
    const float u = point[dimension];
    if (dimension == kFilmDimension) return std::min((x0_ + u * width_) / film_width_, kBelowOne);
    if (dimension == kFilmDimension + 1) return std::min((y0_ + u * height_) / film_height_, kBelowOne);
    return std::min(u, kBelowOne);
  }

 private:
  std::span<const float> points_;
  uint32_t dimensions_;
  float x0_, y0_, width_, height_, film_width_, film_height_;
};

}  // namespace

TileIntegrand::TileIntegrand(std::string transport, uint32_t dimensions, Evaluator evaluate, uint32_t film_width,
                             uint32_t film_height, const RenderTarget& target, uint32_t side)
    : transport_(std::move(transport)), dimensions_(dimensions), evaluate_(std::move(evaluate)),
      film_width_(film_width), film_height_(film_height), target_(target), side_(side),
      arena_(tbb::this_task_arena::max_concurrency()) {
  if (dimensions_ < 2)
    throw Error("transport '" + transport_ + "' has " + std::to_string(dimensions_) +
                " primary-sample dimensions: a render needs 2 for the film");
}

void TileIntegrand::SetTile(const PixelWindow& tile) {
  tile_ = tile;
  // Pixel p's filter reaches (p + 0.5 - r, p + 0.5 + r).
  const float r = target_.FilterRadius();
  const float x0 = std::max(0.0f, float(tile.x0) + 0.5f - r), x1 = std::min(float(film_width_), tile.x1 - 0.5f + r);
  const float y0 = std::max(0.0f, float(tile.y0) + 0.5f - r), y1 = std::min(float(film_height_), tile.y1 - 0.5f + r);
  reach_x0_ = x0, reach_y0_ = y0, reach_width_ = x1 - x0, reach_height_ = y1 - y0;
  area_ = reach_width_ * reach_height_;
  pixels_ = float(tile.x1 - tile.x0) * float(tile.y1 - tile.y0);
}

void TileIntegrand::Evaluate(std::span<const float> points, std::span<float> values) {
  try {
    if (target_.Cancelled()) throw Error("the render was cancelled");
    const size_t n = points.size() / dimensions_, k = OutputDimensions();
    for (size_t i = 0; i < points.size(); ++i)
      if (!(points[i] >= 0 && points[i] <= 1))
        throw Error("point " + std::to_string(i / dimensions_) + " has coordinate " +
                    std::to_string(i % dimensions_) + " = " + std::to_string(points[i]) + ", outside [0, 1]");
    std::fill(values.begin(), values.end(), 0.0f);
    const size_t threads = size_t(std::max(1, arena_.max_concurrency()));
    const size_t chunk = std::max(kMinChunk, (n + 4 * threads - 1) / (4 * threads));
    arena_.execute([&] {
      tbb::parallel_for(size_t(0), (n + chunk - 1) / chunk, [&](size_t c) {
        const size_t first = c * chunk, count = std::min(chunk, n - first);
        EvaluateChunk(points.subspan(first * dimensions_, count * dimensions_), values.subspan(first * k, count * k));
      });
    });
  } catch (const std::exception& e) {
    std::lock_guard lock(failure_mutex_);
    if (failure_.empty()) failure_ = e.what();
    throw;
  }
}

void TileIntegrand::EvaluateChunk(std::span<const float> points, std::span<float> values) const {
  const BatchPoints batch(points, dimensions_, reach_x0_, reach_y0_, reach_width_, reach_height_, float(film_width_),
                          float(film_height_));
  FilmSamples out;
  evaluate_(batch, out);
  const std::string& transport = transport_;
  if (out.splats)
    throw Error("transport '" + transport +
                "' splats its contributions anywhere on the film (its paths start at the lights), which a remote "
                "integrator cannot integrate pixel by pixel: render it with an integrator of yarfd's (mean_sample, "
                "vegas...)");
  const size_t k = OutputDimensions();
  const float r = target_.FilterRadius();
  for (size_t c = 0; c < out.Count(); ++c) {
    const uint32_t i = out.point[c];
    if (i >= batch.Count())
      throw Error("transport '" + transport + "' made a contribution of point " + std::to_string(i) +
                  " of a batch of " + std::to_string(batch.Count()));
    const float x = out.xy[2 * c], y = out.xy[2 * c + 1];
    const Vec3 rgb = out.rgb[c];
    if (!(std::isfinite(x) && std::isfinite(y) && std::isfinite(rgb.x) && std::isfinite(rgb.y) &&
          std::isfinite(rgb.z)))
      continue;  // the film leaves it out too
    // The pixels of the tile whose filters reach (x, y), as Film::Footprint.
    const float px0 = std::max(float(tile_.x0), std::ceil(x - r - 0.5f));
    const float px1 = std::min(float(tile_.x1) - 1, std::floor(x + r - 0.5f));
    const float py0 = std::max(float(tile_.y0), std::ceil(y - r - 0.5f));
    const float py1 = std::min(float(tile_.y1) - 1, std::floor(y + r - 0.5f));
    float* row = &values[size_t(i) * k];
    for (float py = py0; py <= py1; ++py)
      for (float px = px0; px <= px1; ++px) {
        const float w = target_.PixelWeight(uint32_t(px), uint32_t(py), x, y);
        if (w == 0) continue;  // a negative lobe counts
        const Vec3 value = rgb * (area_ * w);
        float* slot = row + Slot(uint32_t(px), uint32_t(py));
        slot[0] += value.x;
        slot[1] += value.y;
        slot[2] += value.z;
        row[0] += Luminance(value) / pixels_;
      }
  }
}

std::string TileIntegrand::Failure() const {
  std::lock_guard lock(failure_mutex_);
  return failure_;
}

}  // namespace yarf
