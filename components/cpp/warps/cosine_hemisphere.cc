// cosine_hemisphere — directions of the hemisphere z > 0, density ∝ cos θ
//
// Malley's method: a uniform point of the unit disk (concentric map)
// lifted straight up onto the hemisphere lands with density cos θ / π, the
// importance of a Lambertian surface's cosine factor.
//
// Signature: [0,1)² → unit vectors (x, y, z), pdf cos θ / π per steradian;
// 0 for z ≤ 0 and for points that are not unit vectors. Inverse: exact
// (the disk's inverse of (x, y)).
//
// Parameters: none (CosineHemisphere::Parameters() below).
#include <array>

#include "square_warp.h"
#include "yarf/plugin.h"
#include "yarf/support/warps.h"

namespace {

using yarf::Vec3;

struct CosineHemisphere {
  static yarf::ParameterSchema Parameters() { return {}; }
  explicit CosineHemisphere(const yarf::Properties&) {}
  Vec3 Sample(float u0, float u1) const { return yarf::SampleCosineHemisphere(u0, u1); }
  float Density(Vec3 w) const { return yarf::CosineHemispherePdf(w.z); }
  std::array<float, 2> Invert(Vec3 w) const { return yarf::InvertCosineHemisphere(w); }
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::DirectionWarp<CosineHemisphere>>(
      registrar, "cosine_hemisphere", "1.0.0", "Cosine-weighted directions of the hemisphere (Malley)");
}
