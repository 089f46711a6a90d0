// A coarse grid of extinction majorants over the unit cube and the walk
// of a ray through its cells (a 3-D DDA, as pbrt-v4's
// DDAMajorantIterator), which turns a ray into majorant segments.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "yarf/geometry.h"
#include "yarf/medium.h"
#include "yarf/vecmath.h"

namespace yarf {

// The part [t0, t1) of [0, tmax) over which o + t·d lies in the unit
// cube; false when there is none.
inline bool ClipToUnitCube(Vec3 o, Vec3 d, float tmax, float& t0, float& t1) {
  t0 = 0;
  t1 = tmax;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0) {
      if (!(o[a] >= 0 && o[a] <= 1)) return false;
      continue;
    }
    float near = (0 - o[a]) / d[a], far = (1 - o[a]) / d[a];
    if (near > far) std::swap(near, far);
    t0 = std::max(t0, near);
    t1 = std::min(t1, far);
  }
  return t0 < t1;
}

class MajorantGrid {
 public:
  MajorantGrid(int nx, int ny, int nz) : n_{nx, ny, nz}, values_(size_t(nx) * size_t(ny) * size_t(nz)) {}

  int Resolution(int axis) const { return n_[axis]; }
  Vec3& At(int x, int y, int z) { return values_[(size_t(z) * size_t(n_[1]) + size_t(y)) * size_t(n_[0]) + size_t(x)]; }
  const Vec3& At(int x, int y, int z) const { return const_cast<MajorantGrid*>(this)->At(x, y, z); }

  // Appends to `out` the segments of the ray o + t·d (unit-cube
  // coordinates) over [t0, t1), a stretch inside the cube: one per cell
  // crossed, each with its cell's majorant, a run of equal ones merged.
  void Walk(Vec3 o, Vec3 d, float t0, float t1, std::vector<MajorantSegment>& out) const {
    const size_t first = out.size();
    const auto push = [&](float a, float b, Vec3 sigma) {
      if (!(b > a)) return;
      if (out.size() > first) {
        MajorantSegment& last = out.back();
        if (last.t1 == a && last.sigma_maj.x == sigma.x && last.sigma_maj.y == sigma.y &&
            last.sigma_maj.z == sigma.z) {
          last.t1 = b;
          return;
        }
      }
      out.push_back({a, b, sigma});
    };
    // The t where the ray meets plane k/n of `axis`, from the origin each
    // time, so that crossings do not accumulate round-off.
    const auto crossing = [&](int axis, int k) {
      return float((double(k) / n_[axis] - double(o[axis])) / double(d[axis]));
    };
    const Vec3 entry = o + d * t0;
    int cell[3], step[3];
    float next[3];
    for (int a = 0; a < 3; ++a) {
      cell[a] = std::clamp(int(std::floor(entry[a] * float(n_[a]))), 0, n_[a] - 1);
      step[a] = d[a] > 0 ? 1 : (d[a] < 0 ? -1 : 0);
      next[a] = step[a] == 0 ? kInfinity : crossing(a, cell[a] + (step[a] > 0 ? 1 : 0));
    }
    float t = t0;
    while (true) {
      const int a = next[0] < next[1] ? (next[0] < next[2] ? 0 : 2) : (next[1] < next[2] ? 1 : 2);
      const Vec3 sigma = At(cell[0], cell[1], cell[2]);
      if (!(next[a] < t1)) {
        push(t, t1, sigma);
        return;
      }
      push(t, next[a], sigma);
      t = std::max(t, next[a]);
      cell[a] += step[a];
      if (cell[a] < 0 || cell[a] >= n_[a]) {
        // Round-off put the exit before t1: the rest lies on the cube's
        // face, in the cell just left.
        push(t, t1, sigma);
        return;
      }
      next[a] = crossing(a, cell[a] + (step[a] > 0 ? 1 : 0));
    }
  }

 private:
  int n_[3];
  std::vector<Vec3> values_;
};

}  // namespace yarf
