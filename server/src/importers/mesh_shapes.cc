#include "importers/mesh_shapes.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "importers/matrix.h"

namespace yarf::importers {
namespace {

constexpr double kPi = 3.14159265358979323846;

using Axis = std::array<float, 3>;

template <typename T>
void Add(google::protobuf::RepeatedField<T>* out, std::initializer_list<T> values) {
  for (T value : values) out->Add(value);
}

// A bilinear patch's corners in pbrt's order p00, p10, p01, p11, and its
// point and tangents at (u, v).
struct Patch {
  std::array<Vec3d, 4> p;

  static Vec3d Lerp(const std::array<Vec3d, 4>& c, double u, double v) {
    return c[0] * ((1 - u) * (1 - v)) + c[1] * (u * (1 - v)) + c[2] * ((1 - u) * v) + c[3] * (u * v);
  }
  Vec3d At(double u, double v) const { return Lerp(p, u, v); }
  Vec3d Normal(double u, double v) const {
    const Vec3d dpdu = (p[1] - p[0]) * (1 - v) + (p[3] - p[2]) * v;
    const Vec3d dpdv = (p[2] - p[0]) * (1 - u) + (p[3] - p[1]) * u;
    return Cross(dpdu, dpdv);
  }
  // How far p11 lies off the plane the other three corners span, or the
  // diagonals' when those three are in a line; 0 when flat.
  double Twist() const {
    const Vec3d twist = p[0] - p[1] - p[2] + p[3];
    std::optional<Vec3d> n = Normalized(Cross(p[1] - p[0], p[2] - p[0]));
    if (!n) n = Normalized(Cross(p[3] - p[0], p[2] - p[1]));
    return n ? std::abs(Dot(twist, *n)) : 0.0;
  }
  // Cells per side: a cell's facets are off the surface by at most
  // twist / (4 n²).
  int Cells(int most) const {
    const double size = std::max(Length(p[3] - p[0]), Length(p[2] - p[1]));
    const double twist = Twist();
    if (!(twist > kBilinearTolerance * size)) return 1;
    const double cells = std::ceil(std::sqrt(twist / (4 * kBilinearTolerance * size)));
    return int(std::clamp(cells, 1.0, double(most)));
  }
};

}  // namespace

TriangleArrays BilinearPatches(const std::vector<double>& positions, const std::vector<uint32_t>& indices,
                               const std::vector<double>& normals, const std::vector<double>& uvs) {
  const size_t patches = indices.size() / 4;
  auto corners = [&](const std::vector<double>& values, size_t width, size_t k) {
    std::array<Vec3d, 4> c;
    for (size_t i = 0; i < 4; ++i) {
      const double* v = &values[width * indices[4 * k + i]];
      c[i] = {v[0], v[1], width == 3 ? v[2] : 0.0};
    }
    return c;
  };
  // The finest grid the triangle budget allows every patch.
  const double budget = double(kBilinearTriangles) / (2.0 * double(std::max<size_t>(patches, 1)));
  const int most = int(std::clamp(std::floor(std::sqrt(budget)), 1.0, double(kBilinearCells)));
  std::vector<int> cells(patches);
  bool twisted = false;
  for (size_t k = 0; k < patches; ++k) {
    cells[k] = Patch{corners(positions, 3, k)}.Cells(most);
    twisted = twisted || cells[k] > 1;
  }
  const bool surface_normals = normals.empty() && twisted;
  TriangleArrays out;
  for (size_t k = 0; k < patches; ++k) {
    const Patch patch{corners(positions, 3, k)};
    const std::array<Vec3d, 4> uv =
        uvs.empty() ? std::array<Vec3d, 4>{Vec3d{0, 0, 0}, Vec3d{1, 0, 0}, Vec3d{0, 1, 0}, Vec3d{1, 1, 0}}
                    : corners(uvs, 2, k);
    const int n = cells[k];
    const uint32_t first = uint32_t(out.positions.size() / 3);
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        const double u = double(i) / n, v = double(j) / n;
        const Vec3d p = patch.At(u, v), t = Patch::Lerp(uv, u, v);
        out.positions.insert(out.positions.end(), {p.x, p.y, p.z});
        out.uvs.insert(out.uvs.end(), {t.x, t.y});
        if (surface_normals || !normals.empty()) {
          const Vec3d m = surface_normals ? patch.Normal(u, v) : Patch::Lerp(corners(normals, 3, k), u, v);
          out.normals.insert(out.normals.end(), {m.x, m.y, m.z});
        }
      }
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const uint32_t a = first + uint32_t(j * (n + 1) + i), b = a + 1, c = a + uint32_t(n + 1), d = c + 1;
        out.indices.insert(out.indices.end(), {a, b, d, a, d, c});
      }
    out.face_triangles.push_back(uint32_t(2 * n * n));
  }
  return out;
}

