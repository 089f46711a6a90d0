#include "kernel/image_io.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>

#include "yarf/error.h"

namespace yarf {
namespace {

float SrgbEncode(float linear) {
  linear = std::clamp(linear, 0.0f, 1.0f);
  return linear <= 0.0031308f ? 12.92f * linear : 1.055f * std::pow(linear, 1 / 2.4f) - 0.055f;
}

}  // namespace

std::string EncodeImage(const std::vector<float>& rgb, uint32_t width, uint32_t height, ImageFormat format,
                        const std::vector<ImageLayer>& layers) {
  const bool exr = format == ImageFormat::kExr;
  const std::string name = exr ? "image.exr" : "image.png";
  std::vector<unsigned char> buffer;
  OIIO::Filesystem::IOVecOutput memory(buffer);
  auto out = OIIO::ImageOutput::create(name);
  if (!out) throw Error("image output: " + OIIO::geterror());
  const size_t layer_count = exr ? layers.size() : 0, channels = 3 * (1 + layer_count);
  OIIO::ImageSpec spec(int(width), int(height), int(channels), exr ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::UINT8);
  static constexpr const char* kRgb[] = {"R", "G", "B"};
  for (size_t l = 0; l < layer_count; ++l)
    for (size_t c = 0; c < 3; ++c) spec.channelnames[3 * (l + 1) + c] = layers[l].name + "." + kRgb[c];
  if (!out->supports("ioproxy") || !out->set_ioproxy(&memory))
    throw Error("image output: " + name + " writer cannot write to memory");
  if (!exr) spec.attribute("oiio:ColorSpace", "sRGB");
  if (!out->open(name, spec)) throw Error("image output: " + out->geterror());
  bool ok;
  if (exr) {
    // Interleaved: each pixel's R, G, B, then each layer's.
    std::vector<float> all(size_t(width) * height * channels);
    for (size_t p = 0; p < size_t(width) * height; ++p) {
      std::copy_n(&rgb[3 * p], 3, &all[channels * p]);
      for (size_t l = 0; l < layer_count; ++l) std::copy_n(&layers[l].rgb[3 * p], 3, &all[channels * p + 3 * (l + 1)]);
    }
    ok = out->write_image(OIIO::TypeDesc::FLOAT, all.data());
  } else {
    std::vector<unsigned char> bytes(rgb.size());
    for (size_t i = 0; i < rgb.size(); ++i)
      bytes[i] = static_cast<unsigned char>(std::lround(SrgbEncode(rgb[i]) * 255.0f));
    ok = out->write_image(OIIO::TypeDesc::UINT8, bytes.data());
  }
  if (!ok || !out->close()) throw Error("image output: " + out->geterror());
  return std::string(buffer.begin(), buffer.end());
}

}  // namespace yarf
