// Encoding images to files through OpenImageIO. Kept apart from RPC code:
// OIIO's headers must not meet protobuf's in one translation unit.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace yarf {

enum class ImageFormat { kExr, kPng };

// Encodes linear RGB pixels [height, width, 3]: EXR as half floats, PNG as
// 8-bit sRGB. Returns the file's bytes; throws Error on failure.
std::string EncodeImage(const std::vector<float>& rgb, uint32_t width, uint32_t height,
                        ImageFormat format);

}  // namespace yarf
