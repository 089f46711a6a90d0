// principled — the Disney BSDF, as Mitsuba 3's `principled`
//
// Burley's artist-friendly model ("Physically based shading at Disney",
// 2012; "Extending the Disney BRDF to a BSDF with integrated subsurface
// scattering", 2015) in the form Mitsuba 3 gives it: one set of
// parameters in [0, 1] blends a diffuse base, a metal, a glass and a
// clear coat. With m = metallic, s = spec_trans, c = base_color, the
// weights of the diffuse base and of the glass are b = (1 - m)(1 - s) and
// t = (1 - m) s, and seen from outside (cos θi > 0):
//
//   diffuse      b c/π (f_d + f_r), blended toward the fake subsurface term
//                f_ss by flatness; f_d = (1 - F_i/2)(1 - F_o/2), f_r the
//                retro-reflection 2 ρ cos²θd (F_i + F_o + F_i F_o (2ρ cos²θd - 1))
//                of roughness ρ, with F_x = (1 - |cos θx|)⁵ (Schlick's weight)
//   sheen        sheen (1 - m) (1 - cos θd)⁵ · lerp(1, c/lum(c), sheen_tint)
//                (only where b > 0, as in Mitsuba)
//   specular     F D G2 / (4 |cos θi| |cos θo|), GGX of α = ρ² stretched by
//                anisotropic, F = (1 - m)(1 - spec_tint) F_dielectric(η) +
//                m Schlick(c) + (1 - m) spec_tint Schlick(c/lum(c) R0(η))
//   refraction   √c t (1 - F_dielectric) D G2 |wi·h| |wo·h| /
//                (|cos θi| |cos θo| (wi·h + η wo·h)²), as roughdielectric.cc
//   clear coat   ¼ clearcoat Schlick(0.04) D₁(h) G1(wi) G1(wo): Burley's GTR1
//                normals of α = lerp(0.1, 0.001, clearcoat_gloss), Smith's
//                GGX masking of α = 0.25. As Mitsuba's, it has no
//                1/(4 cos θi cos θo), kept so that renders match Mitsuba's.
//
// Seen from inside (cos θi < 0) only the glass scatters: t F_dielectric
// D G2 / (4 |cos θi| |cos θo|) reflected, and the refraction above.
// θd is the angle between the half vector h and wo. η is 'eta', or from
// 'specular' (Disney's parameterisation) η = 2 / (1 - √(0.08 specular)) - 1.
// Refraction of radiance carries the 1/η² of roughdielectric.cc; of
// importance, not.
//
// Like Burley's model, it does not conserve energy for every parameter
// set: the retro-reflection and the sheen (which has no 1/π) make a bright,
// rough base with sheen reflect more than arrives at grazing incidence
// (base 0.8, roughness 1, sheen 1: an albedo of 1.32).
//
// Differences from Mitsuba: G2 is Smith's height-correlated joint masking
// (microfacet.h) where Mitsuba multiplies two G1s, as for the other rough
// models; the luminance is Rec. 709's (vecmath.h).
//
// Parameters: Principled::Parameters() below. A texture's values are
// clamped to the parameter's range.
// With spec_trans, η = 1 becomes 1.001 and specular = 0 becomes 0.001, as
// in Mitsuba: matched indices would refract without bending.
//
// Lobes: diffuse reflection (diffuse and sheen), glossy reflection
// (specular and clear coat) and, when spec_trans is not 0, glossy
// refraction. Sample picks, from outside, the diffuse lobe, the clear coat
// or the main specular lobe with odds b·(diffuse rate) : ¼ clearcoat
// (clearcoat rate) : (main specular rate), from inside the specular lobe
// only; the specular lobe draws a normal visible from wi (Heitz 2018) and
// reflects with odds 1 - t(1 - F) (from inside F) or refracts. It returns
// the density and value of the mixture of the allowed lobes.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "microfacet.h"
#include "principled_lobes.h"
#include "yarf/support/scatter_rows.h"
#include "surface_properties.h"
#include "yarf/plugin.h"
#include "yarf/texture.h"
#include "yarf/support/warps.h"

