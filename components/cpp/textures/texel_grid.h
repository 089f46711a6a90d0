// An image's texels in memory, looked up without a MIP map: the texel
// containing a point, or the four around it blended (bitmap.cc's
// "nearest" and "bilinear", Mitsuba's and pbrt-v4's defaults). The
// conventions are OpenImageIO's TextureSystem's, which looks up the
// MIP-mapped filters: texel i's centre at (i + 0.5) / size, v = 0 at the
// top row, and its four wraps. Read from memory, a lookup costs a few
// nanoseconds, against OIIO's hundreds through its tile cache.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>

#include "linear_image.h"

namespace yarf::textures {

// Where a lookup outside [0, 1] goes.
enum class Wrap { kRepeat, kMirror, kClamp, kBlack };

class TexelGrid {
 public:
  TexelGrid(LinearImage image, Wrap wrap) : image_(std::move(image)), wrap_(wrap) {}

  // Each writes the image's channels to `out`: 0 where (s, t) is not finite,
  // or for a texel outside the image under Wrap::kBlack.
  void Nearest(double s, double t, float* out) const {
    if (!(std::isfinite(s) && std::isfinite(t))) return Black(out);
    const int64_t x = Wrapped(int64_t(std::floor(Near(s * image_.width))), image_.width);
    const int64_t y = Wrapped(int64_t(std::floor(Near(t * image_.height))), image_.height);
    if (x < 0 || y < 0) return Black(out);
    const float* texel = Texel(x, y);
    for (int c = 0; c < image_.channels; ++c) out[c] = texel[c];
  }

  void Bilinear(double s, double t, float* out) const {
    if (!(std::isfinite(s) && std::isfinite(t))) return Black(out);
    const double x = Near(s * image_.width - 0.5), y = Near(t * image_.height - 0.5);
    const int64_t x0 = int64_t(std::floor(x)), y0 = int64_t(std::floor(y));
    const float fx = float(x - double(x0)), fy = float(y - double(y0));
    // The two columns and rows around (s, t), wrapped once each.
    const int64_t columns[2] = {Wrapped(x0, image_.width), Wrapped(x0 + 1, image_.width)};
    const int64_t rows[2] = {Wrapped(y0, image_.height), Wrapped(y0 + 1, image_.height)};
    const float column_weight[2] = {1 - fx, fx}, row_weight[2] = {1 - fy, fy};
    Black(out);
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) {
        if (columns[i] < 0 || rows[j] < 0) continue;  // black
        const float* texel = Texel(columns[i], rows[j]);
        const float w = column_weight[i] * row_weight[j];
        for (int c = 0; c < image_.channels; ++c) out[c] += w * texel[c];
      }
  }

 private:
  void Black(float* out) const { std::fill_n(out, image_.channels, 0.0f); }

  // A finite texel coordinate kept within ±2^40: beyond, every wrap gives
  // a texel as meaningless as the lookup, and its index fits an int64_t.
  static double Near(double x) {
    constexpr double kFar = 1099511627776.0;
    return std::clamp(x, -kFar, kFar);
  }

  // Index i of an axis of `size` texels, wrapped; -1 outside under kBlack.
  int64_t Wrapped(int64_t i, int64_t size) const {
    if (i >= 0 && i < size) return i;
    switch (wrap_) {
      case Wrap::kRepeat:
        return (i % size + size) % size;
      case Wrap::kMirror: {
        // Reflected about the image's edges: -1 is 0, -2 is 1, size is size - 1.
        const int64_t folded = i < 0 ? -i - 1 : i;
        const int64_t period = folded / size, within = folded % size;
        return period % 2 == 0 ? within : size - 1 - within;
      }
      case Wrap::kClamp:
        return std::clamp<int64_t>(i, 0, size - 1);
      case Wrap::kBlack:
        break;
    }
    return -1;
  }

  // Texel (x, y) of the image, both wrapped already.
  const float* Texel(int64_t x, int64_t y) const {
    return &image_.texels[(size_t(y) * size_t(image_.width) + size_t(x)) * size_t(image_.channels)];
  }

  LinearImage image_;
  Wrap wrap_;
};

}  // namespace yarf::textures
