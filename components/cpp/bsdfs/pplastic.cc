// pplastic — a rough dielectric coating over a diffuse base, each
// reflecting on its own
//
// Mitsuba 3's `pplastic` (its polarized plastic, after Baek et al. 2020)
// as Mitsuba renders it in RGB: the coating reflects like a rough
// dielectric (microfacet.h), and the base is seen through the smooth
// interface's Fresnel transmittance on the way in and out, with none of
// the light the coating reflects back inside (roughplastic's r̄, η²):
//
//   f(wi, wo) = R F(wi·h) D(h) G2(wi, wo) / (4 cos θi cos θo)
//             + ρ (1 - F(cos θi)) (1 - F(cos θo)) / π
//
// with h = (wi + wo)/|wi + wo|, F the dielectric Fresnel reflectance for
// η = int_ior / ext_ior, R = specular_reflectance, ρ =
// diffuse_reflectance. One-sided, as in Mitsuba: 0 unless wi and wo lie
// above.
//
// Parameters: PPlastic::Parameters() below; the indices' defaults are
// polypropylene inside and air outside; the roughness may be anisotropic
// and textured.
//
// Lobes: glossy reflection and diffuse reflection. Sample picks the glossy
// lobe with probability F s / (F s + (1 - F)(1 - s)), F = F(cos θi), s =
// mean(R) / (mean(R) + mean(ρ)) at the point, or the one lobe `allowed`
// leaves; it draws the glossy lobe from the normals visible from wi, the
// diffuse one from the cosine-weighted hemisphere, and returns the density
// and value of the mixture of the allowed lobes.
#include <cmath>
#include <cstdint>
#include <span>

#include "coating.h"
#include "microfacet.h"
#include "surface_properties.h"
#include "yarf/plugin.h"
#include "yarf/support/scatter_rows.h"
#include "yarf/support/warps.h"
#include "yarf/texture.h"

namespace {

using yarf::Vec3;
namespace mf = yarf::microfacet;

constexpr uint32_t kGlossyLobe = yarf::kScatterReflect | yarf::kScatterGlossy;
constexpr uint32_t kDiffuseLobe = yarf::kScatterReflect | yarf::kScatterDiffuse;

class PPlastic final : public yarf::SurfaceModel {
 public:
  static yarf::ParameterSchema Parameters() {
    using P = yarf::Parameter;
    return yarf::JoinParameters({
        {P::RgbTexture("diffuse_reflectance").Default(0.5).Range(0, 1).Doc("ρ, the base's colour, per channel"),
         P::RgbTexture("specular_reflectance")
             .Default(1.0)
             .Range(0, 1)
             .Doc("R, a factor on the coating's reflection (for realism, 1)")},
        mf::RoughnessParameters(0.1, /*anisotropic=*/true, /*textured=*/true),
        yarf::RelativeIndexParameters(1.49, 1.000277),
    });
  }

  explicit PPlastic(const yarf::Properties& props)
      : diffuse_(yarf::TexturedValue::Color(props, "diffuse_reflectance", Vec3(0.5f, 0.5f, 0.5f), /*unit=*/true)),
        specular_(yarf::TexturedValue::Color(props, "specular_reflectance", Vec3(1.0f, 1.0f, 1.0f), /*unit=*/true)),
        roughness_(mf::ReadTexturedRoughness(props, 0.1, /*anisotropic=*/true)),
        eta_(yarf::ReadRelativeIndex(props, 1.49, 1.000277)) {}

  void Evaluate(yarf::TransportMode, std::span<const float> wi, std::span<const float> wo,
                const yarf::SurfacePoints& at, std::span<float> value) const override {
    const Layers layers(*this, at);
    yarf::EvaluateEach(wi, wo, value,
                       [&](size_t k, Vec3 in, Vec3 out) { return Value(layers, k, in, out, true, true); });
  }

