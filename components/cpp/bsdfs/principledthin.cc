// principledthin — the thin Disney BSDF, as Mitsuba 3's `principledthin`
//
// Burley's model of a thin translucent sheet ("Extending the Disney BRDF
// to a BSDF with integrated subsurface scattering", 2015, §4) in the form
// Mitsuba 3 gives it: a surface without inside (leaves, paper, a curtain,
// a soap film) that scatters alike from both sides, reflecting and
// transmitting. With s = spec_trans, d = diff_trans / 2 and c = base_color,
// and wo' the mirror image through the sheet of a wo on the other side of
// it, h the half vector of wi and wo (or wo'):
//
//   diffuse      (1 - s)(1 - d) c/π (f_d + f_r), blended toward the fake
//                subsurface term f_ss by flatness (principled.cc's base)
//   sheen        sheen (1 - s)(1 - d) (1 - cos θd)⁵ lerp(1, c/lum(c), sheen_tint)
//   specular     s F D G2 / (4 cos θi cos θo), GGX of α = ρ² stretched by
//                anisotropic, F = lerp(F_dielectric(η), Schlick(c/lum(c) R0(η)),
//                spec_tint)
//   transmission s c (1 - F_dielectric) D' G2' / (4 cos θi cos θo) at (wi, wo'):
//                light passes the sheet unbent, blurred by GGX of the roughness
//                scaled by (0.65 η - 0.35) (Burley 2015, fig. 15)
//   translucency (1 - s) d c/π into the other side (Lambert's law)
//
// θd is the angle between h and wo (or wo'). The sheet has the same medium
// on both sides, so radiance and importance scatter alike, and f is
// symmetric in wi and wo.
//
// Differences from Mitsuba: G2 is Smith's height-correlated joint masking
// (microfacet.h) where Mitsuba multiplies two G1s, as in principled.cc.
// Mitsuba also drops the transmission where wo itself (not its mirror
// image wo', whose masking the lobe models) faces the microfacet, mostly
// where wo lies low; that rule is not symmetric in wi and wo (Mitsuba's
// sheet is not reciprocal there), so yarf keeps the whole lobe. Together
// they make yarf's sheet transmit a little more: at roughness 0.5, 1.4%
// at normal incidence to 6% at cos θi = 0.1. The diffuse, sheen and
// translucent lobes, and every density, are Mitsuba's. The luminance is
// Rec. 709's (vecmath.h).
//
// Parameters: PrincipledThin::Parameters() below. A texture's values are
// clamped to the parameter's range (eta's to [0.01, 100]).
//
// Lobes: diffuse reflection (diffuse and sheen); when spec_trans is not 0,
// glossy reflection and glossy transmission (kScatterRefract: wo on the
// other side); when diff_trans is not 0, diffuse transmission. Sample
// picks the specular reflection, the specular transmission, the diffuse
// reflection or the translucency with Mitsuba's odds s/2 (rate) : s/2
// (rate) : (1 - s)(1 - d) (rate) : (1 - s) d (rate), among the allowed
// lobes; the specular lobes draw a normal visible from wi (Heitz 2018)
// and reflect about it (mirrored through the sheet to transmit), the
// others a cosine-weighted direction. It returns the density and value of
// the mixture of the allowed lobes.
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <utility>

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

constexpr uint32_t kDiffuseReflectLobe = yarf::kScatterReflect | yarf::kScatterDiffuse;
constexpr uint32_t kDiffuseTransmitLobe = yarf::kScatterRefract | yarf::kScatterDiffuse;
constexpr uint32_t kGlossyReflectLobe = yarf::kScatterReflect | yarf::kScatterGlossy;
constexpr uint32_t kGlossyTransmitLobe = yarf::kScatterRefract | yarf::kScatterGlossy;

// The scalar parameters, each a number or a texture: one table read by
// the constructor and indexed by the model.
enum Parameter {
  kRoughness, kAnisotropic, kSpecTrans, kSpecTint, kSheen, kSheenTint, kFlatness, kDiffTrans, kEta,
  kParameterCount
};
// The weights among them (all but eta).
constexpr pr::ParameterInfo kWeights[kEta] = {
    {"roughness", 0.5f, "ρ: the specular lobes' GGX α is ρ²"},
    {"anisotropic", 0.0f, "stretches the specular lobes along the shading frame's x"},
    {"spec_trans", 0.0f, "s: the share of the specular reflection and transmission"},
    {"spec_tint", 0.0f, "tints the specular reflection toward the hue of base_color"},
    {"sheen", 0.0f, "the sheen at grazing angles"},
    {"sheen_tint", 0.0f, "tints the sheen toward the hue of base_color"},
    {"flatness", 0.0f, "blends the diffuse base toward the fake subsurface term"},
    {"diff_trans", 0.0f, "twice the diffuse lobe's share sent to the other side (2: all of it)", 2.0f}};

