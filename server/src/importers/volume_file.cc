#include "importers/volume_file.h"

#include <array>
#include <cstring>
#include <fstream>
#include <vector>

namespace yarf::importers {
namespace {

constexpr size_t kHeaderBytes = 48;

uint32_t Word(const unsigned char* p) { return p[0] | p[1] << 8 | p[2] << 16 | uint32_t(p[3]) << 24; }

float Float32(const unsigned char* p) {
  const uint32_t bits = Word(p);
  float f;
  std::memcpy(&f, &bits, sizeof f);
  return f;
}

VolHeader ReadHeader(std::ifstream& in, const std::filesystem::path& file, const SourceLocation& where) {
  std::array<unsigned char, kHeaderBytes> h{};
  const std::string name = "'" + file.string() + "'";
  if (!in.read(reinterpret_cast<char*>(h.data()), h.size())) Fail(where, name + " is too short for a .vol grid");
  if (h[0] != 'V' || h[1] != 'O' || h[2] != 'L' || h[3] != 3) Fail(where, name + " is not a .vol grid (version 3)");
  if (Word(&h[4]) != 1) Fail(where, name + ": only float32 .vol grids (encoding 1) are supported");
  VolHeader header;
  header.nx = Word(&h[8]), header.ny = Word(&h[12]), header.nz = Word(&h[16]), header.channels = Word(&h[20]);
  header.min = {Float32(&h[24]), Float32(&h[28]), Float32(&h[32])};
  header.max = {Float32(&h[36]), Float32(&h[40]), Float32(&h[44])};
  if (header.nx < 1 || header.ny < 1 || header.nz < 1 || header.channels < 1 || header.channels > 6)
    Fail(where, name + ": its resolution or channel count is out of range");
  std::error_code error;
  const uint64_t bytes = std::filesystem::file_size(file, error);
  const uint64_t values = uint64_t(header.nx) * uint64_t(header.ny) * uint64_t(header.nz) * uint64_t(header.channels);
  if (error || bytes < kHeaderBytes || (bytes - kHeaderBytes) / 4 < values)
    Fail(where, name + " holds fewer values than its header says");
  return header;
}

}  // namespace

VolHeader ReadVolHeader(const std::filesystem::path& file, const SourceLocation& where) {
  std::ifstream in(file, std::ios::binary);
  if (!in) Fail(where, "cannot read '" + file.string() + "'");
  return ReadHeader(in, file, where);
}

Rgb VolMean(const std::filesystem::path& file, const SourceLocation& where) {
  std::ifstream in(file, std::ios::binary);
  if (!in) Fail(where, "cannot read '" + file.string() + "'");
  const VolHeader header = ReadHeader(in, file, where);
  const size_t channels = size_t(header.channels);
  const uint64_t voxels = uint64_t(header.nx) * uint64_t(header.ny) * uint64_t(header.nz);
  std::vector<double> sums(channels, 0.0);
  std::vector<unsigned char> block(4 * channels * 4096);
  for (uint64_t done = 0; done < voxels;) {
    const uint64_t count = std::min<uint64_t>(4096, voxels - done);
    if (!in.read(reinterpret_cast<char*>(block.data()), std::streamsize(4 * channels * count)))
      Fail(where, "cannot read '" + file.string() + "'");
    for (uint64_t i = 0; i < count; ++i)
      for (size_t c = 0; c < channels; ++c) sums[c] += Float32(&block[4 * (i * channels + c)]);
    done += count;
  }
  for (double& s : sums) s /= double(voxels);
  if (channels == 3) return {sums[0], sums[1], sums[2]};
  double all = 0;
  for (double s : sums) all += s / double(channels);
  return {all, all, all};
}

}  // namespace yarf::importers
