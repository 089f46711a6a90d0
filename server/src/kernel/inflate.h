// Compressed files: zlib streams (Mitsuba's serialized meshes) and gzip
// files (pbrt's .pbrt.gz scenes, .ply.gz meshes).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace yarf {

// Whether `bytes` start as a gzip file does.
bool IsGzip(std::string_view bytes);

struct Inflated {
  std::string bytes;
  // False when the stream holds more than the limit asked for.
  bool complete = true;
};

// The first `limit` bytes a zlib or gzip stream (the header says which;
// gzip members one after another are one file; other bytes after the end
// are not read) inflates to. Throws
// std::runtime_error on damaged or truncated data. Only what the limit
// allows is ever inflated: a small file that inflates to terabytes costs
// `limit` bytes.
Inflated Inflate(std::string_view compressed, uint64_t limit);

}  // namespace yarf
