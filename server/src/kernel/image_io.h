// Encoding images to files through OpenImageIO. Kept apart from RPC code:
// OIIO's headers must not meet protobuf's in one translation unit.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace yarf {

enum class ImageFormat { kExr, kPng };

// A named image beside the main one (an arbitrary output variable):
// linear RGB [height, width, 3].
struct ImageLayer {
  std::string name;
  std::vector<float> rgb;
};

// Encodes linear RGB pixels [height, width, 3]: EXR as half floats, with
// each layer as channels NAME.R, NAME.G, NAME.B after R, G, B; PNG as
// 8-bit sRGB (without layers). Returns the file's bytes; throws Error on
// failure.
std::string EncodeImage(const std::vector<float>& rgb, uint32_t width, uint32_t height, ImageFormat format,
                        const std::vector<ImageLayer>& layers = {});

}  // namespace yarf
