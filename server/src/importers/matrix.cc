#include "importers/matrix.h"

namespace yarf::importers {

std::optional<Vec3d> Normalized(const Vec3d& v) {
  const double length = Length(v);
  if (!(length > 1e-300) || !std::isfinite(length)) return std::nullopt;
  return v * (1.0 / length);
}

Matrix4::Matrix4() : m_{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1} {}

Matrix4 Matrix4::Translate(const Vec3d& t) {
  return Matrix4({1, 0, 0, t.x, 0, 1, 0, t.y, 0, 0, 1, t.z, 0, 0, 0, 1});
}

Matrix4 Matrix4::Scale(const Vec3d& s) {
  return Matrix4({s.x, 0, 0, 0, 0, s.y, 0, 0, 0, 0, s.z, 0, 0, 0, 0, 1});
}

std::optional<Matrix4> Matrix4::Rotate(const Vec3d& axis, double degrees) {
  const auto a = Normalized(axis);
  if (!a || !std::isfinite(degrees)) return std::nullopt;
  const double theta = degrees * 3.14159265358979323846 / 180.0;
  const double s = std::sin(theta), c = std::cos(theta), t = 1 - c;
  const double x = a->x, y = a->y, z = a->z;
  return Matrix4({t * x * x + c, t * x * y - s * z, t * x * z + s * y, 0,  //
                  t * x * y + s * z, t * y * y + c, t * y * z - s * x, 0,  //
                  t * x * z - s * y, t * y * z + s * x, t * z * z + c, 0,  //
                  0, 0, 0, 1});
}

std::optional<Matrix4> Matrix4::LookAt(const Vec3d& origin, const Vec3d& target, const Vec3d& up) {
  const auto dir = Normalized(target - origin);
  if (!dir) return std::nullopt;
  const auto left = Normalized(Cross(up, *dir));
  if (!left || std::abs(Dot(*Normalized(up), *dir)) > 1 - 1e-12) return std::nullopt;
  const Vec3d new_up = Cross(*dir, *left);
  return Matrix4({left->x, new_up.x, dir->x, origin.x,  //
                  left->y, new_up.y, dir->y, origin.y,  //
                  left->z, new_up.z, dir->z, origin.z,  //
                  0, 0, 0, 1});
}

Matrix4 Matrix4::operator*(const Matrix4& o) const {
  std::array<double, 16> r{};
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      for (int k = 0; k < 4; ++k) r[4 * i + j] += m_[4 * i + k] * o.m_[4 * k + j];
  return Matrix4(r);
}

Vec3d Matrix4::Point(const Vec3d& p) const {
  return {m_[0] * p.x + m_[1] * p.y + m_[2] * p.z + m_[3],
          m_[4] * p.x + m_[5] * p.y + m_[6] * p.z + m_[7],
          m_[8] * p.x + m_[9] * p.y + m_[10] * p.z + m_[11]};
}

Vec3d Matrix4::Vector(const Vec3d& v) const {
  return {m_[0] * v.x + m_[1] * v.y + m_[2] * v.z, m_[4] * v.x + m_[5] * v.y + m_[6] * v.z,
          m_[8] * v.x + m_[9] * v.y + m_[10] * v.z};
}

std::optional<Vec3d> Matrix4::Normal(const Vec3d& n) const {
  const auto inverse = Inverse();
  if (!inverse) return std::nullopt;
  const auto& i = inverse->m_;
  // (M⁻¹)ᵀ n
  return Vec3d{i[0] * n.x + i[4] * n.y + i[8] * n.z, i[1] * n.x + i[5] * n.y + i[9] * n.z,
               i[2] * n.x + i[6] * n.y + i[10] * n.z};
}

double Matrix4::Determinant3() const {
  return m_[0] * (m_[5] * m_[10] - m_[6] * m_[9]) - m_[1] * (m_[4] * m_[10] - m_[6] * m_[8]) +
         m_[2] * (m_[4] * m_[9] - m_[5] * m_[8]);
}

std::optional<Matrix4> Matrix4::Inverse() const {
  // Gauss-Jordan elimination with partial pivoting on [M | I].
  std::array<double, 16> a = m_;
  Matrix4 inverse;
  std::array<double, 16>& r = inverse.m_;
  for (int column = 0; column < 4; ++column) {
    int pivot = column;
    for (int row = column + 1; row < 4; ++row)
      if (std::abs(a[4 * row + column]) > std::abs(a[4 * pivot + column])) pivot = row;
    if (!(std::abs(a[4 * pivot + column]) > 1e-300)) return std::nullopt;
    for (int k = 0; k < 4; ++k) {
      std::swap(a[4 * column + k], a[4 * pivot + k]);
      std::swap(r[4 * column + k], r[4 * pivot + k]);
    }
    const double scale = 1 / a[4 * column + column];
    for (int k = 0; k < 4; ++k) {
      a[4 * column + k] *= scale;
      r[4 * column + k] *= scale;
    }
    for (int row = 0; row < 4; ++row) {
      if (row == column) continue;
      const double f = a[4 * row + column];
      for (int k = 0; k < 4; ++k) {
        a[4 * row + k] -= f * a[4 * column + k];
        r[4 * row + k] -= f * r[4 * column + k];
      }
    }
  }
  if (!inverse.IsFinite()) return std::nullopt;
  return inverse;
}

bool Matrix4::IsFinite() const {
  for (double v : m_)
    if (!std::isfinite(v)) return false;
  return true;
}

v1::Transform Matrix4::ToProto() const {
  v1::Transform t;
  for (double v : m_) t.add_m(v);
  return t;
}

}  // namespace yarf::importers
