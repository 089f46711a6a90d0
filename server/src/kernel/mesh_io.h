// Triangle meshes from OBJ (tinyobjloader) and PLY files held in memory.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "yarf/vecmath.h"

namespace yarf {

struct TriangleMesh {
  std::vector<Vec3> positions;
  // Three indices per triangle.
  std::vector<uint32_t> indices;

  size_t TriangleCount() const { return indices.size() / 3; }
};

// Parses `bytes` as `format` ("obj" or "ply"); throws Error naming `name`
// on malformed input. Polygons are split into triangles.
TriangleMesh ParseMesh(std::string_view bytes, std::string_view format, const std::string& name);

// Throws Error unless every index is in range and every position finite.
void ValidateMesh(const TriangleMesh& mesh, const std::string& name);

}  // namespace yarf
