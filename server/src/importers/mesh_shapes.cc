#include "importers/mesh_shapes.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace yarf::importers {
namespace {

constexpr double kPi = 3.14159265358979323846;

using Axis = std::array<float, 3>;

template <typename T>
void Add(google::protobuf::RepeatedField<T>* out, std::initializer_list<T> values) {
  for (T value : values) out->Add(value);
}

}  // namespace

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

v1::Mesh DiskMesh(DiskUv uv) {
  v1::Mesh mesh;
  auto vertex = [&](double r, double phi) {
    Add<float>(mesh.mutable_positions(), {float(r * std::cos(phi)), float(r * std::sin(phi)), 0.0f});
    Add<float>(mesh.mutable_normals(), {0, 0, 1});
    const double turn = phi / (2 * kPi);
    if (uv == DiskUv::kMitsuba)
      Add<float>(mesh.mutable_uvs(), {float(r), float(turn)});
    else
      Add<float>(mesh.mutable_uvs(), {float(turn), float(1 - r)});
  };
  // Vertices 0..N-1: the centre of each segment; N..2N: the rim, its
  // first point repeated at φ = 2π.
  for (int k = 0; k < kDiskSegments; ++k) vertex(0, 2 * kPi * (k + 0.5) / kDiskSegments);
  for (int k = 0; k <= kDiskSegments; ++k) vertex(1, 2 * kPi * k / kDiskSegments);
  for (uint32_t k = 0; k < uint32_t(kDiskSegments); ++k)
    Add<uint32_t>(mesh.mutable_indices(), {k, kDiskSegments + k, kDiskSegments + k + 1});
  // The repeated rim point sits exactly where the first does.
  mesh.set_positions(3 * (2 * kDiskSegments), 1.0f);
  mesh.set_positions(3 * (2 * kDiskSegments) + 1, 0.0f);
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
