// An image file read into linear float texels (bitmap.cc). Integer
// images (8- or 16-bit PNG, JPEG, TIFF, ...) usually store colour
// gamma-encoded; a renderer must remove that encoding before it filters,
// since averaging encoded values darkens edges and distant detail
// (Mitsuba decodes its sRGB bitmaps on load, pbrt-v4 too). Float images
// (EXR, HDR, PFM) are linear already and are taken as they are.
#pragma once

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "yarf/error.h"
#include "yarf/parameters.h"

namespace yarf::textures {

// The declarations of the image file a class reads as
// props.ResolvedFile("filename"): a scene names it by `filename`, a path
// in the scene's folder, or by `asset`, the SHA-256 of an uploaded file;
// the server finds either and hands the class `filename`. Neither is
// declared required, as a scene gives one or the other; `doc` says what
// the image is and when it is needed.
inline std::vector<Parameter> ImageFileParameters(const std::string& doc) {
  return {
      Parameter::File("filename").Required().Doc(doc),
      Parameter::String("asset").Doc("the SHA-256 of an uploaded image, in place of filename"),
  };
}

// How the integer texels of a file encode linear values.
struct Encoding {
  enum class Kind { kLinear, kSrgb, kGamma };
  Kind kind = Kind::kSrgb;
  double gamma = 1;  // kGamma: linear = encoded^gamma, as pbrt's "gamma G"

  float ToLinear(float c) const {
    switch (kind) {
      case Kind::kLinear:
        return c;
      case Kind::kSrgb:
        return c <= 0.04045f ? c / 12.92f : float(std::pow((double(c) + 0.055) / 1.055, 2.4));
      case Kind::kGamma:
        return float(std::pow(double(c), gamma));
    }
    return c;
  }
};

struct LinearImage {
  int width = 0, height = 0;
  int channels = 0;           // 1 (grey) or 3 (RGB)
  std::vector<float> texels;  // row by row from the top, `channels` per texel
};

// Bounds on what one texture may hold in memory (4 bytes per channel of a
// texel, plus the MIP levels): 65536 texels a side, 2^26 in all (8192²).
inline constexpr int64_t kMaxImageSide = 65536;
inline constexpr int64_t kMaxImageTexels = int64_t(1) << 26;

// Reads the first image of `file` (named `key` in errors): a grey image,
// with or without alpha, gives 1 channel; anything else its first three
// (alpha and further channels are dropped).
inline LinearImage ReadLinearImage(const std::filesystem::path& file, const Encoding& encoding,
                                   const std::string& key) {
  // The message names the file, not the server folder it was resolved in.
  const std::string what = "property '" + key + "': the image '" + file.filename().string() + "'";
  std::error_code error;
  if (!std::filesystem::is_regular_file(file, error)) throw Error(what + " does not exist");
  auto input = OIIO::ImageInput::open(file.string());
  if (!input) throw Error(what + " cannot be read: " + OIIO::geterror());
  const OIIO::ImageSpec& spec = input->spec();
  if (spec.depth > 1) throw Error(what + " is a volume; a texture needs a 2-D image");
  if (spec.width < 1 || spec.height < 1 || spec.nchannels < 1 || spec.width > kMaxImageSide ||
      spec.height > kMaxImageSide || int64_t(spec.width) * spec.height > kMaxImageTexels)
    throw Error(what + " is " + std::to_string(spec.width) + " x " + std::to_string(spec.height) +
                " texels; a texture may have at most " + std::to_string(kMaxImageSide) + " a side and " +
                std::to_string(kMaxImageTexels) + " in all");
  LinearImage image;
  image.width = spec.width;
  image.height = spec.height;
  image.channels = spec.nchannels >= 3 ? 3 : 1;
  // A two-channel image is grey and alpha, in either order.
  const int first = spec.nchannels == 2 && spec.alpha_channel == 0 ? 1 : 0;
  image.texels.resize(size_t(image.width) * size_t(image.height) * size_t(image.channels));
  if (!input->read_image(0, 0, first, first + image.channels, OIIO::TypeFloat, image.texels.data()))
    throw Error(what + " cannot be read: " + input->geterror());

  if (!spec.format.is_floating_point() && encoding.kind != Encoding::Kind::kLinear) {
    if (spec.format == OIIO::TypeDesc::UINT8) {
      // 256 possible values: decode each once.
      std::array<float, 256> table;
      for (int i = 0; i < 256; ++i) table[i] = encoding.ToLinear(float(i) / 255.0f);
      for (float& c : image.texels) c = table[std::min(255, std::max(0, int(std::lround(c * 255.0f))))];
    } else {
      for (float& c : image.texels) c = encoding.ToLinear(std::max(0.0f, c));
    }
  }
  for (float c : image.texels)
    if (!std::isfinite(c)) throw Error(what + " has texels that are not finite numbers");
  return image;
}

}  // namespace yarf::textures