v1::Mesh InlineMesh(const std::vector<float>& positions, const std::vector<uint32_t>& indices) {
  v1::Mesh mesh;
  mesh.mutable_positions()->Add(positions.begin(), positions.end());
  mesh.mutable_indices()->Add(indices.begin(), indices.end());
  return mesh;
}

v1::Mesh CubeMesh() {
  // Each face by the directions in which u and v grow across it; its
  // normal is v × u and its (u, v) = (0, 0) corner lies at n − u − v.
  struct Face {
    Axis u, v;
  };
  constexpr Face kFaces[] = {
      {{0, 0, 1}, {1, 0, 0}},    // y = -1
      {{-1, 0, 0}, {0, 0, -1}},  // y = +1
      {{0, 1, 0}, {0, 0, -1}},   // x = +1
      {{0, 1, 0}, {1, 0, 0}},    // z = +1
      {{0, 1, 0}, {0, 0, 1}},    // x = -1
      {{0, -1, 0}, {1, 0, 0}},   // z = -1
  };
  v1::Mesh mesh;
  for (const Face& f : kFaces) {
    const Axis n = {f.v[1] * f.u[2] - f.v[2] * f.u[1], f.v[2] * f.u[0] - f.v[0] * f.u[2],
                    f.v[0] * f.u[1] - f.v[1] * f.u[0]};
    const uint32_t first = uint32_t(mesh.positions_size() / 3);
    for (const auto& [s, t] : {std::pair{0, 0}, std::pair{1, 0}, std::pair{1, 1}, std::pair{0, 1}}) {
      for (int k = 0; k < 3; ++k) mesh.add_positions(n[k] + (2 * s - 1) * f.u[k] + (2 * t - 1) * f.v[k]);
      Add<float>(mesh.mutable_normals(), {n[0], n[1], n[2]});
      Add<float>(mesh.mutable_uvs(), {float(s), float(t)});
    }
    // Corners (0,0), (1,0), (1,1), (0,1): counter-clockwise about n.
    Add<uint32_t>(mesh.mutable_indices(), {first + 3, first + 2, first + 1, first, first + 3, first + 1});
  }
  return mesh;
}

v1::Mesh DiskMesh(DiskUv uv, double inner, double phi_max_degrees) {
  const double phi_max = std::clamp(phi_max_degrees, 1e-4, 360.0) * (kPi / 180);
  const bool whole = phi_max_degrees >= 360;
  const int steps = std::max(1, int(std::ceil(kDiskSegments * phi_max / (2 * kPi) - 1e-9)));
  v1::Mesh mesh;
  auto vertex = [&](double r, double phi) {
    // A whole turn ends exactly where it starts.
    const bool end = whole && phi >= phi_max;
    Add<float>(mesh.mutable_positions(),
               {end ? float(r) : float(r * std::cos(phi)), end ? 0.0f : float(r * std::sin(phi)), 0.0f});
    Add<float>(mesh.mutable_normals(), {0, 0, 1});
    const double turn = phi / phi_max;
    if (uv == DiskUv::kMitsuba)
      Add<float>(mesh.mutable_uvs(), {float(r), float(turn)});
    else
      Add<float>(mesh.mutable_uvs(), {float(turn), float((1 - r) / (1 - inner))});
  };
  const auto angle = [&](double k) { return phi_max * k / steps; };
  if (inner > 0) {
    // Vertices 2k on the inner rim, 2k + 1 on the outer, for k = 0..steps.
    for (int k = 0; k <= steps; ++k) {
      vertex(inner, angle(k));
      vertex(1, angle(k));
    }
    for (uint32_t k = 0; k < uint32_t(steps); ++k)
      Add<uint32_t>(mesh.mutable_indices(), {2 * k, 2 * k + 1, 2 * k + 3, 2 * k, 2 * k + 3, 2 * k + 2});
    return mesh;
  }
  // Vertices 0..steps-1: the centre of each segment; steps..2·steps: the
  // rim.
  for (int k = 0; k < steps; ++k) vertex(0, angle(k + 0.5));
  for (int k = 0; k <= steps; ++k) vertex(1, angle(k));
  const uint32_t n = uint32_t(steps);
  for (uint32_t k = 0; k < n; ++k) Add<uint32_t>(mesh.mutable_indices(), {k, n + k, n + k + 1});
  return mesh;
}

