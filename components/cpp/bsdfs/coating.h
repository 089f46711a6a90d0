// The diffuse base under a dielectric coating, as plastic.cc and
// roughplastic.cc (Mitsuba 3's `plastic` and `roughplastic`) both model
// it: the base's value, corrected for the light the coating reflects back
// inside, and Mitsuba's odds of sampling the coating's lobe or the base's.
// How the coating itself reflects and transmits differs between the two
// and stays in each file. Also the parameters both read alike.
#pragma once

#include <optional>
#include <span>
#include <vector>

#include "microfacet.h"
#include "yarf/parameters.h"
#include "yarf/support/warps.h"
#include "yarf/texture.h"
#include "yarf/vecmath.h"

namespace yarf::coating {

// The parameters both models read alike: the base's colour ρ
// (diffuse_reflectance), the coating's R (specular_reflectance) and
// nonlinear.
inline std::vector<Parameter> CoatingParameters() {
  return {
      Parameter::RgbTexture("diffuse_reflectance").Default(0.5).Range(0, 1).Doc("ρ, the base's colour, per channel"),
      Parameter::RgbTexture("specular_reflectance")
          .Default(1.0)
          .Range(0, 1)
          .Doc("R, a factor on the coating's reflection (for realism, 1)"),
      Parameter::Bool("nonlinear")
          .Default(false)
          .Doc("ρ' = ρ / (1 - ρ r̄), darker and more saturated, not ρ / (1 - r̄)"),
  };
}

// The mean of the channels, by which Mitsuba weighs the lobes.
inline float Mean(Vec3 v) { return (v.x + v.y + v.z) / 3.0f; }

// ρ' / η² per channel: the base's value before the coating's two
// transmissions and 1/π, with ρ' = ρ / (1 - r̄) or, nonlinear, ρ / (1 - ρ r̄),
// where r̄ is the coating's reflectance, from inside, of diffuse light.
// (A float r̄ widened to double gives the float products exactly.)
inline Vec3 ScaledDiffuse(Vec3 rho, double internal, bool nonlinear, float eta) {
  float scaled[3];
  for (int c = 0; c < 3; ++c)
    scaled[c] = rho[c] / (1.0f - float(nonlinear ? rho[c] * internal : internal)) / (eta * eta);
  return Vec3::Load(scaled);
}

// Which lobes a coated material has, and the weight s = mean(R) /
// (mean(R) + mean(ρ)) of the coating's among them. "Specular" is the
// coating's lobe, as in Mitsuba (R = specular_reflectance): a delta lobe
// in plastic.cc, a glossy one in roughplastic.cc.
struct LobeWeights {
  bool has_diffuse = false, has_specular = false;
  float specular_weight = 0;
};

inline LobeWeights WeighLobes(Vec3 diffuse, Vec3 specular) {
  const float total = Mean(diffuse) + Mean(specular);
  return {Mean(diffuse) > 0, Mean(specular) > 0, total > 0 ? Mean(specular) / total : 0.0f};
}

// The coating's colours at one point.
struct Point {
  Vec3 specular;
  LobeWeights lobes;
  // ρ' / η² per channel (ScaledDiffuse).
  Vec3 scaled_diffuse;
};

// The coating's colours at a call's points, its base (`diffuse`) and
// coating (`specular`) colours perhaps textures: derived once per call
// when neither varies.
class Points {
 public:
  Points(const TexturedValue& diffuse, const TexturedValue& specular, const yarf::SurfacePoints& at, double internal,
         bool nonlinear, float eta)
      : diffuse_(diffuse.At(at)), specular_(specular.At(at)), internal_(internal), nonlinear_(nonlinear), eta_(eta) {
    if (diffuse_.IsUniform() && specular_.IsUniform()) uniform_ = At(0);
  }

  Point operator[](size_t k) const { return uniform_ ? *uniform_ : At(k); }

 private:
  Point At(size_t k) const {
    const Vec3 diffuse = diffuse_[k], specular = specular_[k];
    return {specular, WeighLobes(diffuse, specular), ScaledDiffuse(diffuse, internal_, nonlinear_, eta_)};
  }

  PointValues<Vec3> diffuse_, specular_;
  double internal_;
  bool nonlinear_;
  float eta_;
  std::optional<Point> uniform_;
};

// A rough coating's reflection, f / R: F(wi·h) D(h) G2(wi, wo) / (4 cos θi
// cos θo), h the half vector (roughplastic's and pplastic's), for wi and
// wo above.
inline float RoughCoatingReflection(const microfacet::Roughness& roughness, float eta, Vec3 wi, Vec3 wo) {
  const Vec3 h = Normalize(wi + wo);
  return FresnelDielectric(Dot(wi, h), eta) * microfacet::Ndf(h, roughness) * microfacet::SmithG2(wi, wo, roughness) /
         (4.0f * wi.z * wo.z);
}

// The density of a rough coating's Sample: its lobe (the normals visible
// from wi) with odds p_glossy, the base's cosine-weighted hemisphere with
// the rest; the coating lobe's part below the surface is lost (Sample
// returns no sample there).
inline float RoughCoatingDensity(const microfacet::Roughness& roughness, Vec3 wi, Vec3 wo, float p_glossy) {
  if (!(wi.z > 0 && wo.z > 0)) return 0.0f;
  float density = (1.0f - p_glossy) * CosineHemispherePdf(wo.z);
  if (p_glossy > 0) {
    const Vec3 h = Normalize(wi + wo);
    density += p_glossy * microfacet::SmithG1(wi, roughness) * microfacet::Ndf(h, roughness) / (4.0f * wi.z);
  }
  return density;
}

}  // namespace yarf::coating
