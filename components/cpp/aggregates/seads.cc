// seads — a uniform grid of voxels over the triangles (Fujimoto, Tanaka
// and Iwata's "spatially enumerated auxiliary data structure", ARTS 1986),
// the aggregate the paper gives as its example of a replaceable part.
//
// The scene's box is cut into cells of equal size, about `density` cells
// per triangle, as cubic as the box allows (Cleary and Wyvill's rule); each
// cell lists the triangles whose plane crosses it within their bounding
// box. A ray walks the cells it pierces in order (Amanatides and Woo's 3D
// digital differential analyser) and stops at the first cell holding a hit
// nearer than the cell's far side. Triangles are tested with Möller and
// Trumbore's algorithm, which gives the barycentrics Embree gives.
//
// A grid has no hierarchy: it is fast where triangles are spread evenly and
// slow where a few cells hold most of them (the "teapot in a stadium").
//
// Parameters: density, max_resolution (Seads::Parameters() below).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "yarf/plugin.h"

namespace {

using yarf::Vec3;

// A triangle as the test wants it: a corner and the two edges from it.
struct Triangle {
  Vec3 p0, e1, e2;
};

class Seads final : public yarf::Aggregate {
 public:
  static yarf::ParameterSchema Parameters() {
    using P = yarf::Parameter;
    return {
        P::Float("density").Default(2.0).Range(0.01, 64).Doc("cells per triangle the grid aims at"),
        P::Int("max_resolution").Default(512).Range(1, 2048).Doc("most cells along an axis"),
    };
  }

  explicit Seads(const yarf::Properties& p)
      : density_(p.Float("density")), max_resolution_(int(p.Int("max_resolution", 512, 1, 2048))) {}

  void Add(std::span<const Vec3> positions, std::span<const uint32_t> indices) override {
    if (indices.size() % 3 != 0) throw yarf::Error("seads: a mesh's indices are not whole triangles");
    for (uint32_t index : indices)
      if (index >= positions.size()) throw yarf::Error("seads: a mesh's index is past its vertices");
    first_triangle_.push_back(uint32_t(triangles_.size()));
    for (size_t t = 0; t < indices.size(); t += 3) {
      const Vec3 p0 = positions[indices[t]], p1 = positions[indices[t + 1]], p2 = positions[indices[t + 2]];
      triangles_.push_back({p0, p1 - p0, p2 - p0});
    }
  }

  void Commit() override {
    if (triangles_.size() >= (uint64_t(1) << 32)) throw yarf::Error("seads: more than 2^32 triangles");
    lower_ = Vec3(kHuge, kHuge, kHuge);
    upper_ = -lower_;
    for (const Triangle& t : triangles_) {
      const auto [lo, hi] = BoxOf(t);
      lower_ = Min(lower_, lo);
      upper_ = Max(upper_, hi);
    }
    if (triangles_.empty()) lower_ = upper_ = Vec3(0, 0, 0);
    // A flat box still has cells of some thickness.
    const Vec3 extent = upper_ - lower_;
    const float pad = 1e-4f * std::max({extent.x, extent.y, extent.z, 1e-6f});
    lower_ = lower_ - Vec3(pad, pad, pad);
    upper_ += Vec3(pad, pad, pad);
    ChooseResolution();
    FitBinningBudget();
    Bin();
  }

  void Bounds(Vec3& lower, Vec3& upper) const override {
    lower = lower_;
    upper = upper_;
  }

  bool Intersect(const yarf::Ray& ray, yarf::AggregateHit& hit) const override {
    float best = ray.tfar;
    uint32_t best_triangle = kNone;
    float best_u = 0, best_v = 0;
    Walk(ray, [&](std::span<const uint32_t> cell, float cell_exit) {
      for (uint32_t index : cell) {
        float t, u, v;
        if (Hits(triangles_[index], ray, t, u, v) && t <= best) {
          best = t;
          best_triangle = index;
          best_u = u;
          best_v = v;
        }
      }
      // A hit beyond this cell may hide a nearer one in the cells ahead.
      return best_triangle != kNone && best <= cell_exit;
    });
    if (best_triangle == kNone) return false;
    const auto mesh = std::upper_bound(first_triangle_.begin(), first_triangle_.end(), best_triangle) - 1;
    hit.mesh = uint32_t(mesh - first_triangle_.begin());
    hit.primitive = best_triangle - *mesh;
    hit.t = best;
    hit.u = best_u;
    hit.v = best_v;
    return true;
  }

  bool Occluded(const yarf::Ray& ray) const override {
    bool blocked = false;
    Walk(ray, [&](std::span<const uint32_t> cell, float) {
      for (uint32_t index : cell) {
        float t, u, v;
        if (Hits(triangles_[index], ray, t, u, v) && t <= ray.tfar) return blocked = true;
      }
      return false;
    });
    return blocked;
  }

 private:
  static constexpr float kHuge = 3.0e38f;
  static constexpr uint32_t kNone = 0xFFFFFFFFu;

