// Shapes yarf has no primitive for, built as inline triangle meshes in
// object space (counter-clockwise seen from the side the normal points to).
#pragma once

#include <cstdint>
#include <vector>

#include "yarf/v1/scene.pb.h"

namespace yarf::importers {

// Segments of the triangle fan standing for a disk: the fan's area is
// within 0.1% of the disk's.
constexpr int kDiskSegments = 128;

// The cube [-1, 1]³, normals outward: 8 vertices, 12 triangles.
v1::Mesh CubeMesh();

// The unit disk in the z = 0 plane, normal +z, as a fan of kDiskSegments
// triangles around its centre.
v1::Mesh DiskMesh();

// An inline mesh from xyz triples and index triples.
v1::Mesh InlineMesh(const std::vector<float>& positions, const std::vector<uint32_t>& indices);

}  // namespace yarf::importers