namespace {

using yarf::Vec3;
namespace mf = yarf::microfacet;
namespace pr = yarf::principled;

constexpr uint32_t kDiffuseLobe = yarf::kScatterReflect | yarf::kScatterDiffuse;
constexpr uint32_t kGlossyLobe = yarf::kScatterReflect | yarf::kScatterGlossy;
constexpr uint32_t kRefractLobe = yarf::kScatterRefract | yarf::kScatterGlossy;

// The scalar parameters, each a number in [0, 1] or a texture: one table
// read by the constructor and indexed by the model.
enum Parameter {
  kRoughness, kAnisotropic, kMetallic, kSpecTrans, kSpecTint, kSheen, kSheenTint, kFlatness,
  kClearcoat, kClearcoatGloss, kParameterCount
};
constexpr pr::ParameterInfo kParameters[kParameterCount] = {
    {"roughness", 0.5f, "ρ: the specular lobes' GGX α is ρ²"},
    {"anisotropic", 0.0f, "stretches the specular lobes along the shading frame's x"},
    {"metallic", 0.0f, "m: the share of the metal"},
    {"spec_trans", 0.0f, "s: the glass's share of what is not metal"},
    {"spec_tint", 0.0f, "tints the dielectric reflection toward the hue of base_color"},
    {"sheen", 0.0f, "the sheen at grazing angles"},
    {"sheen_tint", 0.0f, "tints the sheen toward the hue of base_color"},
    {"flatness", 0.0f, "blends the diffuse base toward the fake subsurface term"},
    {"clearcoat", 0.0f, "the clear coat's weight"},
    {"clearcoat_gloss", 0.0f, "the clear coat's gloss: α from 0.1 to 0.001"}};

// η from 'eta' or 'specular' (they exclude each other); `refracts` moves
// it off 1, where a refraction would not bend.
float ReadEta(const yarf::Properties& props, bool refracts) {
  if (props.Has("eta") && props.Has("specular"))
    throw yarf::Error("properties 'eta' and 'specular' exclude each other: give the index of refraction one way");
  if (props.Has("eta")) {
    const float eta = yarf::RequireIndex(props.Float("eta"), "eta");
    return refracts && eta == 1.0f ? 1.001f : eta;
  }
  double specular = props.Float("specular", 0.5);
  if (!(specular >= 0.0 && specular <= 1.0))
    throw yarf::Error("property 'specular' must be a number in [0, 1]");
  if (refracts && specular == 0.0) specular = 1e-3;
  return float(2.0 / (1.0 - std::sqrt(0.08 * specular)) - 1.0);
}

// Burley's GTR1 ("generalised Trowbridge–Reitz", γ = 1) distribution of
// the clear coat's normals, its D at cos θm, and a normal drawn by
// inverting its projected CDF (density D cos θm).
float Gtr1(float cos_m, float alpha) {
  const float a2 = alpha * alpha;
  const float d = (a2 - 1.0f) / (yarf::kPi * std::log(a2) * (1.0f + (a2 - 1.0f) * cos_m * cos_m));
  return d * cos_m > 1e-20f ? d : 0.0f;
}

Vec3 SampleGtr1(float alpha, float u0, float u1) {
  const float a2 = alpha * alpha;
  const float cos2 = std::clamp((1.0f - std::pow(a2, 1.0f - u1)) / (1.0f - a2), 0.0f, 1.0f);
  return yarf::SphericalDirection(std::sqrt(1.0f - cos2), std::sqrt(cos2), 2.0f * yarf::kPi * u0);
}

// The clear coat's masking: Smith's G1 of GGX at α = 0.25 (Burley).
constexpr mf::Roughness kClearcoatMasking{0.25f, 0.25f, mf::Distribution::kGgx};

// The parameters at one point, and what the lobes derive from them.
struct Material {
  Vec3 base;
  std::array<float, kParameterCount> p{};
  mf::Roughness specular;    // GGX of the main lobes
  float clearcoat_alpha = 0; // GTR1's α
  float diffuse_weight = 0;  // (1 - metallic)(1 - spec_trans)
  float glass_weight = 0;    // (1 - metallic) spec_trans

