// phong_lobe — directions around +z with density ∝ cos^n θ
//
// The lobe of Phong's specular term: cos θ = u0^(1/(n+1)) inverts the
// lobe's marginal distribution in cos θ, and φ = 2π·u1. n = 0 gives the
// uniform hemisphere; larger n narrows the lobe around +z.
//
// Signature: [0,1)² → unit vectors (x, y, z), pdf (n + 1) / 2π · cos^n θ
// per steradian; 0 for z ≤ 0 and for points that are not unit vectors.
// Inverse: exact, u0 = cos^(n+1) θ, u1 = φ / 2π.
//
// Parameters: PhongLobe::Parameters() below.
#include <array>
#include <cmath>

#include "square_warp.h"
#include "yarf/plugin.h"
#include "yarf/support/warps.h"

namespace {

using yarf::Vec3;

float RequireExponent(double exponent) {
  if (!(exponent >= 0.0 && std::isfinite(exponent)))
    throw yarf::Error("property 'exponent' must be a finite number ≥ 0");
  return float(exponent);
}

class PhongLobe {
 public:
  static yarf::ParameterSchema Parameters() {
    return {yarf::Parameter::Float("exponent").Default(30).Min(0).Doc("the lobe's exponent n")};
  }

  explicit PhongLobe(const yarf::Properties& props)
      : exponent_(RequireExponent(props.Float("exponent", 30.0))) {}

  Vec3 Sample(float u0, float u1) const { return yarf::SamplePhongLobe(u0, u1, exponent_); }
  float Density(Vec3 w) const { return yarf::PhongLobePdf(w.z, exponent_); }
  std::array<float, 2> Invert(Vec3 w) const { return yarf::InvertPhongLobe(w, exponent_); }

 private:
  float exponent_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::DirectionWarp<PhongLobe>>(registrar, "phong_lobe", "1.0.0",
                                                 "Directions around +z with density proportional to cos^n");
}
