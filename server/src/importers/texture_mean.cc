#include "importers/texture_mean.h"

#include <OpenImageIO/imageio.h>

#include <cmath>
#include <vector>

namespace yarf::importers {
namespace {

double SrgbToLinear(double v) { return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); }

// Images beyond this many values are refused (a tiled one is read whole).
constexpr uint64_t kMaxValues = uint64_t(1) << 28, kMaxSide = uint64_t(1) << 20;

struct WeightedSum {
  Rgb sum;
  double weights = 0;
  uint64_t pixels = 0;
};

// Σ weight × linear colour and Σ weight over the pixels.
WeightedSum SumPixels(const std::filesystem::path& file, ImageEncoding encoding, double gamma,
                      const SourceLocation& where, const PixelWeightFunction& pixel_weight) {
  auto in = OIIO::ImageInput::open(file.string());
  if (!in) Fail(where, "cannot read image '" + file.string() + "': " + OIIO::geterror());
  const OIIO::ImageSpec& spec = in->spec();
  const uint64_t width = uint64_t(std::max(spec.width, 0)), height = uint64_t(std::max(spec.height, 0));
  const uint64_t depth = uint64_t(std::max(spec.depth, 1));
  if (width > kMaxSide || height > kMaxSide || depth > kMaxSide)
    Fail(where, "image '" + file.string() + "' is too large");
  const uint64_t count = width * height * depth;
  const int channels = spec.nchannels;
  if (count == 0 || channels <= 0 || channels > 64 || count * uint64_t(channels) > kMaxValues)
    Fail(where, "image '" + file.string() + "' is empty or too large");
  // Scanline images are read a row at a time; tiled ones whole.
  const bool rows = spec.tile_width == 0 && spec.depth <= 1;
  std::vector<float> pixels(rows ? width * channels : count * channels);
  auto read = [&](int y) {
    return rows ? in->read_scanline(y, 0, OIIO::TypeDesc::FLOAT, pixels.data())
                : in->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, pixels.data());
  };
  bool srgb = encoding == ImageEncoding::kSrgb;
  if (encoding == ImageEncoding::kAuto) {
    const std::string space = spec.get_string_attribute("oiio:ColorSpace");
    srgb = space == "sRGB" || (space.empty() && (spec.format == OIIO::TypeDesc::UINT8 ||
                                                 spec.format == OIIO::TypeDesc::UINT16));
  }
  const int colour_channels = channels >= 3 ? 3 : 1;
  double sum[3] = {0, 0, 0}, total = 0;
  for (uint64_t pass = 0; pass < (rows ? height : 1); ++pass) {
    if (!read(spec.y + int(pass))) Fail(where, "cannot read image '" + file.string() + "': " + in->geterror());
    const uint64_t n = rows ? width : count;
    for (uint64_t p = 0; p < n; ++p) {
      const double w = pixel_weight(p % width, rows ? pass : p / width % height, width, height);
      total += w;
      for (int c = 0; c < colour_channels; ++c) {
        double v = pixels[p * channels + c];
        if (!std::isfinite(v)) v = 0;
        if (srgb) v = SrgbToLinear(v);
        if (gamma != 1) v = std::pow(std::max(v, 0.0), gamma);
        sum[c] += w * v;
      }
    }
  }
  if (colour_channels == 1) sum[1] = sum[2] = sum[0];
  return {{sum[0], sum[1], sum[2]}, total, rows ? width * height : count};
}

}  // namespace

Rgb ImageMeanColour(const std::filesystem::path& file, ImageEncoding encoding, double gamma,
                    const SourceLocation& where, PixelWeight weight) {
  // The weight of the pixels of row y: for a latitude-longitude map, the
  // integral of sin θ times the row's hat of linear interpolation (width
  // d on either side; half a hat at the poles).
  const auto row_weight = [weight](uint64_t, uint64_t y, uint64_t, uint64_t height) {
    if (weight == PixelWeight::kEqual || height < 2) return 1.0;
    const double d = M_PI / double(height - 1);
    if (y == 0 || y == height - 1) return 1 - std::sin(d) / d;
    return 4 * std::sin(double(y) * d) * std::pow(std::sin(d / 2), 2) / d;  // 1 - cos d = 2 sin²(d/2)
  };
  const WeightedSum s = SumPixels(file, encoding, gamma, where, row_weight);
  return s.sum * (1 / s.weights);
}

Rgb ImageWeightedSumPerPixel(const std::filesystem::path& file, ImageEncoding encoding, double gamma,
                             const SourceLocation& where, const PixelWeightFunction& weight) {
  const WeightedSum s = SumPixels(file, encoding, gamma, where, weight);
  return s.sum * (1 / double(s.pixels));
}

}  // namespace yarf::importers