  Material(Vec3 base_color, const std::array<float, kParameterCount>& values) : base(base_color), p(values) {
    specular = pr::DisneyRoughness(p[kRoughness], p[kAnisotropic]);
    clearcoat_alpha = 0.1f + (0.001f - 0.1f) * p[kClearcoatGloss];
    diffuse_weight = (1.0f - p[kMetallic]) * (1.0f - p[kSpecTrans]);
    glass_weight = (1.0f - p[kMetallic]) * p[kSpecTrans];
  }
};

using Points = pr::PointParameters<Material, kParameterCount>;

// The odds of each lobe Sample draws, summing to 1 (or all 0).
struct Odds {
  float diffuse = 0, clearcoat = 0, specular = 0;
};

// The shares of reflection and refraction in the main specular lobe at a
// microfacet.
struct Split {
  float reflect = 0, refract = 0;
};

// How wi and wo meet: the half vector h (h.z > 0) of a reflection or a
// refraction, and whether it faces both as it must.
struct Pair {
  bool reflect = false, outside = false, compatible = false;
  float eta = 1;  // index of wo's side over wi's side, for a refraction
  Vec3 h;
  float fresnel = 0;  // F_dielectric(wi·h)
};

class Principled final : public yarf::SurfaceModel {
 public:
  static yarf::ParameterSchema Parameters() {
    using P = yarf::Parameter;
    yarf::ParameterSchema schema = {pr::BaseColorParameter()};
    for (const pr::ParameterInfo& info : kParameters) schema.push_back(pr::WeightParameter(info));
    schema.push_back(P::Float("eta").Min(0).Doc("η, the interior over the exterior index, instead of specular"));
    schema.push_back(
        P::Float("specular").Range(0, 1).Doc("η = 2 / (1 - √(0.08 specular)) - 1 instead; 0.5 without eta"));
    for (const char* rate : {"diffuse_reflectance_sampling_rate", "main_specular_sampling_rate",
                             "clearcoat_sampling_rate"})
      schema.push_back(pr::SamplingRateParameter(rate));
    return schema;
  }

  explicit Principled(const yarf::Properties& props)
      : base_(pr::ReadBaseColor(props)),
        values_(ReadParameters(props)),
        eta_(ReadEta(props, !values_[kSpecTrans].IsZero())),
        diffuse_rate_(pr::ReadSamplingRate(props, "diffuse_reflectance_sampling_rate")),
        specular_rate_(pr::ReadSamplingRate(props, "main_specular_sampling_rate")),
        clearcoat_rate_(pr::ReadSamplingRate(props, "clearcoat_sampling_rate")) {}

  void Evaluate(yarf::TransportMode mode, std::span<const float> wi, std::span<const float> wo,
                const yarf::SurfacePoints& at, std::span<float> value) const override {
    const Points points(base_, values_, at);
    yarf::EvaluateEach(wi, wo, value,
                       [&](size_t k, Vec3 in, Vec3 out) { return Value(points[k], in, out, mode, 0); });
  }

  void Sample(yarf::TransportMode mode, std::span<const float> wi, const yarf::SurfacePoints& at,
              std::span<const float> uniform, uint32_t allowed, std::span<float> wo,
              std::span<float> weight, std::span<float> pdf,
              std::span<uint32_t> flags) const override {
    const size_t count = wi.size() / 3;
    const Points points(base_, values_, at);
    const yarf::SampleRows rows{wo, weight, pdf, flags};
    for (size_t k = 0; k < count; ++k) {
      const Material m = points[k];
      const Vec3 in = Vec3::Load(&wi[3 * k]);
      const float* u = &uniform[3 * k];
      Vec3 out;
      uint32_t lobe = yarf::kScatterNone;
      if (in.z != 0) lobe = Draw(m, in, u, allowed, &out);
      const float density = lobe != yarf::kScatterNone ? Density(m, in, out, allowed) : 0.0f;
      if (!(density > 0)) {
        rows.StoreNoSample(k);
        continue;
      }
      rows.Store(k, out, Value(m, in, out, mode, allowed) * (std::abs(out.z) / density), density, lobe);
    }
  }

