#include "importers/loop_subdivision.h"

#include <opensubdiv/far/error.h>
#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/topologyDescriptor.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>

namespace yarf::importers {
namespace {

namespace osd = OpenSubdiv::OPENSUBDIV_VERSION;

// A point (or tangent) OpenSubdiv's refiner blends.
struct Point {
  double x[3];
  void Clear() { x[0] = x[1] = x[2] = 0; }
  void AddWithWeight(const Point& p, float weight) {
    for (int k = 0; k < 3; ++k) x[k] += weight * p.x[k];
  }
};

Point Minus(const Point& a, const Point& b) { return {{a.x[0] - b.x[0], a.x[1] - b.x[1], a.x[2] - b.x[2]}}; }
Point Cross(const Point& a, const Point& b) {
  return {{a.x[1] * b.x[2] - a.x[2] * b.x[1], a.x[2] * b.x[0] - a.x[0] * b.x[2], a.x[0] * b.x[1] - a.x[1] * b.x[0]}};
}
double Dot(const Point& a, const Point& b) { return a.x[0] * b.x[0] + a.x[1] * b.x[1] + a.x[2] * b.x[2]; }

// OpenSubdiv reports on stdout unless told otherwise, and yarf-import
// writes its scene there.
void ReportError(osd::Far::ErrorType, const char* message) { std::fprintf(stderr, "opensubdiv: %s\n", message); }
void ReportWarning(const char* message) { std::fprintf(stderr, "opensubdiv: %s\n", message); }

}  // namespace

int LoopLevels(size_t triangles, int levels) {
  int kept = 0;
  while (kept < levels && (triangles << (2 * (kept + 1))) <= kLoopTriangles) ++kept;
  return kept;
}

TriangleArrays LoopSubdivision(const std::vector<double>& positions, const std::vector<uint32_t>& indices,
                               int levels) {
  osd::Far::SetErrorCallback(ReportError);
  osd::Far::SetWarningCallback(ReportWarning);
  std::vector<int> corners;
  for (size_t t = 0; t + 2 < indices.size(); t += 3) {
    const uint32_t a = indices[t], b = indices[t + 1], c = indices[t + 2];
    if (a != b && b != c && a != c) corners.insert(corners.end(), {int(a), int(b), int(c)});
  }
  if (corners.empty()) throw std::runtime_error("no triangle has three different corners");
  TriangleArrays out;

  osd::Far::TopologyDescriptor control;
  control.numVertices = int(positions.size() / 3);
  control.numFaces = int(corners.size() / 3);
  const std::vector<int> three(size_t(control.numFaces), 3);
  control.numVertsPerFace = three.data();
  control.vertIndicesPerFace = corners.data();
  osd::Sdc::Options rules;
  rules.SetVtxBoundaryInterpolation(osd::Sdc::Options::VTX_BOUNDARY_EDGE_ONLY);
  using Factory = osd::Far::TopologyRefinerFactory<osd::Far::TopologyDescriptor>;
  const std::unique_ptr<osd::Far::TopologyRefiner> refiner(
      Factory::Create(control, Factory::Options(osd::Sdc::SCHEME_LOOP, rules)));
  if (!refiner) throw std::runtime_error("OpenSubdiv cannot refine this control mesh");
  if (levels > 0) {
    osd::Far::TopologyRefiner::UniformOptions refinement(levels);
    refinement.fullTopologyInLastLevel = true;  // the limit needs each vertex's ring
    refiner->RefineUniform(refinement);
  }

  // Every level's vertices in one buffer, the control points first.
  std::vector<Point> points(size_t(refiner->GetNumVerticesTotal()));
  for (int v = 0; v < control.numVertices; ++v)
    points[v] = {{positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]}};
  const osd::Far::PrimvarRefiner primvars(*refiner);
  Point* level_points = points.data();
  for (int level = 1; level <= levels; ++level) {
    Point* next = level_points + refiner->GetLevel(level - 1).GetNumVertices();
    primvars.Interpolate(level, level_points, next);
    level_points = next;
  }
  const osd::Far::TopologyLevel& last = refiner->GetLevel(levels);
  const size_t count = size_t(last.GetNumVertices());
  std::vector<Point> limit(count), du(count), dv(count);
  primvars.Limit(level_points, limit, du, dv);

  for (int f = 0; f < last.GetNumFaces(); ++f) {
    const osd::Far::ConstIndexArray face = last.GetFaceVertices(f);
    for (int k = 0; k < 3; ++k) out.indices.push_back(uint32_t(face[k]));
  }
  // The limit normal, turned to the side of the winding of the triangles
  // around the vertex (OpenSubdiv's tangents do not say which side).
  std::vector<Point> winding(count, Point{{0, 0, 0}});
  for (size_t t = 0; t < out.indices.size(); t += 3) {
    const Point& a = limit[out.indices[t]];
    const Point n = Cross(Minus(limit[out.indices[t + 1]], a), Minus(limit[out.indices[t + 2]], a));
    for (int k = 0; k < 3; ++k) winding[out.indices[t + k]].AddWithWeight(n, 1.0f);
  }
  for (size_t v = 0; v < count; ++v) {
    Point n = Cross(du[v], dv[v]);
    const double length = std::sqrt(Dot(n, n));
    // A degenerate limit frame (a crease corner): the winding's own normal.
    if (!(length > 0) || !std::isfinite(length)) n = winding[v];
    else if (Dot(n, winding[v]) < 0) n = {{-n.x[0], -n.x[1], -n.x[2]}};
    const double norm = std::sqrt(Dot(n, n));
    for (int k = 0; k < 3; ++k) {
      out.positions.push_back(limit[v].x[k]);
      out.normals.push_back(norm > 0 ? n.x[k] / norm : 0.0);
    }
  }
  return out;
}

}  // namespace yarf::importers
