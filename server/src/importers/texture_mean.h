// yarf has no textures yet: a textured parameter becomes its texture's
// mean colour. This reads an image file's mean.
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

// Mean linear colour of the image at `file` (a grey image gives grey, an
// alpha channel is ignored). Unreadable images fail at `where`.
Rgb ImageMeanColour(const std::filesystem::path& file, ImageEncoding encoding, double gamma,
                    const SourceLocation& where);

}  // namespace yarf::importers
