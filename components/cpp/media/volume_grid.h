// A dense grid of voxel values over the unit cube [0, 1]³, looked up by
// trilinear interpolation between voxel centres, as Mitsuba 3's
// gridvolume and pbrt-v4's SampledGrid do: voxel (x, y, z) of an
// nx × ny × nz grid is centred at ((x + ½)/nx, (y + ½)/ny, (z + ½)/nz).
//
// Past the outermost voxel centres the two renderers differ, so a grid
// says which it follows (GridEdge): Mitsuba clamps to the border voxels,
// pbrt-v4 interpolates toward zero-valued voxels beyond the border (its
// density fades out over the outer half voxel).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "yarf/error.h"
#include "yarf/geometry.h"
#include "yarf/vecmath.h"

namespace yarf {

enum class GridEdge { kClamp, kZero };

// The most voxels a grid may have (256M: 1 GiB of floats per channel).
inline constexpr uint64_t kMaxGridVoxels = uint64_t(1) << 28;

// nx·ny·nz, after checking each is at least 1 and the product is at most
// kMaxGridVoxels.
inline uint64_t GridVoxelCount(int64_t nx, int64_t ny, int64_t nz, const std::string& what) {
  if (nx < 1 || ny < 1 || nz < 1)
    throw Error(what + ": the grid's resolution must be at least 1 along each axis, got " + std::to_string(nx) +
                " x " + std::to_string(ny) + " x " + std::to_string(nz));
  const int64_t limit = int64_t(kMaxGridVoxels);
  if (nx > limit || ny > limit || nz > limit || nx * ny > limit || nx * ny * nz > limit)
    throw Error(what + ": a grid of " + std::to_string(nx) + " x " + std::to_string(ny) + " x " +
                std::to_string(nz) + " voxels is larger than the " + std::to_string(kMaxGridVoxels) +
                " voxels allowed");
  return uint64_t(nx * ny * nz);
}

struct VolumeGrid {
  int nx = 0, ny = 0, nz = 0;
  int channels = 1;  // 1 or 3; a single channel reads as grey
  // ((z·ny + y)·nx + x)·channels + c.
  std::vector<float> values;
  // Where the file placed the grid: the unit cube to the file's own space
  // (a .vol file's bounding box, an OpenVDB grid's voxels in its world
  // space); has_placement is false when the file says nothing usable.
  Transform unit_to_file;
  bool has_placement = false;

  Vec3 Voxel(int x, int y, int z) const {
    const float* v = &values[((size_t(z) * size_t(ny) + size_t(y)) * size_t(nx) + size_t(x)) * size_t(channels)];
    return channels == 1 ? Vec3(v[0], v[0], v[0]) : Vec3(v[0], v[1], v[2]);
  }

  // The interpolated value at `local`, a point of the unit cube.
  Vec3 Lookup(Vec3 local, GridEdge edge) const {
    const float px = local.x * float(nx) - 0.5f, py = local.y * float(ny) - 0.5f, pz = local.z * float(nz) - 0.5f;
    const float fx0 = std::floor(px), fy0 = std::floor(py), fz0 = std::floor(pz);
    const int x0 = int(fx0), y0 = int(fy0), z0 = int(fz0);
    const float dx = px - fx0, dy = py - fy0, dz = pz - fz0;
    const auto at = [&](int x, int y, int z) {
      if (edge == GridEdge::kZero && (x < 0 || y < 0 || z < 0 || x >= nx || y >= ny || z >= nz))
        return Vec3(0, 0, 0);
      return Voxel(std::clamp(x, 0, nx - 1), std::clamp(y, 0, ny - 1), std::clamp(z, 0, nz - 1));
    };
    const auto lerp = [](float t, Vec3 a, Vec3 b) { return a * (1 - t) + b * t; };
    const Vec3 c00 = lerp(dx, at(x0, y0, z0), at(x0 + 1, y0, z0));
    const Vec3 c10 = lerp(dx, at(x0, y0 + 1, z0), at(x0 + 1, y0 + 1, z0));
    const Vec3 c01 = lerp(dx, at(x0, y0, z0 + 1), at(x0 + 1, y0, z0 + 1));
    const Vec3 c11 = lerp(dx, at(x0, y0 + 1, z0 + 1), at(x0 + 1, y0 + 1, z0 + 1));
    return lerp(dz, lerp(dy, c00, c10), lerp(dy, c01, c11));
  }