  void Sample(yarf::TransportMode, std::span<const float> wi, const yarf::SurfacePoints& at,
              std::span<const float> uniform, uint32_t allowed, std::span<float> wo, std::span<float> weight,
              std::span<float> pdf, std::span<uint32_t> flags) const override {
    const Layers layers(*this, at);
    const bool can_glossy = yarf::LobeAllowed(kGlossyLobe, allowed) && !specular_.IsZero();
    const bool can_diffuse = yarf::LobeAllowed(kDiffuseLobe, allowed) && !diffuse_.IsZero();
    const yarf::SampleRows rows{wo, weight, pdf, flags};
    for (size_t k = 0; k < wi.size() / 3; ++k) {
      const Vec3 in = Vec3::Load(&wi[3 * k]);
      const float* u = &uniform[3 * k];
      if (!(in.z > 0) || !(can_glossy || can_diffuse)) {
        rows.StoreNoSample(k);
        continue;
      }
      const float p_glossy = GlossyProbability(layers, k, in.z, can_glossy, can_diffuse);
      const bool pick_glossy = u[0] < p_glossy;
      const mf::Roughness roughness = layers.roughness[k];
      const Vec3 out = pick_glossy ? mf::ReflectAbout(in, mf::SampleVisibleNormal(in, roughness, u[1], u[2]))
                                   : yarf::SampleCosineHemisphere(u[1], u[2]);
      const float density = yarf::coating::RoughCoatingDensity(roughness, in, out, p_glossy);
      if (!(density > 0)) {
        rows.StoreNoSample(k);
        continue;
      }
      rows.Store(k, out, Value(layers, k, in, out, can_glossy, can_diffuse) * (out.z / density), density,
                 pick_glossy ? kGlossyLobe : kDiffuseLobe);
    }
  }

  void Pdf(std::span<const float> wi, std::span<const float> wo, const yarf::SurfacePoints& at,
           std::span<float> pdf) const override {
    const Layers layers(*this, at);
    const bool glossy = !specular_.IsZero(), diffuse = !diffuse_.IsZero();
    yarf::PdfEach(wi, wo, pdf, [&](size_t k, Vec3 in, Vec3 out) {
      if (!(in.z > 0) || !(glossy || diffuse)) return 0.0f;
      const float p_glossy = GlossyProbability(layers, k, in.z, glossy, diffuse);
      return yarf::coating::RoughCoatingDensity(layers.roughness[k], in, out, p_glossy);
    });
  }

  uint32_t Lobes() const override {
    return (specular_.IsZero() ? 0u : kGlossyLobe) | (diffuse_.IsZero() ? 0u : kDiffuseLobe);
  }

 private:
  // The colours and roughness at a call's points.
  struct Layers {
    Layers(const PPlastic& model, const yarf::SurfacePoints& at)
        : diffuse(model.diffuse_.At(at)), specular(model.specular_.At(at)), roughness(model.roughness_.At(at)) {}
    yarf::PointValues<Vec3> diffuse, specular;
    mf::PointRoughness roughness;
  };

  // The odds of the glossy lobe among the lobes in play, at cos θi > 0.
  float GlossyProbability(const Layers& layers, size_t k, float cos_i, bool glossy, bool diffuse) const {
    if (!glossy) return 0.0f;
    if (!diffuse) return 1.0f;
    const float s = yarf::coating::WeighLobes(layers.diffuse[k], layers.specular[k]).specular_weight;
    const float fresnel = yarf::FresnelDielectric(cos_i, eta_);
    const float g = fresnel * s, b = (1 - fresnel) * (1 - s);
    return g + b > 0 ? g / (g + b) : 0.0f;
  }

  // f of the lobes asked for.
  Vec3 Value(const Layers& layers, size_t k, Vec3 wi, Vec3 wo, bool glossy, bool diffuse) const {
    if (!(wi.z > 0 && wo.z > 0)) return Vec3();
    Vec3 out;
    if (glossy)
      out += layers.specular[k] * yarf::coating::RoughCoatingReflection(layers.roughness[k], eta_, wi, wo);
    if (diffuse) {
      const float through = (1 - yarf::FresnelDielectric(wi.z, eta_)) * (1 - yarf::FresnelDielectric(wo.z, eta_));
      out += layers.diffuse[k] * (through * yarf::kInvPi);
    }
    return out;
  }

  yarf::TexturedValue diffuse_, specular_;
  mf::TexturedRoughness roughness_;
  float eta_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<PPlastic>(registrar, "pplastic", "1.0.0",
                           "Rough dielectric coating and diffuse base reflecting apart, as Mitsuba 3's pplastic in "
                           "RGB (one-sided)");
}
