// The RGB film: a weighted-average estimate per pixel under a
// reconstruction filter, with the variance of each estimate; plus, for
// methods that start paths at the lights, a splat image: contributions
// summed under the normalised filter, divided by the number of passes.
//
// Threads may add camera samples and splats at once as long as each writes
// its own window of pixels (the windowed Add and Splat, after
// PrepareSplats); everything else wants the film to itself.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "yarf/transport.h"
#include "yarf/vecmath.h"
#include "yarf/v1/scene.pb.h"

namespace yarf {

// One axis of a separable filter: its weight at a distance from the
// pixel's centre, zero from its radius on.
class FilterAxis {
 public:
  FilterAxis(const v1::ReconstructionFilter& filter, float radius);
  float radius() const { return radius_; }
  float Weight(float d) const;
  // ∫ of the weight around `centre` over [lo, hi]: the part of a pixel's
  // filter that lies on the film.
  float Mass(float centre, float lo, float hi) const;

 private:
  v1::ReconstructionFilter::Kind kind_;
  float radius_;
  // GAUSSIAN: −1/(2σ²) and the weight at the radius, taken off.
  float gaussian_alpha_ = 0, gaussian_offset_ = 0;
  // MITCHELL: the cubic's coefficients on [0, 1] and (1, 2], highest first.
  std::array<float, 4> inner_{}, outer_{};
  // LANCZOS: the window's width.
  float lobes_ = 3;
};

class ReconstructionFilter {
 public:
  // Largest radius in pixels; beyond it a sample would touch too many pixels.
  static constexpr double kMaxRadius = 16;
  // Throws Error for a kind the proto does not name, a radius, standard
  // deviation or parameter that is not finite or out of range, or a
  // filter that does not weigh its own centre most of all its mass.
  explicit ReconstructionFilter(const v1::ReconstructionFilter& filter);
  // How far the filter reaches along either axis.
  float radius() const { return std::max(x_.radius(), y_.radius()); }
  const FilterAxis& x() const { return x_; }
  const FilterAxis& y() const { return y_; }
  float Weight(float dx, float dy) const { return x_.Weight(dx) * y_.Weight(dy); }

 private:
  ReconstructionFilter(const v1::ReconstructionFilter& filter, std::pair<float, float> radii)
      : x_(filter, radii.first), y_(filter, radii.second) {}

  FilterAxis x_, y_;
};

class Film {
 public:
  Film(uint32_t width, uint32_t height, const v1::ReconstructionFilter& filter);

  uint32_t width() const { return width_; }
  uint32_t height() const { return height_; }
  // A camera sample of radiance `value` at raster position (x, y) in pixels.
  void Add(float x, float y, Vec3 value) { Add(x, y, value, Footprint(x, y)); }
  // A contribution to the current pass's splat image.
  void Splat(float x, float y, Vec3 value);
  // The same, to the pixels of `pixels` alone, a part of the sample's
  // Footprint: a sample whose filter reaches several windows is added to
  // each of them in turn, by writers that each hold the lock of one.
  void Add(float x, float y, Vec3 value, const PixelWindow& pixels);
  // Needs PrepareSplats() first.
  void Splat(float x, float y, Vec3 value, const PixelWindow& pixels);
  // Makes the splat images and the border masses (once; later calls do
  // nothing), so that windowed splats from many threads only write pixels.
  void PrepareSplats();
  // Makes the border masses alone (once), for PixelWeight.
  void PrepareMasses();
  // The filter's reach in pixels from a pixel's centre, along each axis.
  float FilterRadius() const { return filter_.radius(); }
  // The weight radiance at raster position (x, y) has in the value of
  // pixel (px, py): the filter around the pixel's centre over the
  // filter's mass on the film (as a splat is spread), so that a pixel's
  // weights integrate to 1 over the film and its camera samples converge
  // to ∫ L·weight. Needs PrepareMasses() first.
  float PixelWeight(uint32_t px, uint32_t py, float x, float y) const {
    return filter_.Weight(float(px) + 0.5f - x, float(py) + 0.5f - y) / (column_mass_[px] * row_mass_[py]);
  }
  // An estimate of pixel (px, py)'s value from `samples` samples and the
  // variance of that estimate, from an integrator that estimates whole
  // pixels itself: it counts as `samples` camera samples of weight 1 with
  // that mean and that variance of their mean, so that the pixel shows
  // it, estimates of the same pixel average by their samples, and a
  // checkpoint saves it as it saves samples. A variance needs at least 2
  // samples (a pixel of one sample has none, as with camera samples); a
  // value or variance that is not finite is left out.
  void AddEstimate(uint32_t px, uint32_t py, Vec3 value, Vec3 variance, uint32_t samples);
  // The pixels a sample at raster position (x, y) may add to under the
  // filter (empty for a position that is not finite): at most
  // kMaxFootprintSide along each axis.
  PixelWindow Footprint(float x, float y) const;
  static constexpr uint32_t kMaxFootprintSide = 2 * uint32_t(ReconstructionFilter::kMaxRadius) + 1;
  // Closes a sample pass of `samples` samples per pixel (passes of W×H
  // points each): its splat image over `samples` becomes one more
  // independent estimate of the pixels' splat values.
  void EndPass(uint32_t samples = 1);
  // Pixel estimates and their variances, row-major [height, width, 3].
  std::vector<float> Pixels() const;
  std::vector<float> Variances() const;

  // The film's whole state (accumulators, splat images, pass count and
  // filter) as bytes, for a checkpoint a render can resume from...
  std::string Save() const;
  // ...and back; throws Error for bytes that are not a saved film.
  static Film Load(std::string_view bytes);

 private:
  struct Pixel {
    double weight = 0, weight_sq = 0;
    double sum[3] = {0, 0, 0};      // Σ w L
    double sum_wsq[3] = {0, 0, 0};  // Σ w² L
    double sum_sq[3] = {0, 0, 0};   // Σ w² L²
  };
  // Splat images: the open pass, and over closed passes Σ and Σ of
  // squares (allocated with the first splat).
  struct Splats {
    std::vector<double> pass, sum, sum_sq;
    uint32_t passes = 0;
  };

  // Calls visit(pixel index, column, row, weight) for the pixels of
  // `pixels` (a part of Footprint(x, y)) under the filter around (x, y).
  template <typename Visit>
  void ForEachPixelInFilter(float x, float y, const PixelWindow& pixels, Visit&& visit) const;

  uint32_t width_, height_;
  v1::ReconstructionFilter filter_spec_;  // kept for Save
  ReconstructionFilter filter_;
  // Per column and per row, the mass of a pixel's filter on the film:
  // splats there are divided by it, as camera samples are by their
  // weights, so that a pixel at the border estimates its own average too
  // (made at the first splat or pixel weight: other films need none).
  std::vector<float> column_mass_, row_mass_;
  std::vector<Pixel> pixels_;
  Splats splats_;
  uint32_t passes_ = 0;
};

}  // namespace yarf
