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

// The unit disk in the z = 0 plane, normal +z, from radius `inner` (in
// [0, 1)) out and from φ = 0 to phi_max (degrees, in (0, 360]), in
// kDiskSegments steps per turn: without a hole, a fan of triangles around
// its centre, each with a centre vertex of its own (at the middle angle of
// its segment), the rim cut at φ = 0, so that interpolated uv follow the
// polar parameterisation; with one, a ring of quads. pbrt-v4's uv run
// (φ / phi_max, (1 − r) / (1 − inner)).
v1::Mesh DiskMesh(DiskUv uv, double inner = 0, double phi_max_degrees = 360);

// The zone of the unit sphere between the planes z = z_min and z = z_max
// (in [-1, 1], z_min < z_max), from φ = 0 to phi_max (degrees, in
// (0, 360]): pbrt-v4's partial sphere, with its uv (φ / phi_max, and v
// from 0 at z_min to 1 at z_max evenly in θ) and smooth normals pointing
// outward, in kCylinderSegments steps per turn of φ and per half turn of θ.
v1::Mesh SphereZoneMesh(double z_min, double z_max, double phi_max_degrees);

// The open tube of radius 1 around the z axis from z = 0 to z = 1, swept
// from φ = 0 to phi_max (degrees, in (0, 360]) in kCylinderSegments steps
// per turn: uv = (φ / phi_max, z) as Mitsuba's and pbrt's cylinders, smooth
// normals pointing outward. Tessellated: yarf has no cylinder primitive.
v1::Mesh CylinderMesh(double phi_max_degrees);

// A triangle mesh as plain arrays: xyz triples, index triples, and
// per-vertex normals (xyz) and uv (pairs), each empty or one per vertex.
struct TriangleArrays {
  std::vector<double> positions, normals, uvs;
  std::vector<uint32_t> indices;
  // How many triangles, in order, make each face of the shape it stands
  // for (a bilinear patch); empty when each triangle is a face.
  std::vector<uint32_t> face_triangles;
};

// Whether bilinear patches may be cut into cells: a twisted patch is cut
// into n × n cells, n the least whose facets lie within kBilinearTolerance
// of the patch's diagonal off its surface (at most kBilinearCells), fewer
// when the mesh would pass kBilinearTriangles triangles.
constexpr double kBilinearTolerance = 1e-3;
constexpr int kBilinearCells = 16;
constexpr size_t kBilinearTriangles = size_t(1) << 22;

// pbrt-v4's bilinear patches as triangles. Patch k has the corners p00,
// p10, p01, p11 at indices[4k..4k+3] and is the surface (1−u)(1−v)p00 +
// u(1−v)p10 + (1−u)v p01 + uv p11: a flat patch (four corners in one
// plane) becomes two triangles, a twisted one a grid of cells, wound as
// ∂p/∂u × ∂p/∂v as pbrt orients the patch. Normals and uv (either empty,
// or one per vertex of `positions`) are interpolated bilinearly as pbrt
// does; uv default to the patch's (u, v). A mesh without normals that has
// a twisted patch gets the surface's own normal at each grid point (pbrt
// shades the patch with it), so the facets do not show.
TriangleArrays BilinearPatches(const std::vector<double>& positions, const std::vector<uint32_t>& indices,
                               const std::vector<double>& normals, const std::vector<double>& uvs);

// An inline mesh from xyz triples and index triples.
v1::Mesh InlineMesh(const std::vector<float>& positions, const std::vector<uint32_t>& indices);

}  // namespace yarf::importers