  void Pdf(std::span<const float> wi, std::span<const float> wo, const yarf::SurfacePoints& at,
           std::span<float> pdf) const override {
    const Points points(base_, values_, at);
    yarf::PdfEach(wi, wo, pdf, [&](size_t k, Vec3 in, Vec3 out) { return Density(points[k], in, out, 0); });
  }

  uint32_t Lobes() const override {
    return kDiffuseLobe | kGlossyLobe | (values_[kSpecTrans].IsZero() ? 0u : kRefractLobe);
  }

 private:
  static std::array<yarf::TexturedValue, kParameterCount> ReadParameters(const yarf::Properties& props) {
    std::array<yarf::TexturedValue, kParameterCount> values;
    for (int i = 0; i < kParameterCount; ++i) values[i] = pr::ReadWeight(props, kParameters[i]);
    return values;
  }

  // The odds of the allowed lobes at wi's side.
  Odds LobeOdds(const Material& m, bool outside, uint32_t allowed) const {
    const bool reflect = yarf::LobeAllowed(kGlossyLobe, allowed);
    const bool refract = yarf::LobeAllowed(kRefractLobe, allowed) && m.glass_weight > 0;
    Odds odds;
    if (outside) {
      if (yarf::LobeAllowed(kDiffuseLobe, allowed)) odds.diffuse = m.diffuse_weight * diffuse_rate_;
      if (reflect) odds.clearcoat = 0.25f * m.p[kClearcoat] * clearcoat_rate_;
      if (reflect || refract) odds.specular = specular_rate_;
    } else if (m.glass_weight > 0 && (reflect || refract)) {
      odds.specular = 1.0f;  // inside, only the glass scatters
    }
    const float total = odds.diffuse + odds.clearcoat + odds.specular;
    if (!(total > 0)) return {};
    return {odds.diffuse / total, odds.clearcoat / total, odds.specular / total};
  }

  // Mitsuba's odds of reflecting and refracting at a microfacet of
  // dielectric Fresnel factor `fresnel`, among the allowed ones.
  static Split SpecularSplit(const Material& m, bool outside, float fresnel, uint32_t allowed) {
    Split split;
    if (yarf::LobeAllowed(kGlossyLobe, allowed))
      split.reflect = outside ? 1.0f - m.glass_weight * (1.0f - fresnel) : fresnel;
    if (yarf::LobeAllowed(kRefractLobe, allowed) && m.glass_weight > 0)
      split.refract = outside ? m.glass_weight * (1.0f - fresnel) : 1.0f - fresnel;
    const float total = split.reflect + split.refract;
    if (!(total > 0)) return {};
    return {split.reflect / total, split.refract / total};
  }