// A textured index is kept where the Fresnel factor and the roughness
// scaling stay finite and meaningful.
constexpr float kMinEta = 0.01f, kMaxEta = 100.0f;

yarf::TexturedValue ReadEta(const yarf::Properties& props) {
  if (auto texture = props.TextureOf("eta")) return yarf::TexturedValue(std::move(texture)).Clamped(kMinEta, kMaxEta);
  return yarf::TexturedValue(yarf::RequireIndex(props.Float("eta", 1.5), "eta"));
}

// The parameters at one point, and what the lobes derive from them.
struct Material {
  Vec3 base;
  std::array<float, kParameterCount> p{};
  mf::Roughness reflection;    // GGX of the specular reflection
  mf::Roughness transmission;  // GGX of the specular transmission
  float diffuse_weight = 0;    // (1 - spec_trans)(1 - diff_trans/2)
  float translucent_weight = 0;  // (1 - spec_trans) diff_trans/2

  Material(Vec3 base_color, const std::array<float, kParameterCount>& values) : base(base_color), p(values) {
    reflection = pr::DisneyRoughness(p[kRoughness], p[kAnisotropic]);
    // A sheet's transmission blurs less than its reflection, by the index
    // (Burley 2015, fig. 15).
    transmission = pr::DisneyRoughness((0.65f * p[kEta] - 0.35f) * p[kRoughness], p[kAnisotropic]);
    const float diff_trans = 0.5f * p[kDiffTrans];
    diffuse_weight = (1.0f - p[kSpecTrans]) * (1.0f - diff_trans);
    translucent_weight = (1.0f - p[kSpecTrans]) * diff_trans;
  }
};

using Points = pr::PointParameters<Material, kParameterCount>;

// The odds of each lobe Sample draws, summing to 1 (or all 0).
struct Odds {
  float glossy_reflect = 0, glossy_transmit = 0, diffuse_reflect = 0, diffuse_transmit = 0;
};

// How wi and wo meet, seen from wi's side (both sides of the sheet are
// alike): wi and wo' (wo, mirrored through the sheet when it lies on the
// other side) above it, and their half vector.
struct Pair {
  bool reflect = false;
  Vec3 wi, wo, h;
};

// The pair of (wi, wo), or false at grazing directions.
bool At(Vec3 wi, Vec3 wo, Pair* out) {
  if (wi.z == 0 || wo.z == 0) return false;
  Pair pair;
  pair.reflect = wi.z * wo.z > 0;
  pair.wi = Vec3(wi.x, wi.y, std::abs(wi.z));
  pair.wo = Vec3(wo.x, wo.y, std::abs(wo.z));
  // Both above the sheet: their half vector faces each of them.
  pair.h = yarf::Normalize(pair.wi + pair.wo);
  *out = pair;
  return true;
}

class PrincipledThin final : public yarf::SurfaceModel {
 public:
  static yarf::ParameterSchema Parameters() {
    yarf::ParameterSchema schema = {pr::BaseColorParameter()};
    for (const pr::ParameterInfo& info : kWeights) schema.push_back(pr::WeightParameter(info));
    schema.push_back(yarf::Parameter::FloatTexture("eta").Default(1.5).Min(0).Doc("the sheet's index of refraction"));
    for (const char* rate : {"specular_reflectance_sampling_rate", "specular_transmittance_sampling_rate",
                             "diffuse_reflectance_sampling_rate", "diffuse_transmittance_sampling_rate"})
      schema.push_back(pr::SamplingRateParameter(rate));
    return schema;
  }

  explicit PrincipledThin(const yarf::Properties& props)
      : base_(pr::ReadBaseColor(props)),
        values_(ReadParameters(props)),
        specular_reflect_rate_(pr::ReadSamplingRate(props, "specular_reflectance_sampling_rate")),
        specular_transmit_rate_(pr::ReadSamplingRate(props, "specular_transmittance_sampling_rate")),
        diffuse_reflect_rate_(pr::ReadSamplingRate(props, "diffuse_reflectance_sampling_rate")),
        diffuse_transmit_rate_(pr::ReadSamplingRate(props, "diffuse_transmittance_sampling_rate")) {}

  // The sheet has one medium on both sides: no 1/η² of radiance, so the
  // transport modes agree.
  void Evaluate(yarf::TransportMode, std::span<const float> wi, std::span<const float> wo,
                const yarf::SurfacePoints& at, std::span<float> value) const override {
    const Points points(base_, values_, at);
    yarf::EvaluateEach(wi, wo, value, [&](size_t k, Vec3 in, Vec3 out) { return Value(points[k], in, out, 0); });
  }

