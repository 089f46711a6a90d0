// Triangle meshes from OBJ (tinyobjloader) and PLY files held in memory.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "yarf/vecmath.h"

namespace yarf {

// A named value per vertex or per triangle (Mitsuba's mesh attributes):
// "vertex_NAME" or "face_NAME", 1 or 3 channels.
struct MeshAttribute {
  std::string name;
  uint32_t channels = 1;
  // channels × (vertex or triangle count) values.
  std::vector<float> values;

  bool PerFace() const { return name.starts_with("face_"); }
};

struct TriangleMesh {
  std::vector<Vec3> positions;
  // Three indices per triangle.
  std::vector<uint32_t> indices;
  // Each empty or one per position: unit vertex normals and texture
  // coordinates (u, v pairs; v = 0 is an image's top row).
  std::vector<Vec3> normals;
  std::vector<float> uvs;
  std::vector<MeshAttribute> attributes;

  size_t TriangleCount() const { return indices.size() / 3; }
};

// The uv at barycentrics (b1, b2) of triangle `primitive` of a mesh with
// these indices and per-vertex `uvs`; (b1, b2) itself when it has none
// (the barycentric parameterisation).
inline void TriangleUvAt(const std::vector<uint32_t>& indices, const std::vector<float>& uvs, uint32_t primitive,
                         float b1, float b2, float uv[2]) {
  if (uvs.empty()) {
    uv[0] = b1, uv[1] = b2;
    return;
  }
  const uint32_t* v = &indices[3 * size_t(primitive)];
  const float b0 = 1 - b1 - b2;
  for (int c = 0; c < 2; ++c) uv[c] = b0 * uvs[2 * v[0] + c] + b1 * uvs[2 * v[1] + c] + b2 * uvs[2 * v[2] + c];
}

// How mesh files are read.
struct MeshOptions {
  // OBJ: v becomes 1 − v (Mitsuba's flip_tex_coords).
  bool flip_tex_coords = true;
  // Drop vertex normals: shade flat.
  bool face_normals = false;
};

// Parses `bytes` as `format` ("obj" or "ply"), inflated first when they
// are a gzip file (pbrt's .ply.gz); throws Error naming `name` on
// malformed input. Polygons are split into triangles.
TriangleMesh ParseMesh(std::string_view bytes, std::string_view format, const std::string& name,
                       const MeshOptions& options = {});

// What a mesh file makes, counted without keeping it: the memory a job
// needs for a mesh follows from these, not from the file's size (an OBJ
// or PLY of long fans is a triangle every few bytes).
struct MeshCounts {
  // Vertices (at most; OBJ corners sharing a triple share one) and triangles.
  uint64_t vertices = 0, triangles = 0;
  // Floats of per-vertex and per-triangle attributes.
  uint64_t attribute_values = 0;
  // The parser's peak memory, while it reads.
  uint64_t parse_bytes = 0;
};

// Counts what ParseMesh would make of `bytes`, throwing Error where its
// reading of the file would (index ranges and values are not checked). A
// gzip file is inflated to at most `max_inflated` bytes: one that holds
// more counts as a parse of more than that, its mesh not counted.
MeshCounts CountMesh(std::string_view bytes, std::string_view format, const std::string& name,
                     uint64_t max_inflated = uint64_t(1) << 62);

// Throws Error unless every index is in range, every position finite, and
// normals, uvs and attributes (finite) have one entry per vertex or face.
// Zero or non-finite normals are replaced by the face's; the rest are
// made unit length.
void ValidateMesh(TriangleMesh& mesh, const std::string& name);

// Smooth vertex normals for a mesh that has none, as Mitsuba computes them
// for its mesh files: each vertex's is the mean of its triangles' unit
// normals weighted by the triangle's angle at the vertex (Thürmer and
// Wüthrich 1998), so that how a surface is split into triangles does not
// tilt it. Degenerate triangles add nothing; a vertex with none but such
// gets a zero normal, which the kernel shades flat. For a mesh
// ValidateMesh has passed.
std::vector<Vec3> AngleWeightedNormals(const TriangleMesh& mesh);

// Drops vertex normals that are each triangle's own face normal (a box
// written with one normal per face): they shade exactly as none, and
// without them the kernel interpolates nothing. Only normals on the side
// the winding gives count: opposite ones decide the mesh's side.
void DropFaceNormals(TriangleMesh& mesh);

}  // namespace yarf