  // Draws wo from one allowed lobe; returns its flags (none on failure).
  uint32_t Draw(const Material& m, Vec3 wi, const float* u, uint32_t allowed, Vec3* wo) const {
    const bool outside = wi.z > 0;
    const Odds odds = LobeOdds(m, outside, allowed);
    if (u[0] < odds.diffuse) {
      *wo = yarf::SampleCosineHemisphere(u[1], u[2]);
      return kDiffuseLobe;
    }
    if (u[0] < odds.diffuse + odds.clearcoat) {
      *wo = mf::ReflectAbout(wi, SampleGtr1(m.clearcoat_alpha, u[1], u[2]));
      return wo->z > 0 ? kGlossyLobe : yarf::kScatterNone;
    }
    if (!(odds.specular > 0)) return yarf::kScatterNone;
    // Normals visible from wi's side; the rest of u[0] picks reflection
    // or refraction.
    const Vec3 h = mf::SampleVisibleNormal(outside ? wi : -wi, m.specular, u[1], u[2]);
    const Split split = SpecularSplit(m, outside, yarf::FresnelDielectric(yarf::Dot(wi, h), eta_), allowed);
    const float pick = (u[0] - odds.diffuse - odds.clearcoat) / odds.specular;
    if (pick < split.reflect) {
      *wo = mf::ReflectAbout(wi, h);
      return wo->z * wi.z > 0 ? kGlossyLobe : yarf::kScatterNone;
    }
    if (split.refract > 0 && mf::RefractAbout(wi, h, eta_, wo) && wo->z * wi.z < 0) return kRefractLobe;
    return yarf::kScatterNone;
  }

  // The half vector of (wi, wo), or false at grazing directions.
  bool At(Vec3 wi, Vec3 wo, Pair* out) const {
    if (wi.z == 0 || wo.z == 0) return false;
    Pair pair;
    pair.reflect = wi.z * wo.z > 0;
    pair.outside = wi.z > 0;
    pair.eta = pair.reflect ? 1.0f : (pair.outside ? eta_ : 1.0f / eta_);
    const Vec3 h = wi + wo * pair.eta;
    const float length = yarf::Length(h);
    if (!(length > 0)) return false;
    pair.h = h.z < 0 ? -h / length : h / length;
    // The facet must face wi, and face wo (reflection) or away from it.
    const Vec3 facing = pair.outside ? pair.h : -pair.h;
    const float wo_side = yarf::Dot(wo, facing);
    pair.compatible = yarf::Dot(wi, facing) > 0 && (pair.reflect ? wo_side > 0 : wo_side < 0);
    pair.fresnel = yarf::FresnelDielectric(yarf::Dot(wi, pair.h), eta_);
    *out = pair;
    return true;
  }

  // f of the allowed lobes (0: all).
  Vec3 Value(const Material& m, Vec3 wi, Vec3 wo, yarf::TransportMode mode, uint32_t allowed) const {
    Pair pair;
    if (!At(wi, wo, &pair)) return Vec3();
    const float cos_i = std::abs(wi.z), cos_o = std::abs(wo.z);
    const float cos_ih = yarf::Dot(wi, pair.h), cos_oh = yarf::Dot(wo, pair.h);
    Vec3 out;
    if (!pair.reflect) {
      if (!pair.compatible || !(m.glass_weight > 0) || !yarf::LobeAllowed(kRefractLobe, allowed)) return out;
      const float denominator = cos_ih + pair.eta * cos_oh;
      float f = m.glass_weight * (1.0f - pair.fresnel) * mf::Ndf(pair.h, m.specular) *
                mf::SmithG2(wi, wo, m.specular) * std::abs(cos_ih * cos_oh) /
                (cos_i * cos_o * denominator * denominator);
      if (mode == yarf::TransportMode::kImportance) f *= pair.eta * pair.eta;
      const Vec3 c = m.base;
      return Vec3(std::sqrt(c.x), std::sqrt(c.y), std::sqrt(c.z)) * f;
    }
    if (pair.compatible && yarf::LobeAllowed(kGlossyLobe, allowed)) {
      const Vec3 fresnel = pair.outside ? PrincipledFresnel(m, pair.fresnel, cos_ih)
                                        : Vec3(1.0f, 1.0f, 1.0f) * (m.glass_weight * pair.fresnel);
      out += fresnel * (mf::Ndf(pair.h, m.specular) * mf::SmithG2(wi, wo, m.specular) / (4.0f * cos_i * cos_o));
      if (pair.outside && m.p[kClearcoat] > 0) {
        const float coat = 0.25f * m.p[kClearcoat] * pr::Schlick(Vec3(0.04f, 0.04f, 0.04f), cos_ih, eta_).x *
                           Gtr1(pair.h.z, m.clearcoat_alpha) * mf::SmithG1(wi, kClearcoatMasking) *
                           mf::SmithG1(wo, kClearcoatMasking);
        out += Vec3(coat, coat, coat);
      }
    }
    if (pair.outside && m.diffuse_weight > 0 && yarf::LobeAllowed(kDiffuseLobe, allowed))
      out += Diffuse(m, cos_i, cos_o, cos_oh);
    return out;
  }

