// Shapes yarf has no primitive for, built as inline triangle meshes in
// object space (counter-clockwise seen from the side the normal points to),
// with the texture coordinates and normals of the renderer they come from.
#pragma once

#include <cstdint>
#include <vector>

#include "yarf/v1/scene.pb.h"

namespace yarf::importers {

// Segments of the triangle fan standing for a disk, and around the tube
// standing for a cylinder: the fan's area is within 0.1% of the disk's.
constexpr int kDiskSegments = 128;
constexpr int kCylinderSegments = 128;

// Mitsuba's cube [-1, 1]³: each face its own four vertices with the flat
// normal (outward) and uv over [0, 1]², laid out as Mitsuba's cube lays
// them; 24 vertices, 12 triangles.
v1::Mesh CubeMesh();

// How a disk's surface is parameterised.
enum class DiskUv {
  kMitsuba,  // (r, φ/2π), φ from +x toward +y (Mitsuba's disk)
  kPbrt,     // (φ/2π, 1 − r) (pbrt-v4's disk of inner radius 0)
};

// The unit disk in the z = 0 plane, normal +z, as a fan of kDiskSegments
// triangles around its centre. Each triangle has a centre vertex of its
// own (at the middle angle of its segment) and the rim is cut at φ = 0,
// so that interpolated uv follow the polar parameterisation.
v1::Mesh DiskMesh(DiskUv uv);

// The open tube of radius 1 around the z axis from z = 0 to z = 1, swept
// from φ = 0 to phi_max (degrees, in (0, 360]) in kCylinderSegments steps
// per turn: uv = (φ / phi_max, z) as Mitsuba's and pbrt's cylinders, smooth
// normals pointing outward. Tessellated: yarf has no cylinder primitive.
v1::Mesh CylinderMesh(double phi_max_degrees);

// An inline mesh from xyz triples and index triples.
v1::Mesh InlineMesh(const std::vector<float>& positions, const std::vector<uint32_t>& indices);

}  // namespace yarf::importers
