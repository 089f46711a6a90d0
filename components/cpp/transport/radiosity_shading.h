// The vertices of the elements, where the radiosity transport also
// receives light so that Gouraud shading interpolates radiosities
// computed at the vertices themselves (Wallace, Elmquist & Haines 1989)
// rather than averaged from the elements around them, which would smear
// a wall's dark corners and the shadows at a box's foot.
//
// Element corners are one vertex when they belong to the same shape, have
// equal floats (PatchMesh computes shared edges' points alike) and their
// elements' planes agree within kCreaseCosine, so that a flat wall is one
// smooth surface across its triangles while a box keeps sharp edges. A
// vertex has two sides like an element; a corner whose element faces the
// other way than the vertex's normal takes the vertex's other side.
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <tuple>
#include <vector>

#include "radiosity_mesh.h"

namespace yarf::radiosity {

inline constexpr float kCreaseCosine = 0.9f;

struct VertexSet {
  std::vector<Vec3> position, normal;
  // A length for how near a shooter is: the root of the mean area of the
  // vertex's elements.
  std::vector<float> size;
  // Per element corner (3e + c): its vertex, and whether it is the
  // vertex's back (the element faces against the vertex's normal).
  std::vector<uint32_t> corner_vertex;
  std::vector<uint8_t> corner_flipped;

  size_t Count() const { return position.size(); }
  // The vertex side (2v or 2v+1) seen from element side k's corner c.
  uint32_t SideOf(uint32_t element_side, uint32_t corner) const {
    const uint32_t c = 3 * (element_side / 2) + corner;
    return 2 * corner_vertex[c] + ((element_side % 2) ^ corner_flipped[c]);
  }
  // The area-weighted mean over each vertex side's element sides of a
  // value given per element side.
  std::vector<Vec3> Mean(const PatchMesh& mesh, const std::vector<Vec3>& per_element_side) const {
    std::vector<Vec3> sum(2 * Count());
    std::vector<float> weight(2 * Count());
    if (Count() == 0) return sum;
    for (uint32_t k = 0; k < per_element_side.size(); ++k)
      for (uint32_t c = 0; c < 3; ++c) {
        const float area = mesh.elements()[k / 2].area;
        sum[SideOf(k, c)] += per_element_side[k] * area;
        weight[SideOf(k, c)] += area;
      }
    for (size_t v = 0; v < sum.size(); ++v)
      if (weight[v] > 0) sum[v] = sum[v] / weight[v];
    return sum;
  }
};

inline VertexSet BuildVertices(const PatchMesh& mesh) {
  const std::vector<Patch>& elements = mesh.elements();
  struct Incidence {
    uint32_t shape, x, y, z;
    uint32_t corner;  // 3e + c
    auto Key() const { return std::tie(shape, x, y, z); }
  };
  std::vector<Incidence> incidences;
  incidences.reserve(3 * elements.size());
  for (uint32_t e = 0; e < elements.size(); ++e)
    for (uint32_t c = 0; c < 3; ++c) {
      const Vec3 p = elements[e].corner[c];
      incidences.push_back({mesh.triangles()[elements[e].triangle].shape, std::bit_cast<uint32_t>(p.x),
                            std::bit_cast<uint32_t>(p.y), std::bit_cast<uint32_t>(p.z), 3 * e + c});
    }
  std::sort(incidences.begin(), incidences.end(),
            [](const Incidence& a, const Incidence& b) { return a.Key() < b.Key(); });

  VertexSet set;
  set.corner_vertex.assign(3 * elements.size(), 0);
  set.corner_flipped.assign(3 * elements.size(), 0);
  std::vector<uint8_t> assigned(incidences.size());
  std::vector<float> area_sum;
  std::vector<uint32_t> area_count;
  for (size_t first = 0; first < incidences.size();) {
    size_t last = first + 1;
    while (last < incidences.size() && incidences[last].Key() == incidences[first].Key()) ++last;
    // Corners here whose planes agree with the first unassigned one's.
    for (size_t a = first; a < last; ++a) {
      if (assigned[a]) continue;
      const uint32_t vertex = uint32_t(set.Count());
      const Patch& seed = elements[incidences[a].corner / 3];
      set.position.push_back(seed.corner[incidences[a].corner % 3]);
      set.normal.push_back(seed.normal);
      area_sum.push_back(0);
      area_count.push_back(0);
      for (size_t b = a; b < last; ++b) {
        if (assigned[b]) continue;
        const Patch& other = elements[incidences[b].corner / 3];
        const float alignment = Dot(seed.normal, other.normal);
        if (std::abs(alignment) < kCreaseCosine) continue;
        assigned[b] = 1;
        set.corner_vertex[incidences[b].corner] = vertex;
        set.corner_flipped[incidences[b].corner] = alignment < 0;
        area_sum[vertex] += other.area;
        ++area_count[vertex];
      }
    }
    first = last;
  }
  set.size.resize(set.Count());
  for (size_t v = 0; v < set.Count(); ++v) set.size[v] = std::sqrt(area_sum[v] / float(area_count[v]));
  return set;
}

}  // namespace yarf::radiosity