  void Sample(yarf::TransportMode, std::span<const float> wi, const yarf::SurfacePoints& at,
              std::span<const float> uniform, uint32_t allowed, std::span<float> wo,
              std::span<float> weight, std::span<float> pdf,
              std::span<uint32_t> flags) const override {
    const size_t count = wi.size() / 3;
    const Points points(base_, values_, at);
    const yarf::SampleRows rows{wo, weight, pdf, flags};
    for (size_t k = 0; k < count; ++k) {
      const Material m = points[k];
      const Vec3 in = Vec3::Load(&wi[3 * k]);
      Vec3 out;
      uint32_t lobe = yarf::kScatterNone;
      if (in.z != 0) lobe = Draw(m, in, &uniform[3 * k], allowed, &out);
      const float density = lobe != yarf::kScatterNone ? Density(m, in, out, allowed) : 0.0f;
      if (!(density > 0)) {
        rows.StoreNoSample(k);
        continue;
      }
      rows.Store(k, out, Value(m, in, out, allowed) * (std::abs(out.z) / density), density, lobe);
    }
  }

  void Pdf(std::span<const float> wi, std::span<const float> wo, const yarf::SurfacePoints& at,
           std::span<float> pdf) const override {
    const Points points(base_, values_, at);
    yarf::PdfEach(wi, wo, pdf, [&](size_t k, Vec3 in, Vec3 out) { return Density(points[k], in, out, 0); });
  }

  uint32_t Lobes() const override {
    uint32_t lobes = kDiffuseReflectLobe;
    if (!values_[kSpecTrans].IsZero()) lobes |= kGlossyReflectLobe | kGlossyTransmitLobe;
    if (!values_[kDiffTrans].IsZero()) lobes |= kDiffuseTransmitLobe;
    return lobes;
  }

 private:
  static std::array<yarf::TexturedValue, kParameterCount> ReadParameters(const yarf::Properties& props) {
    std::array<yarf::TexturedValue, kParameterCount> values;
    for (int i = 0; i < kEta; ++i) values[i] = pr::ReadWeight(props, kWeights[i]);
    values[kEta] = ReadEta(props);
    return values;
  }

  // The odds of the allowed lobes.
  Odds LobeOdds(const Material& m, uint32_t allowed) const {
    Odds odds;
    const float spec_trans = m.p[kSpecTrans];
    if (yarf::LobeAllowed(kGlossyReflectLobe, allowed)) odds.glossy_reflect = 0.5f * spec_trans * specular_reflect_rate_;
    if (yarf::LobeAllowed(kGlossyTransmitLobe, allowed))
      odds.glossy_transmit = 0.5f * spec_trans * specular_transmit_rate_;
    if (yarf::LobeAllowed(kDiffuseReflectLobe, allowed)) odds.diffuse_reflect = m.diffuse_weight * diffuse_reflect_rate_;
    if (yarf::LobeAllowed(kDiffuseTransmitLobe, allowed))
      odds.diffuse_transmit = m.translucent_weight * diffuse_transmit_rate_;
    const float total = odds.glossy_reflect + odds.glossy_transmit + odds.diffuse_reflect + odds.diffuse_transmit;
    if (!(total > 0)) return {};
    return {odds.glossy_reflect / total, odds.glossy_transmit / total, odds.diffuse_reflect / total,
            odds.diffuse_transmit / total};
  }

  // Draws wo from one allowed lobe; returns its flags (none on failure).
  uint32_t Draw(const Material& m, Vec3 wi, const float* u, uint32_t allowed, Vec3* wo) const {
    const Odds odds = LobeOdds(m, allowed);
    const Vec3 in(wi.x, wi.y, std::abs(wi.z));
    // The direction above the sheet on wi's side, and the lobe.
    Vec3 above;
    uint32_t lobe = yarf::kScatterNone;
    if (u[0] < odds.glossy_reflect + odds.glossy_transmit) {
      const bool reflect = u[0] < odds.glossy_reflect;
      const Vec3 h = mf::SampleVisibleNormal(in, reflect ? m.reflection : m.transmission, u[1], u[2]);
      above = mf::ReflectAbout(in, h);
      if (!(above.z > 0)) return yarf::kScatterNone;
      lobe = reflect ? kGlossyReflectLobe : kGlossyTransmitLobe;
    } else if (u[0] < odds.glossy_reflect + odds.glossy_transmit + odds.diffuse_reflect) {
      above = yarf::SampleCosineHemisphere(u[1], u[2]);
      lobe = kDiffuseReflectLobe;
    } else if (odds.diffuse_transmit > 0) {
      above = yarf::SampleCosineHemisphere(u[1], u[2]);
      lobe = kDiffuseTransmitLobe;
    } else {
      return yarf::kScatterNone;
    }
    // Back to wi's side, and through the sheet for a transmission.
    const bool same_side = (lobe & yarf::kScatterReflect) != 0;
    *wo = Vec3(above.x, above.y, (wi.z > 0) == same_side ? above.z : -above.z);
    return above.z > 0 ? lobe : yarf::kScatterNone;
  }

