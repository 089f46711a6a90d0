// libFuzzer entry point: texture and environment map files, read through
// OpenImageIO as the importers read them (their mean colour). The first
// byte picks the file's extension (EXR, PNG, HDR, PFM), the rest is the
// file. Contract: ImageMeanColour returns a colour or throws ImportError.
//
// OpenImageIO itself is not instrumented: what is fuzzed is that no file
// makes our reading crash, hang or allocate without bound. Left out
// before any pixel is read: files the extension's reader does not take
// (OpenImageIO would try every reader it has, DICOM's included, slowly
// and with memory that is never given back), and images over kMaxValues
// (the importer allows 2^28 values, more than the fuzzer's memory limit).
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>

#include "fuzz_file.h"
#include "importers/texture_mean.h"

namespace {

constexpr std::array<const char*, 4> kExtensions = {"exr", "png", "hdr", "pfm"};
constexpr int64_t kMaxValues = int64_t(1) << 22;

bool Fuzzable(const std::string& file) {
  auto in = OIIO::ImageInput::create(file);
  OIIO::ImageSpec spec;
  if (!in || !in->valid_file(file) || !in->open(file, spec)) return false;
  const int64_t values = int64_t(std::max(spec.width, 1)) * std::max(spec.height, 1) * std::max(spec.depth, 1) *
                         std::max(spec.nchannels, 1);
  return spec.width <= 16384 && spec.height <= 16384 && spec.depth <= 16384 && spec.nchannels <= 64 &&
         values <= kMaxValues;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  // One thread: the fuzzer measures and limits this process alone.
  OIIO::attribute("threads", 1);
  OIIO::attribute("exr_threads", 1);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const std::string name = std::string("texture.") + kExtensions[data[0] % kExtensions.size()];
  const std::string file = yarf::fuzz::InputFile(data + 1, size - 1, name).string();
  if (!Fuzzable(file)) return 0;
  const yarf::importers::SourceLocation where{"fuzz.xml", 1};
  try {
    yarf::importers::ImageMeanColour(file, yarf::importers::ImageEncoding::kAuto, 1.0, where);
    yarf::importers::ImageMeanColour(file, yarf::importers::ImageEncoding::kSrgb, 2.2, where,
                                     yarf::importers::PixelWeight::kLatLong);
  } catch (const yarf::importers::ImportError&) {
    // An unreadable image: the expected way to refuse it.
  }
  return 0;
}
