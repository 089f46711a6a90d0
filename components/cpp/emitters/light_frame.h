// The frame of a point light with an orientation of its own (projector,
// goniometric). The kernel hands a point light's directions in the frame
// Frame(axis) it builds from the axis alone (the image of +z by to_world;
// KernelScene::AddLight), which loses the light's roll, so these lights
// take to_world as a property too and rebuild both frames from it.
#pragma once

#include <array>
#include <cmath>

#include "yarf/error.h"
#include "yarf/parameters.h"
#include "yarf/vecmath.h"

namespace yarf {

// The declaration of that property.
inline Parameter LightToWorldParameter() {
  return Parameter::Matrix("to_world").Doc("the light's placement, as its Light's to_world; identity when absent");
}

// A 3 × 3 matrix in double, row-major, acting on column vectors.
struct Matrix3 {
  std::array<double, 9> m{1, 0, 0, 0, 1, 0, 0, 0, 1};

  Vec3 operator*(Vec3 v) const {
    return {float(m[0] * v.x + m[1] * v.y + m[2] * v.z), float(m[3] * v.x + m[4] * v.y + m[5] * v.z),
            float(m[6] * v.x + m[7] * v.y + m[8] * v.z)};
  }
  double Determinant() const {
    return m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) +
           m[2] * (m[3] * m[7] - m[4] * m[6]);
  }
  Matrix3 Inverse() const {
    const double d = Determinant();
    Matrix3 r;
    r.m = {(m[4] * m[8] - m[5] * m[7]) / d, (m[2] * m[7] - m[1] * m[8]) / d, (m[1] * m[5] - m[2] * m[4]) / d,
           (m[5] * m[6] - m[3] * m[8]) / d, (m[0] * m[8] - m[2] * m[6]) / d, (m[2] * m[3] - m[0] * m[5]) / d,
           (m[3] * m[7] - m[4] * m[6]) / d, (m[1] * m[6] - m[0] * m[7]) / d, (m[0] * m[4] - m[1] * m[3]) / d};
    return r;
  }
};

// to_world's linear part M (any invertible one, mirrors included): a
// light-space direction l travels along M·l in the world.
class LightFrame {
 public:
  explicit LightFrame(const Transform& to_world) {
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) linear_.m[size_t(3 * i + j)] = to_world.m[size_t(4 * i + j)];
    const double det = linear_.Determinant();
    if (!(std::abs(det) > 1e-12) || !std::isfinite(det)) throw Error("property 'to_world' must be an invertible transform");
    abs_det_ = float(std::abs(det));
    inverse_ = linear_.Inverse();
    kernel_ = Frame(Normalize(to_world.Vector(Vec3(0, 0, 1))));
  }

  // The light-space direction (not normalised) of a direction the kernel
  // hands, and the world direction M·l of a light-space one.
  Vec3 FromKernel(Vec3 w) const { return inverse_ * kernel_.ToWorld(w); }
  Vec3 ToWorld(Vec3 l) const { return linear_ * l; }
  Vec3 ToKernel(Vec3 l) const { return kernel_.ToLocal(Normalize(linear_ * l)); }
  // dω_light / dω_world at light-space direction l (any length): the
  // world density of a direction is the light-space one times this.
  float DensityFactor(Vec3 l) const {
    const float world = Length(linear_ * l), light = Length(l);
    return world * world * world / (abs_det_ * light * light * light);
  }
  float AbsDeterminant() const { return abs_det_; }

 private:
  Matrix3 linear_, inverse_;
  float abs_det_ = 1;
  Frame kernel_{Vec3(0, 0, 1)};
};

}  // namespace yarf
