// The patches of the radiosity transport: every triangle of the scene cut
// by midpoint subdivision into 4^level congruent sub-triangles, the
// elements that receive light, and the same at `shooter_levels` fewer
// levels, the patches that shoot it (Cohen et al. 1986's substructuring:
// shooting costs rays per element per shooter, so coarse shooters keep
// the solution cheap while the elements keep it sharp).
//
// At level L a triangle (P0, P1, P2) is an n×n grid (n = 2^L) over its
// barycentric coordinates (u, v) = (i/n, j/n): "upright" cells with
// corners (i,j), (i+1,j), (i,j+1) where i+j ≤ n−1, and "inverted" cells
// with corners (i+1,j+1), (i,j+1), (i+1,j) where i+j ≤ n−2; both keep the
// parent's winding. Cell (i,j) upright is patch j·n+i of the triangle, the
// inverted one patch (n−1−j)·n + (n−1−i): the slots the upright ones leave
// free. A hit's (u, v) thus names its patch without a search.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "yarf/error.h"
#include "yarf/transport.h"

namespace yarf::radiosity {

// A triangle of the scene and how finely it is cut.
struct SourceTriangle {
  Vec3 corner[3];
  // The scene's own normal (its flip and mirroring included): the front.
  Vec3 normal;
  uint32_t shape = 0, primitive = 0;
  uint32_t level = 0;  // n = 2^level cells along each edge
  uint32_t shooter_level = 0;
  uint32_t first_element = 0, first_shooter = 0;
};

struct Patch {
  Vec3 corner[3];
  Vec3 centre;
  Vec3 normal;  // the front, as its triangle's
  float area = 0;
  uint32_t triangle = 0;
  // Barycentrics of the centre in its triangle, for the material's uv.
  float u = 0, v = 0;
  // For an element, the shooter it belongs to (unused for shooters).
  uint32_t shooter = 0;
};

// Where a hit lies: its patch and its barycentric weights in that patch.
struct PatchPoint {
  uint32_t patch = 0;
  float weight[3] = {1, 0, 0};
};

class PatchMesh {
 public:
  // Cuts every triangle of the scene until its elements are smaller than
  // max_patch_area, or `level` times when level ≥ 0; shooters have
  // shooter_levels levels fewer. Throws for spheres.
  PatchMesh(const SceneView& scene, double max_patch_area, int level, int shooter_levels, size_t max_elements) {
    first_triangle_.resize(scene.ShapeCount() + 1);
    size_t elements = 0, shooters = 0;
    for (uint32_t shape = 0; shape < scene.ShapeCount(); ++shape) {
      first_triangle_[shape] = uint32_t(triangles_.size());
      for (uint32_t primitive = 0; primitive < scene.PrimitiveCount(shape); ++primitive) {
        SourceTriangle t;
        if (!scene.Triangle(shape, primitive, t.corner))
          throw Error("radiosity: shape " + std::to_string(shape) +
                      " is a sphere (or an environment light); radiosity meshes triangle surfaces only");
        t.shape = shape;
        t.primitive = primitive;
        const float area = TriangleArea(t.corner);
        int l = level;
        if (l < 0)
          for (l = 0; l < kMaxLevel && area / float(1u << (2 * l)) >= max_patch_area;) ++l;
        t.level = uint32_t(std::min(l, kMaxLevel));
        t.shooter_level = uint32_t(std::max(int(t.level) - shooter_levels, 0));
        t.first_element = uint32_t(elements);
        t.first_shooter = uint32_t(shooters);
        elements += size_t(1) << (2 * t.level);
        shooters += size_t(1) << (2 * t.shooter_level);
        if (elements > max_elements)
          throw Error("radiosity: more than " + std::to_string(max_elements) +
                      " elements; raise max_patch_area or lower subdivision");
        triangles_.push_back(t);
      }
    }
    first_triangle_.back() = uint32_t(triangles_.size());
    OrientTriangles(scene);
    elements_.resize(elements);
    shooters_.resize(shooters);
    for (uint32_t k = 0; k < triangles_.size(); ++k) {
      const SourceTriangle& t = triangles_[k];
      Cut(t, k, t.level, &elements_[t.first_element]);
      Cut(t, k, t.shooter_level, &shooters_[t.first_shooter]);
      const uint32_t n = 1u << t.level;
      for (uint32_t e = 0; e < n * n; ++e) {
        Patch& element = elements_[t.first_element + e];
        element.shooter = t.first_shooter + Locate(1u << t.shooter_level, element.u, element.v).patch;
      }
    }
  }

  const std::vector<SourceTriangle>& triangles() const { return triangles_; }
  const std::vector<Patch>& elements() const { return elements_; }
  const std::vector<Patch>& shooters() const { return shooters_; }

  // The element of a hit on (shape, primitive) at barycentrics (u, v),
  // and the hit's weights on its corners.
  PatchPoint Locate(uint32_t shape, uint32_t primitive, float u, float v) const {
    const SourceTriangle& t = triangles_[first_triangle_[shape] + primitive];
    PatchPoint p = Locate(1u << t.level, u, v);
    p.patch += t.first_element;
    return p;
  }

  // Centroids of the 4^level cells of a patch: sample points on it.
  static std::vector<Vec3> SamplePoints(const Patch& patch, uint32_t level) {
    SourceTriangle t;
    std::copy_n(patch.corner, 3, t.corner);
    std::vector<Patch> cells(size_t(1) << (2 * level));
    Cut(t, 0, level, cells.data());
    std::vector<Vec3> points(cells.size());
    for (size_t k = 0; k < cells.size(); ++k) points[k] = cells[k].centre;
    return points;
  }

