// uniform_cone — directions uniform over a cone around +z
//
// The directions within angle θmax of +z: cos θ = 1 - u0·(1 - cos θmax)
// is uniform in [cos θmax, 1] (Archimedes' hat-box theorem) and
// φ = 2π·u1. Used for sampling a spherical light by the solid angle it
// subtends.
//
// Signature: [0,1)² → unit vectors (x, y, z), pdf 1 / (2π (1 - cos θmax))
// per steradian; 0 outside the cone and for points that are not unit
// vectors. Inverse: exact, u0 = (1 - cos θ) / (1 - cos θmax), u1 = φ / 2π.
//
// Parameters: UniformCone::Parameters() below; a negative cos_theta_max
// makes a cone wider than the hemisphere.
#include <array>

#include "square_warp.h"
#include "yarf/plugin.h"
#include "yarf/support/warps.h"

namespace {

using yarf::Vec3;

float RequireCosThetaMax(double value) {
  // Checked as a float too: 1 - cos θmax must stay positive after rounding.
  const float c = float(value);
  if (!(value > -1.0 && value < 1.0 && c > -1.0f && c < 1.0f))
    throw yarf::Error("property 'cos_theta_max' must lie in (-1, 1)");
  return c;
}

class UniformCone {
 public:
  static yarf::ParameterSchema Parameters() {
    using P = yarf::Parameter;
    return {P::Float("cos_theta_max").Default(0.9).Range(-1, 1).Doc("cosine of the cone's half-angle, in (-1, 1)")};
  }

  explicit UniformCone(const yarf::Properties& props)
      : cos_theta_max_(RequireCosThetaMax(props.Float("cos_theta_max", 0.9))) {}

  Vec3 Sample(float u0, float u1) const { return yarf::SampleUniformCone(u0, u1, cos_theta_max_); }
  float Density(Vec3 w) const { return yarf::UniformConePdf(w.z, cos_theta_max_); }
  std::array<float, 2> Invert(Vec3 w) const { return yarf::InvertUniformCone(w, cos_theta_max_); }

 private:
  float cos_theta_max_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::DirectionWarp<UniformCone>>(registrar, "uniform_cone", "1.0.0",
                                                   "Directions uniform over a cone around +z");
}
