// uniform_sphere — directions uniform over the whole sphere
//
// cos θ = 1 - 2·u0 is uniform in [-1, 1] (Archimedes' hat-box theorem:
// equal slabs of z cut equal areas of the sphere) and φ = 2π·u1.
//
// Signature: [0,1)² → unit vectors (x, y, z), pdf 1 / 4π per steradian;
// 0 for points that are not unit vectors. Inverse: exact,
// u0 = (1 - cos θ) / 2, u1 = φ / 2π.
//
// Parameters: none (UniformSphere::Parameters() below).
#include <array>

#include "square_warp.h"
#include "yarf/plugin.h"
#include "yarf/support/warps.h"

namespace {

using yarf::Vec3;

struct UniformSphere {
  static yarf::ParameterSchema Parameters() { return {}; }
  explicit UniformSphere(const yarf::Properties&) {}
  Vec3 Sample(float u0, float u1) const { return yarf::SampleUniformSphere(u0, u1); }
  float Density(Vec3) const { return yarf::UniformSpherePdf(); }
  std::array<float, 2> Invert(Vec3 w) const { return yarf::InvertUniformSphere(w); }
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::DirectionWarp<UniformSphere>>(registrar, "uniform_sphere", "1.0.0",
                                                     "Directions uniform over the sphere");
}