  // f of the allowed lobes (0: all).
  Vec3 Value(const Material& m, Vec3 wi, Vec3 wo, uint32_t allowed) const {
    Pair pair;
    if (!At(wi, wo, &pair)) return Vec3();
    const float cos_i = pair.wi.z, cos_o = pair.wo.z;
    const float cos_h = yarf::Dot(pair.wi, pair.h);  // = wo'·h
    const float eta = m.p[kEta], spec_trans = m.p[kSpecTrans];
    const float fresnel = spec_trans > 0 ? yarf::FresnelDielectric(cos_h, eta) : 0.0f;
    Vec3 out;
    if (pair.reflect) {
      if (spec_trans > 0 && yarf::LobeAllowed(kGlossyReflectLobe, allowed)) {
        Vec3 f = Vec3(1.0f, 1.0f, 1.0f) * fresnel;
        if (m.p[kSpecTint] > 0) {
          const Vec3 tinted = pr::Schlick(pr::Tint(m.base) * pr::NormalReflectance(eta), cos_h, eta);
          f = pr::Lerp(f, tinted, m.p[kSpecTint]);
        }
        out += f * (spec_trans * Microfacet(pair, m.reflection) / (4.0f * cos_i * cos_o));
      }
      if (m.diffuse_weight > 0 && yarf::LobeAllowed(kDiffuseReflectLobe, allowed)) {
        const float shape = pr::DiffuseShape(m.p[kRoughness], m.p[kFlatness], cos_i, cos_o, cos_h);
        out += m.base * (m.diffuse_weight * shape * yarf::kInvPi);
        if (m.p[kSheen] > 0) out += pr::Sheen(m.base, m.p[kSheenTint], cos_h) * (m.p[kSheen] * m.diffuse_weight);
      }
      return out;
    }
    if (spec_trans > 0 && yarf::LobeAllowed(kGlossyTransmitLobe, allowed))
      out += m.base * (spec_trans * (1.0f - fresnel) * Microfacet(pair, m.transmission) / (4.0f * cos_i * cos_o));
    if (m.translucent_weight > 0 && yarf::LobeAllowed(kDiffuseTransmitLobe, allowed))
      out += m.base * (m.translucent_weight * yarf::kInvPi);
    return out;
  }

  // D G2 of a specular lobe at the pair's half vector.
  static float Microfacet(const Pair& pair, const mf::Roughness& roughness) {
    return mf::Ndf(pair.h, roughness) * mf::SmithG2(pair.wi, pair.wo, roughness);
  }

  // The density of the mixture of the allowed lobes Sample draws from.
  float Density(const Material& m, Vec3 wi, Vec3 wo, uint32_t allowed) const {
    Pair pair;
    if (!At(wi, wo, &pair)) return 0.0f;
    const Odds odds = LobeOdds(m, allowed);
    const float diffuse = pair.reflect ? odds.diffuse_reflect : odds.diffuse_transmit;
    const float glossy = pair.reflect ? odds.glossy_reflect : odds.glossy_transmit;
    float density = diffuse * yarf::CosineHemispherePdf(pair.wo.z);
    if (glossy > 0) {
      // dh/dwo' = 1 / (4 wo'·h); the mirror image through the sheet keeps
      // solid angle.
      const mf::Roughness& roughness = pair.reflect ? m.reflection : m.transmission;
      density += glossy * mf::VisibleNormalPdf(pair.wi, pair.h, roughness) / (4.0f * yarf::Dot(pair.wo, pair.h));
    }
    return density;
  }

  yarf::TexturedValue base_;
  std::array<yarf::TexturedValue, kParameterCount> values_;
  float specular_reflect_rate_, specular_transmit_rate_, diffuse_reflect_rate_, diffuse_transmit_rate_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<PrincipledThin>(registrar, "principledthin", "1.0.0",
                                 "Thin principled (Disney) BSDF as in Mitsuba 3: a two-sided sheet with "
                                 "diffuse, sheen, specular, rough transmission and translucency lobes");
}
