#include "kernel/inflate.h"

#include <zlib.h>

#include <algorithm>
#include <climits>
#include <stdexcept>

namespace yarf {

bool IsGzip(std::string_view bytes) {
  return bytes.size() >= 2 && static_cast<unsigned char>(bytes[0]) == 0x1f &&
         static_cast<unsigned char>(bytes[1]) == 0x8b;
}

namespace {

// zlib's stream state, ended however the inflation ends.
class InflateStream {
 public:
  InflateStream() {
    // 32 + 15: a zlib or a gzip header, detected; the largest window.
    if (inflateInit2(&stream_, 32 + 15) != Z_OK) throw std::runtime_error("cannot start zlib");
  }
  ~InflateStream() { inflateEnd(&stream_); }
  InflateStream(const InflateStream&) = delete;
  InflateStream& operator=(const InflateStream&) = delete;

  z_stream* operator->() { return &stream_; }
  z_stream* get() { return &stream_; }

 private:
  z_stream stream_{};
};

}  // namespace

Inflated Inflate(std::string_view compressed, uint64_t limit) {
  InflateStream stream;
  Inflated out;
  const bool gzip = IsGzip(compressed);
  char buffer[1 << 16];
  // zlib counts input in 32-bit units: feed it in pieces.
  const auto feed = [&] {
    const size_t piece = std::min<size_t>(compressed.size(), UINT_MAX);
    stream->next_in = reinterpret_cast<Bytef*>(const_cast<char*>(compressed.data()));
    stream->avail_in = uInt(piece);
    compressed.remove_prefix(piece);
  };
  feed();
  // The input not yet inflated, in the piece zlib holds.
  const auto rest = [&] { return std::string_view(reinterpret_cast<const char*>(stream->next_in), stream->avail_in); };
  for (;;) {
    if (out.bytes.size() == limit) {
      // Full: complete only if nothing is left to inflate.
      stream->next_out = reinterpret_cast<Bytef*>(buffer);
      stream->avail_out = 1;
      const int status = inflate(stream.get(), Z_NO_FLUSH);
      const bool more_members = gzip && (IsGzip(rest()) || !compressed.empty());
      out.complete = status == Z_STREAM_END && stream->avail_out == 1 && !more_members;
      return out;
    }
    stream->next_out = reinterpret_cast<Bytef*>(buffer);
    stream->avail_out = uInt(std::min<uint64_t>(sizeof(buffer), limit - out.bytes.size()));
    const uInt asked = stream->avail_out;
    const int status = inflate(stream.get(), Z_NO_FLUSH);
    out.bytes.append(buffer, asked - stream->avail_out);
    if (status == Z_STREAM_END) {
      // Another gzip member may follow; what follows a zlib stream is not its own.
      if (stream->avail_in == 0 && !compressed.empty()) feed();
      if (!gzip || !IsGzip(rest())) return out;
      if (inflateReset(stream.get()) != Z_OK) throw std::runtime_error("corrupt compressed data");
      continue;
    }
    if (status == Z_OK && stream->avail_in == 0 && !compressed.empty()) {
      feed();
      continue;
    }
    // No input left and no output made: the stream is cut short.
    if (status != Z_OK || (stream->avail_in == 0 && stream->avail_out != 0))
      throw std::runtime_error(status == Z_OK || status == Z_BUF_ERROR ? "truncated compressed data"
                                                                       : "corrupt compressed data");
  }
}

}  // namespace yarf
