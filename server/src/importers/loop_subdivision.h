// pbrt's "loopsubdiv" shape: a triangle control mesh refined by Loop's
// subdivision scheme (OpenSubdiv), its vertices on the limit surface.
#pragma once

#include <cstdint>
#include <vector>

#include "importers/mesh_shapes.h"

namespace yarf::importers {

// Levels are cut so that the refined mesh stays within this many triangles.
constexpr size_t kLoopTriangles = size_t(1) << 22;

// The control mesh (xyz triples, index triples) refined `levels` times
// (each level cuts a triangle in four; LoopLevels says how many stay
// within kLoopTriangles), as pbrt-v4 does: Loop's rules, boundary edges as creases
// (pbrt's boundary rule), every vertex then moved to its limit position,
// with the limit surface's normal, turned to the side the triangles'
// winding gives. Triangles with a repeated corner are left out. Throws
// std::runtime_error when none is left, or for a control mesh OpenSubdiv
// cannot take.
TriangleArrays LoopSubdivision(const std::vector<double>& positions, const std::vector<uint32_t>& indices,
                               int levels);

// The levels LoopSubdivision refines `triangles` by when asked for `levels`.
int LoopLevels(size_t triangles, int levels);

}  // namespace yarf::importers
