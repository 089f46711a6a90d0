#include "importers/mesh_shapes.h"

#include <cmath>

namespace yarf::importers {

v1::Mesh InlineMesh(const std::vector<float>& positions, const std::vector<uint32_t>& indices) {
  v1::Mesh mesh;
  mesh.mutable_positions()->Add(positions.begin(), positions.end());
  mesh.mutable_indices()->Add(indices.begin(), indices.end());
  return mesh;
}

v1::Mesh CubeMesh() {
  // Vertex i has coordinates (±1, ±1, ±1) from the bits of i (x: 1, y: 2, z: 4).
  std::vector<float> positions;
  for (int i = 0; i < 8; ++i)
    for (int bit : {1, 2, 4}) positions.push_back(i & bit ? 1.0f : -1.0f);
  const std::vector<uint32_t> indices = {
      0, 2, 3, 0, 3, 1,  // z = -1
      4, 5, 7, 4, 7, 6,  // z = +1
      0, 1, 5, 0, 5, 4,  // y = -1
      2, 6, 7, 2, 7, 3,  // y = +1
      0, 4, 6, 0, 6, 2,  // x = -1
      1, 3, 7, 1, 7, 5,  // x = +1
  };
  return InlineMesh(positions, indices);
}

v1::Mesh DiskMesh() {
  std::vector<float> positions = {0, 0, 0};
  std::vector<uint32_t> indices;
  for (int k = 0; k < kDiskSegments; ++k) {
    const double phi = 2 * 3.14159265358979323846 * k / kDiskSegments;
    positions.insert(positions.end(), {float(std::cos(phi)), float(std::sin(phi)), 0.0f});
    indices.insert(indices.end(), {0u, uint32_t(1 + k), uint32_t(1 + (k + 1) % kDiskSegments)});
  }
  return InlineMesh(positions, indices);
}

}  // namespace yarf::importers
