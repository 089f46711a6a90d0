// Small value types for the kernel and components: vectors, frames,
// transforms. Header-only so plugins need no link-time dependency.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

namespace yarf {

inline constexpr float kPi = 3.14159265358979323846f;
inline constexpr float kInvPi = 0.31830988618379067154f;

struct Vec3 {
  float x = 0, y = 0, z = 0;

  constexpr Vec3() = default;
  constexpr Vec3(float x_, float y_, float z_) : x(x_), y(y_), z(z_) {}
  static Vec3 Load(const float* p) { return {p[0], p[1], p[2]}; }
  void Store(float* p) const { p[0] = x; p[1] = y; p[2] = z; }

  float operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  Vec3 operator+(Vec3 b) const { return {x + b.x, y + b.y, z + b.z}; }
  Vec3 operator-(Vec3 b) const { return {x - b.x, y - b.y, z - b.z}; }
  Vec3 operator-() const { return {-x, -y, -z}; }
  Vec3 operator*(Vec3 b) const { return {x * b.x, y * b.y, z * b.z}; }
  Vec3 operator*(float s) const { return {x * s, y * s, z * s}; }
  Vec3 operator/(float s) const { return *this * (1.0f / s); }
  Vec3& operator+=(Vec3 b) { return *this = *this + b; }
  Vec3& operator*=(Vec3 b) { return *this = *this * b; }
  Vec3& operator*=(float s) { return *this = *this * s; }
};

inline Vec3 operator*(float s, Vec3 v) { return v * s; }
inline float Dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 Cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float Length(Vec3 v) { return std::sqrt(Dot(v, v)); }
inline Vec3 Normalize(Vec3 v) { return v / Length(v); }
inline float MaxComponent(Vec3 v) { return std::max(v.x, std::max(v.y, v.z)); }
inline float Luminance(Vec3 rgb) { return 0.2126f * rgb.x + 0.7152f * rgb.y + 0.0722f * rgb.z; }

// Orthonormal basis with `n` as its z axis (Duff et al. 2017, branchless).
struct Frame {
  Vec3 s, t, n;

  explicit Frame(Vec3 normal) : n(normal) {
    const float sign = std::copysign(1.0f, n.z);
    const float a = -1.0f / (sign + n.z);
    const float b = n.x * n.y * a;
    s = {1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x};
    t = {b, sign + n.y * n.y * a, -n.y};
  }
  Vec3 ToLocal(Vec3 v) const { return {Dot(v, s), Dot(v, t), Dot(v, n)}; }
  Vec3 ToWorld(Vec3 v) const { return s * v.x + t * v.y + n * v.z; }
};

// Affine 4x4 transform, row-major, acting on column vectors.
struct Transform {
  std::array<double, 16> m{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};

  static Transform Identity() { return {}; }
  Transform operator*(const Transform& b) const {
    Transform r;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) {
        double s = 0;
        for (int k = 0; k < 4; ++k) s += m[i * 4 + k] * b.m[k * 4 + j];
        r.m[i * 4 + j] = s;
      }
    return r;
  }
  Vec3 Point(Vec3 p) const {
    return {float(m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3]),
            float(m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7]),
            float(m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11])};
  }
  Vec3 Vector(Vec3 v) const {
    return {float(m[0] * v.x + m[1] * v.y + m[2] * v.z),
            float(m[4] * v.x + m[5] * v.y + m[6] * v.z),
            float(m[8] * v.x + m[9] * v.y + m[10] * v.z)};
  }
  // The linear part's determinant: 0 for a degenerate transform.
  double Determinant3() const {
    return m[0] * (m[5] * m[10] - m[6] * m[9]) - m[1] * (m[4] * m[10] - m[6] * m[8]) +
           m[2] * (m[4] * m[9] - m[5] * m[8]);
  }
  // Transforms a normal: by the inverse transpose of the linear part
  // (the cofactor matrix, which differs from it by the determinant only).
  Vec3 Normal(Vec3 n) const {
    const double c00 = m[5] * m[10] - m[6] * m[9], c01 = m[6] * m[8] - m[4] * m[10],
                 c02 = m[4] * m[9] - m[5] * m[8];
    const double c10 = m[2] * m[9] - m[1] * m[10], c11 = m[0] * m[10] - m[2] * m[8],
                 c12 = m[1] * m[8] - m[0] * m[9];
    const double c20 = m[1] * m[6] - m[2] * m[5], c21 = m[2] * m[4] - m[0] * m[6],
                 c22 = m[0] * m[5] - m[1] * m[4];
    const Vec3 r{float(c00 * n.x + c01 * n.y + c02 * n.z),
                 float(c10 * n.x + c11 * n.y + c12 * n.z),
                 float(c20 * n.x + c21 * n.y + c22 * n.z)};
    return Determinant3() < 0 ? -r : r;
  }
};

}  // namespace yarf