 private:
  static constexpr int kMaxLevel = 10;

  static float TriangleArea(const Vec3 c[3]) { return 0.5f * Length(Cross(c[1] - c[0], c[2] - c[0])); }

  // The cell of an n-cell grid holding barycentrics (u, v), as an index
  // within its triangle, with the point's weights on the cell's corners.
  static PatchPoint Locate(uint32_t cells, float u, float v) {
    const int n = int(cells);
    const float a = std::clamp(u, 0.0f, 1.0f) * float(n), b = std::clamp(v, 0.0f, 1.0f) * float(n);
    const int i = std::clamp(int(a), 0, n - 1);
    const int j = std::clamp(int(b), 0, n - 1 - i);
    const float fa = a - float(i), fb = b - float(j);
    PatchPoint p;
    if (fa + fb <= 1 || i + j == n - 1) {
      p.patch = uint32_t(j * n + i);
      SetWeights(p, 1 - fa - fb, fa, fb);
    } else {
      p.patch = uint32_t((n - 1 - j) * n + (n - 1 - i));
      SetWeights(p, fa + fb - 1, 1 - fa, 1 - fb);
    }
    return p;
  }

  static void SetWeights(PatchPoint& p, float w0, float w1, float w2) {
    w0 = std::max(w0, 0.0f), w1 = std::max(w1, 0.0f), w2 = std::max(w2, 0.0f);
    const float sum = w0 + w1 + w2;
    p.weight[0] = sum > 0 ? w0 / sum : 1;
    p.weight[1] = sum > 0 ? w1 / sum : 0;
    p.weight[2] = sum > 0 ? w2 / sum : 0;
  }

  // The scene's normal of each triangle differs from its winding's when
  // the shape flips normals or is mirrored: ask the scene, with a short
  // ray onto the triangle's centroid.
  void OrientTriangles(const SceneView& scene) {
    std::vector<Ray> rays(triangles_.size());
    std::vector<Hit> hits(triangles_.size());
    for (size_t k = 0; k < triangles_.size(); ++k) {
      SourceTriangle& t = triangles_[k];
      const Vec3 n = Cross(t.corner[1] - t.corner[0], t.corner[2] - t.corner[0]);
      t.normal = Length(n) > 0 ? Normalize(n) : Vec3(0, 0, 1);
      const Vec3 centroid = (t.corner[0] + t.corner[1] + t.corner[2]) / 3.0f;
      const float offset = 4 * SurfaceOffset(centroid);
      rays[k].origin = centroid + t.normal * offset;
      rays[k].direction = -t.normal;
      rays[k].tfar = 2 * offset;
    }
    scene.Intersect(rays, hits);
    for (size_t k = 0; k < triangles_.size(); ++k) {
      SourceTriangle& t = triangles_[k];
      if (hits[k].shape == t.shape && hits[k].primitive == t.primitive && Dot(hits[k].normal, t.normal) < 0)
        t.normal = -t.normal;
    }
  }

  // The 4^level cells of triangle t (number `index`) into out[0..4^level).
  static void Cut(const SourceTriangle& t, uint32_t index, uint32_t level, Patch* out) {
    const int n = 1 << level;
    const float area = TriangleArea(t.corner) / float(n * n);
    auto add = [&](int slot, Vec3 a, Vec3 b, Vec3 c, float u, float v) {
      Patch& p = out[slot];
      p.corner[0] = a, p.corner[1] = b, p.corner[2] = c;
      p.centre = (a + b + c) / 3.0f;
      p.normal = t.normal;
      p.area = area;
      p.triangle = index;
      p.u = u, p.v = v;
    };
    for (int j = 0; j < n; ++j)
      for (int i = 0; i + j < n; ++i) {
        add(j * n + i, GridPoint(t, n, i, j), GridPoint(t, n, i + 1, j), GridPoint(t, n, i, j + 1),
            (float(i) + 1.0f / 3) / float(n), (float(j) + 1.0f / 3) / float(n));
        if (i + j < n - 1)
          add((n - 1 - j) * n + (n - 1 - i), GridPoint(t, n, i + 1, j + 1), GridPoint(t, n, i, j + 1),
              GridPoint(t, n, i + 1, j), (float(i) + 2.0f / 3) / float(n), (float(j) + 2.0f / 3) / float(n));
      }
  }

  // Grid point (i, j) of an n-cell grid on a triangle. Points on an edge
  // are computed from the edge's ends in a fixed order, so that the
  // triangles sharing the edge get the same floats (whatever their
  // levels) and Gouraud shading can join them.
  static Vec3 GridPoint(const SourceTriangle& t, int n, int i, int j) {
    if (j == 0) return OnEdge(t.corner[0], t.corner[1], i, n);
    if (i == 0) return OnEdge(t.corner[0], t.corner[2], j, n);
    if (i + j == n) return OnEdge(t.corner[2], t.corner[1], i, n);
    return t.corner[0] + (t.corner[1] - t.corner[0]) * (float(i) / float(n)) +
           (t.corner[2] - t.corner[0]) * (float(j) / float(n));
  }
  // The point k/n of the way from a to b.
  static Vec3 OnEdge(Vec3 a, Vec3 b, int k, int n) {
    if (k == 0) return a;
    if (k == n) return b;
    if (std::tie(b.x, b.y, b.z) < std::tie(a.x, a.y, a.z)) {
      std::swap(a, b);
      k = n - k;
    }
    return a + (b - a) * (float(k) / float(n));
  }

  std::vector<SourceTriangle> triangles_;
  std::vector<uint32_t> first_triangle_;
  std::vector<Patch> elements_, shooters_;
};

}  // namespace yarf::radiosity