  static std::pair<Vec3, Vec3> BoxOf(const Triangle& t) {
    const Vec3 p1 = t.p0 + t.e1, p2 = t.p0 + t.e2;
    return {Min(t.p0, Min(p1, p2)), Max(t.p0, Max(p1, p2))};
  }
  static Vec3 Min(Vec3 a, Vec3 b) { return Vec3(std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)); }
  static Vec3 Max(Vec3 a, Vec3 b) { return Vec3(std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)); }

  // Cells along each axis: about density × triangles in all, in
  // proportion to the box's sides.
  void ChooseResolution() {
    const Vec3 extent = upper_ - lower_;
    const double volume = double(extent.x) * extent.y * extent.z;
    const double per_unit = std::cbrt(density_ * double(std::max<size_t>(triangles_.size(), 1)) / volume);
    for (int axis = 0; axis < 3; ++axis) {
      const double cells = std::round(double(extent[axis]) * per_unit);
      resolution_[axis] = int(std::clamp(cells, 1.0, double(max_resolution_)));
      cell_size_[axis] = extent[axis] / float(resolution_[axis]);
      inverse_cell_size_[axis] = 1.0f / cell_size_[axis];
    }
  }

  // Bin visits every cell of each triangle's box: triangles that span the
  // scene make that triangles × cells, quadratic in the triangles (40 000
  // took a minute). Past kMaxBoxCells in all the grid is made coarser,
  // halving every axis, until the visits fit: a finer grid would not
  // separate such triangles anyway.
  static constexpr uint64_t kMaxBoxCells = uint64_t(1) << 26;
  uint64_t BoxCells() const {
    uint64_t total = 0;
    for (const Triangle& t : triangles_) {
      const auto [lo, hi] = BoxOf(t);
      uint64_t cells = 1;
      for (int axis = 0; axis < 3; ++axis) cells *= uint64_t(CellOf(hi[axis], axis) - CellOf(lo[axis], axis) + 1);
      total += cells;
    }
    return total;
  }
  void FitBinningBudget() {
    const Vec3 extent = upper_ - lower_;
    while (BoxCells() > kMaxBoxCells && std::max({resolution_[0], resolution_[1], resolution_[2]}) > 1)
      for (int axis = 0; axis < 3; ++axis) {
        resolution_[axis] = std::max(1, resolution_[axis] / 2);
        cell_size_[axis] = extent[axis] / float(resolution_[axis]);
        inverse_cell_size_[axis] = 1.0f / cell_size_[axis];
      }
  }

  int CellOf(float coordinate, int axis) const {
    const float cell = (coordinate - lower_[axis]) * inverse_cell_size_[axis];
    return std::clamp(int(cell), 0, resolution_[axis] - 1);
  }
  size_t Index(int x, int y, int z) const { return (size_t(z) * resolution_[1] + y) * resolution_[0] + x; }

  // Whether the triangle's plane crosses the cell's box (with a margin, so
  // that a hit on a cell's side is in both cells).
  bool PlaneCrosses(const Triangle& t, Vec3 normal, Vec3 cell_lower) const {
    const Vec3 half = Vec3(cell_size_[0], cell_size_[1], cell_size_[2]) * 0.5f;
    const Vec3 center = cell_lower + half;
    const float reach = std::abs(normal.x) * half.x + std::abs(normal.y) * half.y + std::abs(normal.z) * half.z;
    return std::abs(Dot(normal, center - t.p0)) <= reach * 1.001f + 1e-7f * Length(normal) * Length(center);
  }

  // Each cell's triangles, as runs of cell_triangles_ (counted, then filled).
  void Bin() {
    const size_t cells = size_t(resolution_[0]) * resolution_[1] * resolution_[2];
    cell_start_.assign(cells + 1, 0);
    for (int pass = 0; pass < 2; ++pass) {
      std::vector<uint32_t> fill;
      if (pass == 1) {
        for (size_t c = 0; c < cells; ++c) cell_start_[c + 1] += cell_start_[c];
        cell_triangles_.resize(cell_start_[cells]);
        fill.assign(cell_start_.begin(), cell_start_.end() - 1);
      }
      for (uint32_t index = 0; index < triangles_.size(); ++index) {
        const Triangle& t = triangles_[index];
        const Vec3 normal = Cross(t.e1, t.e2);
        auto [lo, hi] = BoxOf(t);
        std::array<int, 3> first, last;
        for (int axis = 0; axis < 3; ++axis) {
          const float margin = 1e-5f * cell_size_[axis];
          first[axis] = CellOf(lo[axis] - margin, axis);
          last[axis] = CellOf(hi[axis] + margin, axis);
        }
        for (int z = first[2]; z <= last[2]; ++z)
          for (int y = first[1]; y <= last[1]; ++y)
            for (int x = first[0]; x <= last[0]; ++x) {
              const Vec3 cell_lower = lower_ + Vec3(x * cell_size_[0], y * cell_size_[1], z * cell_size_[2]);
              if (!PlaneCrosses(t, normal, cell_lower)) continue;
              const size_t cell = Index(x, y, z);
              if (pass == 0)
                ++cell_start_[cell + 1];
              else
                cell_triangles_[fill[cell]++] = index;
            }
      }
    }
  }

  // Möller and Trumbore: the hit's distance in [tnear, ∞) and barycentrics.
  static bool Hits(const Triangle& tri, const yarf::Ray& ray, float& t, float& u, float& v) {
    const Vec3 p = Cross(ray.direction, tri.e2);
    const float determinant = Dot(tri.e1, p);
    if (determinant == 0 || !std::isfinite(determinant)) return false;
    const float inverse = 1.0f / determinant;
    const Vec3 s = ray.origin - tri.p0;
    u = Dot(s, p) * inverse;
    if (!(u >= 0 && u <= 1)) return false;
    const Vec3 q = Cross(s, tri.e1);
    v = Dot(ray.direction, q) * inverse;
    if (!(v >= 0 && u + v <= 1)) return false;
    t = Dot(tri.e2, q) * inverse;
    return t >= ray.tnear;
  }

  // Calls visit(cell's triangles, distance where the ray leaves the cell)
  // for each cell the ray pierces within [tnear, tfar], nearest first,
  // until visit returns true.
  template <typename Visit>
  void Walk(const yarf::Ray& ray, Visit&& visit) const {
    if (cell_triangles_.empty()) return;
    // A ray without a finite origin and direction crosses no cell in order.
    for (int axis = 0; axis < 3; ++axis)
      if (!std::isfinite(ray.origin[axis]) || !std::isfinite(ray.direction[axis])) return;
    if (ray.direction.x == 0 && ray.direction.y == 0 && ray.direction.z == 0) return;
    // The ray's interval inside the grid's box (slabs).
    float enter = ray.tnear, leave = ray.tfar;
    std::array<float, 3> inverse;
    for (int axis = 0; axis < 3; ++axis) {
      inverse[axis] = 1.0f / ray.direction[axis];
      float near = (lower_[axis] - ray.origin[axis]) * inverse[axis];
      float far = (upper_[axis] - ray.origin[axis]) * inverse[axis];
      if (near > far) std::swap(near, far);
      // NaN (a ray along a slab's side) leaves the interval as it is.
      enter = near > enter ? near : enter;
      leave = far < leave ? far : leave;
    }
    if (!(enter <= leave) || !std::isfinite(enter)) return;
    std::array<int, 3> cell, step, end;
    std::array<float, 3> next, delta;
    for (int axis = 0; axis < 3; ++axis) {
      cell[axis] = CellOf(ray.origin[axis] + ray.direction[axis] * enter, axis);
      const float d = ray.direction[axis];
      if (d > 0) {
        step[axis] = 1;
        end[axis] = resolution_[axis];
        next[axis] = (lower_[axis] + float(cell[axis] + 1) * cell_size_[axis] - ray.origin[axis]) * inverse[axis];
        delta[axis] = cell_size_[axis] * inverse[axis];
      } else if (d < 0) {
        step[axis] = -1;
        end[axis] = -1;
        next[axis] = (lower_[axis] + float(cell[axis]) * cell_size_[axis] - ray.origin[axis]) * inverse[axis];
        delta[axis] = -cell_size_[axis] * inverse[axis];
      } else {
        step[axis] = 0;
        end[axis] = -2;
        next[axis] = kHuge;
        delta[axis] = 0;
      }
    }
    // A straight walk crosses each axis's cells at most once.
    for (int steps = resolution_[0] + resolution_[1] + resolution_[2]; steps >= 0; --steps) {
      const size_t index = Index(cell[0], cell[1], cell[2]);
      const int axis = next[0] < next[1] ? (next[0] < next[2] ? 0 : 2) : (next[1] < next[2] ? 1 : 2);
      const float exit = std::min(next[axis], leave);
      const std::span<const uint32_t> triangles(cell_triangles_.data() + cell_start_[index],
                                                cell_start_[index + 1] - cell_start_[index]);
      if (!triangles.empty() && visit(triangles, exit)) return;
      if (next[axis] > leave) return;
      cell[axis] += step[axis];
      if (cell[axis] == end[axis]) return;
      next[axis] += delta[axis];
    }
  }

  const double density_;
  const int max_resolution_;
  std::vector<Triangle> triangles_;
  // The first triangle of each mesh added.
  std::vector<uint32_t> first_triangle_;
  Vec3 lower_, upper_;
  std::array<int, 3> resolution_{1, 1, 1};
  std::array<float, 3> cell_size_{1, 1, 1}, inverse_cell_size_{1, 1, 1};
  std::vector<uint64_t> cell_start_;
  std::vector<uint32_t> cell_triangles_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Seads>(registrar, "seads", "1.0.0",
                        "Uniform grid of voxels (SEADS), walked cell by cell, in place of Embree's BVH");
}
