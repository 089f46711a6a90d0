// yarf has no textures yet: a textured parameter becomes its texture's
// mean colour, an environment map its mean radiance. This reads an image
// file's mean.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>

#include "importers/import_error.h"
#include "importers/spectrum.h"

namespace yarf::importers {

enum class ImageEncoding {
  kAuto,    // the file's own: sRGB for 8- and 16-bit integer images, else linear
  kLinear,  // values are linear already
  kSrgb,    // values are sRGB-encoded
};

// How much of what an image covers each pixel stands for.
enum class PixelWeight {
  kEqual,    // the same: textures, pbrt's equal-area environment maps
  kLatLong,  // a latitude-longitude map read as Mitsuba's envmap reads
             // it: row y at θ = yπ/(h-1), linear in between; a row counts
             // by the solid angle it stands for, so the mean is over
             // directions
};

// Mean linear colour of the image at `file` (a grey image gives grey, an
// alpha channel is ignored). Unreadable images fail at `where`.
Rgb ImageMeanColour(const std::filesystem::path& file, ImageEncoding encoding, double gamma,
                    const SourceLocation& where, PixelWeight weight = PixelWeight::kEqual);

// weight(x, y, width, height) of each pixel (row y = 0 at the top).
using PixelWeightFunction = std::function<double(uint64_t, uint64_t, uint64_t, uint64_t)>;

// The sum over the pixels of weight × linear colour, over the pixel count
// (not over the weights): with equal-area pixels of solid angle Ω / count,
// Ω times this is an integral over directions.
Rgb ImageWeightedSumPerPixel(const std::filesystem::path& file, ImageEncoding encoding, double gamma,
                             const SourceLocation& where, const PixelWeightFunction& weight);

}  // namespace yarf::importers
