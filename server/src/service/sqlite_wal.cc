#include "service/sqlite_wal.h"

#include <array>
#include <cstdint>
#include <fstream>
#include <string_view>
#include <vector>

#include "yarf/error.h"

namespace yarf {
namespace {

// https://www.sqlite.org/fileformat.html#the_write_ahead_log
constexpr uint32_t kWalMagic = 0x377f0682;  // | 1: checksums of big-endian words
constexpr uint32_t kWalVersion = 3007000;
constexpr size_t kWalHeaderBytes = 32, kFrameHeaderBytes = 24;

uint32_t BigEndian32(const unsigned char* p) {
  return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 | uint32_t(p[3]);
}
uint32_t LittleEndian32(const unsigned char* p) {
  return uint32_t(p[3]) << 24 | uint32_t(p[2]) << 16 | uint32_t(p[1]) << 8 | uint32_t(p[0]);
}

// SQLite's running checksum of a WAL: two sums over 32-bit words.
class Checksum {
 public:
  explicit Checksum(bool big_endian_words) : big_endian_(big_endian_words) {}
  void Add(const unsigned char* bytes, size_t size) {
    for (size_t i = 0; i + 8 <= size; i += 8) {
      s1_ += Word(bytes + i) + s2_;
      s2_ += Word(bytes + i + 4) + s1_;
    }
  }
  bool Matches(const unsigned char* stored) const {
    return BigEndian32(stored) == s1_ && BigEndian32(stored + 4) == s2_;
  }

 private:
  uint32_t Word(const unsigned char* p) const { return big_endian_ ? BigEndian32(p) : LittleEndian32(p); }
  bool big_endian_;
  uint32_t s1_ = 0, s2_ = 0;
};

bool SameSalts(const unsigned char* frame, const unsigned char* header) {
  return BigEndian32(frame + 8) == BigEndian32(header + 16) && BigEndian32(frame + 12) == BigEndian32(header + 20);
}

bool IsCommit(const unsigned char* frame) { return BigEndian32(frame + 4) != 0; }

}  // namespace

std::optional<std::string> WalDamage(const std::filesystem::path& wal) {
  std::ifstream in(wal, std::ios::binary);
  if (!in) {
    if (!std::filesystem::exists(wal)) return std::nullopt;
    throw Error("cannot read " + wal.string());
  }
  std::array<unsigned char, kWalHeaderBytes> header{};
  in.read(reinterpret_cast<char*>(header.data()), header.size());
  // Shorter than its header: SQLite was cut off before it wrote a frame.
  if (size_t(in.gcount()) < header.size()) return std::nullopt;
  const bool has_frames = in.peek() != std::ifstream::traits_type::eof();
  const uint32_t magic = BigEndian32(header.data()), page_size = BigEndian32(header.data() + 8);
  Checksum sum(magic & 1);
  sum.Add(header.data(), 24);
  if ((magic & ~1u) != kWalMagic || BigEndian32(header.data() + 4) != kWalVersion || page_size < 512 ||
      page_size > 65536 || (page_size & (page_size - 1)) != 0 || !sum.Matches(header.data() + 24)) {
    if (!has_frames) return std::nullopt;
    return wal.string() + " has a damaged header: SQLite would ignore the whole log and every transaction in it";
  }
  // Frames of this log carry its salts; frames after the first one that
  // does not are left over from an earlier log, overwritten only in part.
  std::vector<unsigned char> frame(kFrameHeaderBytes + page_size);
  uint64_t index = 0, damaged_at = 0;
  while (in.read(reinterpret_cast<char*>(frame.data()), std::streamsize(frame.size()))) {
    ++index;
    if (damaged_at == 0) {
      sum.Add(frame.data(), 8);
      sum.Add(frame.data() + kFrameHeaderBytes, page_size);
      if (!SameSalts(frame.data(), header.data())) return std::nullopt;  // the end of this log
      if (BigEndian32(frame.data()) == 0 || !sum.Matches(frame.data() + 16)) damaged_at = index;
    } else if (SameSalts(frame.data(), header.data()) && IsCommit(frame.data())) {
      return wal.string() + " is damaged at frame " + std::to_string(damaged_at) + " of " + std::to_string(index) +
             ", before a committed transaction: SQLite would drop it and every transaction after the damage";
    }
  }
  if (in.bad()) throw Error("cannot read " + wal.string());
  return std::nullopt;
}

bool InWalMode(const std::filesystem::path& database) {
  std::ifstream in(database, std::ios::binary);
  std::array<char, 20> header{};
  in.read(header.data(), header.size());
  if (size_t(in.gcount()) < header.size() || std::string_view(header.data(), 16) != std::string_view("SQLite format 3\0", 16))
    return false;
  // The file format's write and read versions: 2 for WAL.
  return header[18] == 2 && header[19] == 2;
}

}  // namespace yarf