v1::Mesh SphereZoneMesh(double z_min, double z_max, double phi_max_degrees) {
  const double phi_max = std::clamp(phi_max_degrees, 1e-4, 360.0) * (kPi / 180);
  const bool whole = phi_max_degrees >= 360;
  // pbrt-v4's θ range: from the lower cap (v = 0) to the upper (v = 1).
  const double theta_low = std::acos(std::clamp(z_min, -1.0, 1.0));
  const double theta_high = std::acos(std::clamp(z_max, -1.0, 1.0));
  const int columns = std::max(1, int(std::ceil(kCylinderSegments * phi_max / (2 * kPi) - 1e-9)));
  const int rows = std::max(1, int(std::ceil(kCylinderSegments / 2 * (theta_low - theta_high) / kPi - 1e-9)));
  v1::Mesh mesh;
  // Vertex (row, column) at index row·(columns + 1) + column.
  for (int i = 0; i <= rows; ++i) {
    const double v = double(i) / rows, theta = theta_low + v * (theta_high - theta_low);
    const double sin_theta = std::sin(theta), cos_theta = std::cos(theta);
    for (int k = 0; k <= columns; ++k) {
      const double u = double(k) / columns, phi = u * phi_max;
      const bool end = whole && k == columns;
      const float x = float(sin_theta * (end ? 1.0 : std::cos(phi))), y = float(end ? 0.0 : sin_theta * std::sin(phi));
      Add<float>(mesh.mutable_positions(), {x, y, float(cos_theta)});
      Add<float>(mesh.mutable_normals(), {x, y, float(cos_theta)});
      Add<float>(mesh.mutable_uvs(), {float(u), float(v)});
    }
  }
  const auto at = [&](int i, int k) { return uint32_t(i * (columns + 1) + k); };
  for (int i = 0; i < rows; ++i)
    for (int k = 0; k < columns; ++k) {
      // Counter-clockwise seen from outside; a ring at a pole is a point,
      // where the quad is one triangle.
      const uint32_t a = at(i, k), b = at(i, k + 1), c = at(i + 1, k + 1), d = at(i + 1, k);
      const bool low_pole = i == 0 && theta_low >= kPi - 1e-12, high_pole = i + 1 == rows && theta_high <= 1e-12;
      if (!low_pole) Add<uint32_t>(mesh.mutable_indices(), {a, b, c});
      if (!high_pole) Add<uint32_t>(mesh.mutable_indices(), {a, c, d});
    }
  return mesh;
}

v1::Mesh CylinderMesh(double phi_max_degrees) {
  const double phi_max = std::clamp(phi_max_degrees, 1e-4, 360.0) * (kPi / 180);
  const int steps = std::max(1, int(std::ceil(kCylinderSegments * phi_max / (2 * kPi) - 1e-9)));
  v1::Mesh mesh;
  // Vertex 2k at z = 0 and 2k + 1 at z = 1, for k = 0..steps.
  for (int k = 0; k <= steps; ++k) {
    const double u = double(k) / steps, phi = u * phi_max;
    // A whole turn ends exactly where it starts.
    const float c = k == steps && phi_max_degrees >= 360 ? 1.0f : float(std::cos(phi));
    const float s = k == steps && phi_max_degrees >= 360 ? 0.0f : float(std::sin(phi));
    for (float z : {0.0f, 1.0f}) {
      Add<float>(mesh.mutable_positions(), {c, s, z});
      Add<float>(mesh.mutable_normals(), {c, s, 0});
      Add<float>(mesh.mutable_uvs(), {float(u), z});
    }
  }
  for (uint32_t k = 0; k < uint32_t(steps); ++k) {
    const uint32_t bottom = 2 * k, next = 2 * k + 2;
    Add<uint32_t>(mesh.mutable_indices(), {bottom, next, next + 1, bottom, next + 1, bottom + 1});
  }
  return mesh;
}

}  // namespace yarf::importers
