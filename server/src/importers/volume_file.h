// Mitsuba's .vol grid files (the binary "VOL" version 3 of Mitsuba 0.6 and
// 3): little-endian; a 48-byte header (magic, version, encoding 1 =
// float32, nx, ny, nz, channels, the bounding box min and max), then the
// values, x fastest, channels innermost.
#pragma once

#include <cstdint>
#include <filesystem>

#include "importers/import_error.h"
#include "importers/matrix.h"
#include "importers/spectrum.h"

namespace yarf::importers {

struct VolHeader {
  int64_t nx = 0, ny = 0, nz = 0, channels = 0;
  // The bounding box the file records (Mitsuba's use_grid_bbox).
  Vec3d min, max;
};

// The header; fails at `where` when the file is not a float32 .vol grid
// holding all its values.
VolHeader ReadVolHeader(const std::filesystem::path& file, const SourceLocation& where);

// The mean of the values: per channel for 3 channels, grey for 1 (and the
// mean of all channels otherwise).
Rgb VolMean(const std::filesystem::path& file, const SourceLocation& where);

}  // namespace yarf::importers
