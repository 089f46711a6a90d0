#include "service/job_files.h"

#include <bit>
#include <cstring>
#include <fstream>
#include <string_view>

#include "service/state_folder.h"
#include "yarf/error.h"

namespace yarf {
namespace {

// Each file starts with an 8-byte tag naming its kind and format version;
// numbers are little-endian.
constexpr std::string_view kCheckpointTag = "YARFCKP1";
constexpr std::string_view kImageTag = "YARFIMG1";
static_assert(std::endian::native == std::endian::little, "job files are little-endian");

void PutU32(std::string& out, uint32_t value) { out.append(reinterpret_cast<const char*>(&value), sizeof value); }

uint32_t GetU32(std::string_view bytes, size_t offset) {
  uint32_t value;
  std::memcpy(&value, bytes.data() + offset, sizeof value);
  return value;
}

// The bytes after the tag; throws unless the file starts with `tag` and
// holds at least `header` bytes after it.
std::string_view Body(std::string_view bytes, std::string_view tag, size_t header,
                      const std::filesystem::path& path) {
  if (bytes.size() < tag.size() + header || bytes.substr(0, tag.size()) != tag)
    throw Error(path.string() + " is not a yarf " + (tag == kImageTag ? "image" : "checkpoint") + " file");
  return bytes.substr(tag.size());
}

}  // namespace

void WriteCheckpoint(const std::filesystem::path& path, uint32_t samples_done, const std::string& film) {
  std::string bytes(kCheckpointTag);
  bytes.reserve(kCheckpointTag.size() + 4 + film.size());
  PutU32(bytes, samples_done);
  bytes += film;
  WriteFileAtomically(path, bytes);
}

std::optional<FilmCheckpoint> ReadCheckpoint(const std::filesystem::path& path) {
  const std::optional<std::string> bytes = ReadWholeFile(path);
  if (!bytes) return std::nullopt;
  const std::string_view body = Body(*bytes, kCheckpointTag, 4, path);
  try {
    return FilmCheckpoint{GetU32(body, 0), Film::Load(body.substr(4))};
  } catch (const Error& e) {
    throw Error(path.string() + ": " + e.what());
  }
}

void WriteJobImage(const std::filesystem::path& path, const JobImage& image) {
  const size_t values = size_t(image.width) * image.height * 3;
  if (image.pixels.size() != values || image.variances.size() != values)
    throw Error("an image of " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                " pixels needs " + std::to_string(values) + " values");
  std::string bytes(kImageTag);
  PutU32(bytes, image.width);
  PutU32(bytes, image.height);
  for (const std::vector<float>* values : {&image.pixels, &image.variances})
    bytes.append(reinterpret_cast<const char*>(values->data()), values->size() * sizeof(float));
  WriteFileAtomically(path, bytes);
}

std::optional<std::pair<uint32_t, uint32_t>> ReadJobImageSize(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    if (!std::filesystem::exists(path)) return std::nullopt;
    throw Error("cannot read " + path.string());
  }
  std::string header(kImageTag.size() + 8, '\0');
  in.read(header.data(), std::streamsize(header.size()));
  header.resize(size_t(in.gcount()));
  const std::string_view body = Body(header, kImageTag, 8, path);
  return std::pair(GetU32(body, 0), GetU32(body, 4));
}

std::optional<JobImage> ReadJobImage(const std::filesystem::path& path) {
  const std::optional<std::string> bytes = ReadWholeFile(path);
  if (!bytes) return std::nullopt;
  const std::string_view body = Body(*bytes, kImageTag, 8, path);
  JobImage image;
  image.width = GetU32(body, 0);
  image.height = GetU32(body, 4);
  if (image.width > (1u << 20) || image.height > (1u << 20)) throw Error(path.string() + " is not a yarf image file");
  const size_t values = size_t(image.width) * image.height * 3;
  if (body.size() - 8 != 2 * values * sizeof(float))
    throw Error(path.string() + " is truncated: " + std::to_string(body.size() - 8) + " bytes of data for " +
                std::to_string(image.width) + "x" + std::to_string(image.height) + " pixels");
  image.pixels.resize(values);
  image.variances.resize(values);
  std::memcpy(image.pixels.data(), body.data() + 8, values * sizeof(float));
  std::memcpy(image.variances.data(), body.data() + 8 + values * sizeof(float), values * sizeof(float));
  return image;
}

}  // namespace yarf
