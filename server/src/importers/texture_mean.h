// yarf has no textures yet: a textured parameter becomes its texture's
// mean colour, an environment map its mean radiance. This reads an image
// file's mean.
#pragma once

#include <filesystem>

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

}  // namespace yarf::importers
