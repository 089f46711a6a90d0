#include "service/job_files.h"

#include <openssl/evp.h>

#include <array>
#include <bit>
#include <cstring>
#include <fstream>
#include <string_view>
#include <utility>

#include "service/state_folder.h"
#include "yarf/error.h"

namespace yarf {
namespace {

// Each file starts with an 8-byte tag naming its kind and format version
// and ends with the SHA-256 of all the bytes before it; numbers are
// little-endian.
//   checkpoint: tag, samples_done u32, attempt u32, job number u64, film
//   image:      tag, width u32, height u32, job number u64, attempt u32,
//               pixels, variances (float32)
// samples_done stays where version 1 had it, for tools that peek at it.
constexpr std::string_view kCheckpointTag = "YARFCKP2";
constexpr std::string_view kImageTag = "YARFIMG2";
// Version 1: no owner, no checksum.
constexpr std::string_view kLegacyCheckpointTag = "YARFCKP1";
constexpr std::string_view kLegacyImageTag = "YARFIMG1";
constexpr size_t kCheckpointHeader = 16, kImageHeader = 20, kLegacyImageHeader = 8;
constexpr size_t kDigestBytes = 32;
// Larger sides are refused before anything is allocated for them.
constexpr uint32_t kMaxImageSide = 1u << 20;
static_assert(std::endian::native == std::endian::little, "job files are little-endian");

using Digest = std::array<unsigned char, kDigestBytes>;

Digest Sha256(std::string_view bytes) {
  Digest digest;
  unsigned int size = 0;
  if (EVP_Digest(bytes.data(), bytes.size(), digest.data(), &size, EVP_sha256(), nullptr) != 1 ||
      size != kDigestBytes)
    throw Error("cannot compute a SHA-256");
  return digest;
}

void PutU32(std::string& out, uint32_t value) { out.append(reinterpret_cast<const char*>(&value), sizeof value); }
void PutU64(std::string& out, uint64_t value) { out.append(reinterpret_cast<const char*>(&value), sizeof value); }

template <typename T>
T Get(std::string_view bytes, size_t offset) {
  T value;
  std::memcpy(&value, bytes.data() + offset, sizeof value);
  return value;
}

void AppendDigestAndWrite(const std::filesystem::path& path, std::string& bytes) {
  const Digest digest = Sha256(bytes);
  bytes.append(reinterpret_cast<const char*>(digest.data()), digest.size());
  WriteFileAtomically(path, bytes);
}

std::string_view KindOf(std::string_view tag) { return tag == kImageTag ? "image" : "checkpoint"; }

// The bytes after the tag; throws unless the file starts with `tag` and
// holds at least `header` bytes after it.
std::string_view Header(std::string_view bytes, std::string_view tag, std::string_view legacy_tag, size_t header,
                        const std::filesystem::path& path) {
  if (bytes.substr(0, legacy_tag.size()) == legacy_tag)
    throw Error(path.string() + " was written by an older yarfd, without its job's id and a checksum");
  if (bytes.size() < tag.size() + header || bytes.substr(0, tag.size()) != tag)
    throw Error(path.string() + " is not a yarf " + std::string(KindOf(tag)) + " file");
  return bytes.substr(tag.size());
}

// Header(), minus the digest at the end, which is checked against the
// bytes before it.
std::string_view Body(std::string_view bytes, std::string_view tag, std::string_view legacy_tag, size_t header,
                      const std::filesystem::path& path) {
  Header(bytes, tag, legacy_tag, header + kDigestBytes, path);
  const std::string_view covered = bytes.substr(0, bytes.size() - kDigestBytes);
  const Digest digest = Sha256(covered);
  if (std::memcmp(digest.data(), bytes.data() + covered.size(), kDigestBytes) != 0)
    throw Error(path.string() + " fails its checksum: it was changed or damaged after it was written");
  return covered.substr(tag.size());
}

void CheckJob(uint64_t written_for, uint64_t expected, const std::filesystem::path& path) {
  if (written_for != expected)
    throw Error(path.string() + " belongs to job number " + std::to_string(written_for) + ", not " +
                std::to_string(expected));
}

// `body` is an image's bytes after its tag.
void CheckImageOwner(std::string_view body, const JobFileOwner& owner, const std::filesystem::path& path) {
  CheckJob(Get<uint64_t>(body, 8), owner.job_number, path);
  if (const auto attempt = Get<uint32_t>(body, 16); attempt != owner.attempt)
    throw Error(path.string() + " was written by attempt " + std::to_string(attempt) + ", not by the job's last (" +
                std::to_string(owner.attempt) + ")");
}

// Throws unless an image's header gives a size a film can have: a pixel
// at least, kMaxImageSide at most.
void CheckImageSize(uint32_t width, uint32_t height, const std::filesystem::path& path) {
  if (width == 0 || height == 0 || width > kMaxImageSide || height > kMaxImageSide)
    throw Error(path.string() + " is not a yarf image file");
}

// The pixels and variances of a `width` x `height` image in `data`.
JobImage ImageOf(uint32_t width, uint32_t height, std::string_view data, const std::filesystem::path& path) {
  CheckImageSize(width, height, path);
  JobImage image{width, height, {}, {}};
  const size_t values = size_t(width) * height * 3;
  if (data.size() != 2 * values * sizeof(float))
    throw Error(path.string() + " is truncated: " + std::to_string(data.size()) + " bytes of data for " +
                std::to_string(width) + "x" + std::to_string(height) + " pixels");
  image.pixels.resize(values);
  image.variances.resize(values);
  std::memcpy(image.pixels.data(), data.data(), values * sizeof(float));
  std::memcpy(image.variances.data(), data.data() + values * sizeof(float), values * sizeof(float));
  return image;
}

}  // namespace

void WriteCheckpoint(const std::filesystem::path& path, const JobFileOwner& owner, uint32_t samples_done,
                     const std::string& film) {
  std::string bytes(kCheckpointTag);
  bytes.reserve(kCheckpointTag.size() + kCheckpointHeader + film.size() + kDigestBytes);
  PutU32(bytes, samples_done);
  PutU32(bytes, owner.attempt);
  PutU64(bytes, owner.job_number);
  bytes += film;
  AppendDigestAndWrite(path, bytes);
}

std::optional<FilmCheckpoint> ReadCheckpoint(const std::filesystem::path& path, const JobFileOwner& reader) {
  const std::optional<std::string> bytes = ReadWholeFile(path);
  if (!bytes) return std::nullopt;
  const std::string_view body = Body(*bytes, kCheckpointTag, kLegacyCheckpointTag, kCheckpointHeader, path);
  const auto samples_done = Get<uint32_t>(body, 0);
  const auto attempt = Get<uint32_t>(body, 4);
  CheckJob(Get<uint64_t>(body, 8), reader.job_number, path);
  if (attempt > reader.attempt)
    throw Error(path.string() + " was written by attempt " + std::to_string(attempt) + ", after this one (" +
                std::to_string(reader.attempt) + ")");
  try {
    return FilmCheckpoint{samples_done, attempt, Film::Load(body.substr(kCheckpointHeader))};
  } catch (const Error& e) {
    throw Error(path.string() + ": " + e.what());
  }
}

void WriteJobImage(const std::filesystem::path& path, const JobFileOwner& owner, const JobImage& image) {
  const size_t values = size_t(image.width) * image.height * 3;
  if (image.pixels.size() != values || image.variances.size() != values)
    throw Error("an image of " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                " pixels needs " + std::to_string(values) + " values");
  std::string bytes(kImageTag);
  bytes.reserve(kImageTag.size() + kImageHeader + 2 * values * sizeof(float) + kDigestBytes);
  PutU32(bytes, image.width);
  PutU32(bytes, image.height);
  PutU64(bytes, owner.job_number);
  PutU32(bytes, owner.attempt);
  for (const std::vector<float>* values : {&image.pixels, &image.variances})
    bytes.append(reinterpret_cast<const char*>(values->data()), values->size() * sizeof(float));
  AppendDigestAndWrite(path, bytes);
}

std::optional<std::pair<uint32_t, uint32_t>> ReadJobImageSize(const std::filesystem::path& path,
                                                              const JobFileOwner& owner) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    if (!std::filesystem::exists(path)) return std::nullopt;
    throw Error("cannot read " + path.string());
  }
  std::string header(kImageTag.size() + kImageHeader, '\0');
  in.read(header.data(), std::streamsize(header.size()));
  header.resize(size_t(in.gcount()));
  const std::string_view body = Header(header, kImageTag, kLegacyImageTag, kImageHeader, path);
  CheckImageOwner(body, owner, path);
  const uint32_t width = Get<uint32_t>(body, 0), height = Get<uint32_t>(body, 4);
  CheckImageSize(width, height, path);
  return std::pair(width, height);
}

std::optional<JobImage> ReadJobImage(const std::filesystem::path& path, const JobFileOwner& owner) {
  const std::optional<std::string> bytes = ReadWholeFile(path);
  if (!bytes) return std::nullopt;
  const std::string_view body = Body(*bytes, kImageTag, kLegacyImageTag, kImageHeader, path);
  CheckImageOwner(body, owner, path);
  return ImageOf(Get<uint32_t>(body, 0), Get<uint32_t>(body, 4), body.substr(kImageHeader), path);
}

bool UpgradeLegacyJobImage(const std::filesystem::path& path, const JobFileOwner& owner) {
  const std::optional<std::string> bytes = ReadWholeFile(path);
  if (!bytes || bytes->size() < kLegacyImageTag.size() + kLegacyImageHeader ||
      std::string_view(*bytes).substr(0, kLegacyImageTag.size()) != kLegacyImageTag)
    return false;
  const std::string_view body = std::string_view(*bytes).substr(kLegacyImageTag.size());
  WriteJobImage(path, owner,
                ImageOf(Get<uint32_t>(body, 0), Get<uint32_t>(body, 4), body.substr(kLegacyImageHeader), path));
  return true;
}

}  // namespace yarf
