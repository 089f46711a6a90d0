// uniform_hemisphere — directions uniform over the hemisphere z ≥ 0
//
// cos θ = u0 is uniform in [0, 1] (Archimedes' hat-box theorem) and
// φ = 2π·u1.
//
// Signature: [0,1)² → unit vectors (x, y, z), pdf 1 / 2π per steradian;
// 0 for z < 0 and for points that are not unit vectors. Inverse: exact,
// u0 = cos θ, u1 = φ / 2π.
//
// Parameters: none (UniformHemisphere::Parameters() below).
#include <array>

#include "square_warp.h"
#include "yarf/plugin.h"
#include "yarf/support/warps.h"

namespace {

using yarf::Vec3;

struct UniformHemisphere {
  static yarf::ParameterSchema Parameters() { return {}; }
  explicit UniformHemisphere(const yarf::Properties&) {}
  Vec3 Sample(float u0, float u1) const { return yarf::SampleUniformHemisphere(u0, u1); }
  float Density(Vec3 w) const { return yarf::UniformHemispherePdf(w.z); }
  std::array<float, 2> Invert(Vec3 w) const { return yarf::InvertUniformHemisphere(w); }
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::DirectionWarp<UniformHemisphere>>(
      registrar, "uniform_hemisphere", "1.0.0", "Directions uniform over the hemisphere z >= 0");
}