  // The main lobe's Fresnel factor from outside: the dielectric's, the
  // metal's (Schlick's of base_color) and the tinted dielectric's blended.
  Vec3 PrincipledFresnel(const Material& m, float dielectric, float cos_ih) const {
    const float metallic = m.p[kMetallic], tint = m.p[kSpecTint];
    Vec3 out = Vec3(1.0f, 1.0f, 1.0f) * ((1.0f - metallic) * (1.0f - tint) * dielectric);
    if (metallic > 0) out += metallic * pr::Schlick(m.base, cos_ih, eta_);
    if (tint > 0) {
      const float r0 = pr::NormalReflectance(cos_ih >= 0 ? eta_ : 1.0f / eta_);
      out += (1.0f - metallic) * tint * pr::Schlick(pr::Tint(m.base) * r0, cos_ih, eta_);
    }
    return out;
  }

  // The diffuse base (with retro-reflection and fake subsurface) and the
  // sheen; θd is the angle between h and wo.
  static Vec3 Diffuse(const Material& m, float cos_i, float cos_o, float cos_d) {
    const float shape = pr::DiffuseShape(m.p[kRoughness], m.p[kFlatness], cos_i, cos_o, cos_d);
    Vec3 out = m.base * (m.diffuse_weight * shape * yarf::kInvPi);
    if (m.p[kSheen] > 0 && m.p[kMetallic] < 1)
      out += pr::Sheen(m.base, m.p[kSheenTint], cos_d) * (m.p[kSheen] * (1.0f - m.p[kMetallic]));
    return out;
  }

  // The density of the mixture of the allowed lobes Sample draws from.
  float Density(const Material& m, Vec3 wi, Vec3 wo, uint32_t allowed) const {
    Pair pair;
    if (!At(wi, wo, &pair)) return 0.0f;
    const Odds odds = LobeOdds(m, pair.outside, allowed);
    float density = 0;
    if (pair.reflect && pair.outside) density += odds.diffuse * yarf::CosineHemispherePdf(wo.z);
    if (!pair.compatible) return density;
    const float visible = mf::VisibleNormalPdf(pair.outside ? wi : -wi, pair.h, m.specular);
    const Split split = SpecularSplit(m, pair.outside, pair.fresnel, allowed);
    const float cos_oh = std::abs(yarf::Dot(wo, pair.h));
    if (pair.reflect) {
      // dh/dwo = 1 / (4 |wo·h|).
      const float jacobian = 1.0f / (4.0f * cos_oh);
      density += odds.specular * split.reflect * visible * jacobian;
      if (pair.outside) density += odds.clearcoat * Gtr1(pair.h.z, m.clearcoat_alpha) * pair.h.z * jacobian;
    } else {
      // dh/dwo = η² |wo·h| / (wi·h + η wo·h)² (Walter et al., eq. 17).
      const float denominator = yarf::Dot(wi, pair.h) + pair.eta * yarf::Dot(wo, pair.h);
      density += odds.specular * split.refract * visible * pair.eta * pair.eta * cos_oh /
                 (denominator * denominator);
    }
    return density;
  }

  yarf::TexturedValue base_;
  std::array<yarf::TexturedValue, kParameterCount> values_;
  // Interior over exterior index of refraction.
  float eta_;
  float diffuse_rate_, specular_rate_, clearcoat_rate_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Principled>(registrar, "principled", "1.0.0",
                             "Principled (Disney) BSDF as in Mitsuba 3: diffuse, sheen, metal, "
                             "glass and clear coat lobes blended by parameters in [0, 1]");
}