  // The largest value, per channel, of the voxels whose interpolation
  // reaches into the box [lo, hi] of the unit cube: a bound of Lookup
  // there under either edge rule (voxel values being non-negative).
  Vec3 Max(Vec3 lo, Vec3 hi) const {
    const auto range = [](float lo, float hi, int n) {
      const int first = int(std::clamp(std::floor(lo * float(n) - 0.5f), 0.0f, float(n - 1)));
      const int last = int(std::clamp(std::floor(hi * float(n) - 0.5f) + 1, 0.0f, float(n - 1)));
      return std::pair{first, last};
    };
    const auto [x0, x1] = range(lo.x, hi.x, nx);
    const auto [y0, y1] = range(lo.y, hi.y, ny);
    const auto [z0, z1] = range(lo.z, hi.z, nz);
    Vec3 m(0, 0, 0);
    for (int z = z0; z <= z1; ++z)
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
          const Vec3 v = Voxel(x, y, z);
          m = Vec3(std::max(m.x, v.x), std::max(m.y, v.y), std::max(m.z, v.z));
        }
    return m;
  }

  // Refuses non-finite voxels and brings the others into [lo, hi] (so
  // that round-off such as a simulation's -1e-7 does not make a
  // coefficient negative).
  void Sanitize(float lo, float hi, const std::string& what) {
    for (size_t i = 0; i < values.size(); ++i) {
      if (!std::isfinite(values[i]))
        throw Error(what + ": voxel value " + std::to_string(i) + " is not a finite number");
      values[i] = std::clamp(values[i], lo, hi);
    }
  }
};

// The inverse of an affine transform; an Error naming `what` when its
// linear part is singular (or nearly so) or not finite.
inline Transform InverseAffine(const Transform& t, const std::string& what) {
  const auto& m = t.m;
  const double det = t.Determinant3();
  double norms = 1;
  for (int c = 0; c < 3; ++c) norms *= std::sqrt(m[c] * m[c] + m[4 + c] * m[4 + c] + m[8 + c] * m[8 + c]);
  if (!std::isfinite(det) || !(std::abs(det) > 1e-12 * norms) || !(norms > 0))
    throw Error(what + " is singular: it maps the grid's box to a flat or empty one");
  if (m[12] != 0 || m[13] != 0 || m[14] != 0 || m[15] != 1)
    throw Error(what + " must be affine (last row 0 0 0 1)");
  Transform r;
  const double inv = 1 / det;
  r.m[0] = (m[5] * m[10] - m[6] * m[9]) * inv;
  r.m[1] = (m[2] * m[9] - m[1] * m[10]) * inv;
  r.m[2] = (m[1] * m[6] - m[2] * m[5]) * inv;
  r.m[4] = (m[6] * m[8] - m[4] * m[10]) * inv;
  r.m[5] = (m[0] * m[10] - m[2] * m[8]) * inv;
  r.m[6] = (m[2] * m[4] - m[0] * m[6]) * inv;
  r.m[8] = (m[4] * m[9] - m[5] * m[8]) * inv;
  r.m[9] = (m[1] * m[8] - m[0] * m[9]) * inv;
  r.m[10] = (m[0] * m[5] - m[1] * m[4]) * inv;
  for (int i = 0; i < 3; ++i)
    r.m[4 * i + 3] = -(r.m[4 * i] * m[3] + r.m[4 * i + 1] * m[7] + r.m[4 * i + 2] * m[11]);
  return r;
}

}  // namespace yarf
