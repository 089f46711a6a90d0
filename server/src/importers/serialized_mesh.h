// Mitsuba's "serialized" mesh files: a zlib stream per shape, with a table
// of shape offsets at the end of the file.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "importers/import_error.h"

namespace yarf::importers {

struct SerializedMesh {
  std::string name;              // version 4 files name their shapes
  std::vector<float> positions;  // xyz triples
  std::vector<uint32_t> indices; // triangle triples
  // Each empty when the file has none: xyz per vertex, uv per vertex, and
  // rgb per vertex.
  std::vector<float> normals, uvs, colors;
};

// Decodes shape `shape_index` of a serialized file's bytes. Malformed or
// truncated data fails at `where` (the shape element naming the file).
SerializedMesh DecodeSerializedMesh(std::string_view bytes, uint64_t shape_index,
                                    const SourceLocation& where);

}  // namespace yarf::importers
