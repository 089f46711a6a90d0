// The directions of a diffuse reflection lobe (lambertian, roughdiffuse):
// wo on wi's side of the surface, drawn from the cosine-weighted
// hemisphere there. Both sides reflect alike (pbrt's DiffuseBxDF) unless
// the model is one-sided: then the back side is black (Mitsuba's diffuse,
// one-sided unless wrapped in its twosided).
#pragma once

#include <cmath>

#include "yarf/parameters.h"
#include "yarf/properties.h"
#include "yarf/support/warps.h"
#include "yarf/vecmath.h"

namespace yarf {

class DiffuseHemisphere {
 public:
  static Parameter TwoSidedParameter() {
    return Parameter::Bool("two_sided").Default(true).Doc(
        "whether the back side reflects like the front (false: it is black)");
  }
  explicit DiffuseHemisphere(const Properties& props) : two_sided_(props.Bool("two_sided", true)) {}

  // wi and wo (local) on one side: the front, or either when two-sided.
  bool Reflects(Vec3 in, Vec3 out) const { return in.z * out.z > 0 && (two_sided_ || in.z > 0); }

  // A direction for wi, cosine-weighted and mirrored onto wi's side, and
  // its density: 0 where wi reflects nothing.
  Vec3 Sample(Vec3 in, float u0, float u1, float& density) const {
    Vec3 out = SampleCosineHemisphere(u0, u1);
    if (in.z < 0) out.z = -out.z;
    density = Pdf(in, out);
    return out;
  }

  float Pdf(Vec3 in, Vec3 out) const { return Reflects(in, out) ? CosineHemispherePdf(std::abs(out.z)) : 0.0f; }

 private:
  bool two_sided_;
};

}  // namespace yarf
