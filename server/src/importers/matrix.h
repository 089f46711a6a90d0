// Double-precision 3-vectors and 4x4 affine matrices for composing the
// transforms of scene files (row-major, acting on column vectors).
#pragma once

#include <array>
#include <cmath>
#include <optional>

#include "yarf/v1/component.pb.h"

namespace yarf::importers {

struct Vec3d {
  double x = 0, y = 0, z = 0;

  Vec3d operator+(const Vec3d& o) const { return {x + o.x, y + o.y, z + o.z}; }
  Vec3d operator-(const Vec3d& o) const { return {x - o.x, y - o.y, z - o.z}; }
  Vec3d operator*(double s) const { return {x * s, y * s, z * s}; }
  Vec3d operator-() const { return {-x, -y, -z}; }
};

inline double Dot(const Vec3d& a, const Vec3d& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3d Cross(const Vec3d& a, const Vec3d& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double Length(const Vec3d& v) { return std::sqrt(Dot(v, v)); }
inline double TriangleArea(const Vec3d& a, const Vec3d& b, const Vec3d& c) { return Length(Cross(b - a, c - a)) / 2; }
// The unit vector along v; nullopt when v is (nearly) zero or not finite.
std::optional<Vec3d> Normalized(const Vec3d& v);

class Matrix4 {
 public:
  Matrix4();  // identity
  explicit Matrix4(const std::array<double, 16>& row_major) : m_(row_major) {}

  static Matrix4 Translate(const Vec3d& t);
  static Matrix4 Scale(const Vec3d& s);
  // Right-handed rotation by `degrees` about `axis` (any nonzero length).
  static std::optional<Matrix4> Rotate(const Vec3d& axis, double degrees);
  // Camera (or object) to world: columns (cross(up, dir), up', dir, origin),
  // the look-at frame both Mitsuba and pbrt build. nullopt when degenerate.
  static std::optional<Matrix4> LookAt(const Vec3d& origin, const Vec3d& target, const Vec3d& up);

  double operator()(int row, int column) const { return m_[4 * row + column]; }
  Matrix4 operator*(const Matrix4& o) const;
  bool operator==(const Matrix4& o) const { return m_ == o.m_; }

  Vec3d Point(const Vec3d& p) const;
  Vec3d Vector(const Vec3d& v) const;
  // Transforms a normal by the inverse transpose (nullopt when singular).
  std::optional<Vec3d> Normal(const Vec3d& n) const;
  double Determinant3() const;  // of the linear part
  std::optional<Matrix4> Inverse() const;
  bool IsIdentity() const { return *this == Matrix4(); }
  bool IsFinite() const;
  const std::array<double, 16>& values() const { return m_; }

  v1::Transform ToProto() const;

 private:
  std::array<double, 16> m_;
};

}  // namespace yarf::importers
