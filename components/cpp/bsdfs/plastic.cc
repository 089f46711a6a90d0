// plastic — smooth dielectric coating over a diffuse base
//
// Mitsuba 3's `plastic`: a smooth dielectric interface of relative index
// η = int_ior / ext_ior over a diffuse base of reflectance ρ, with the
// light scattered between them summed in closed form. The interface
// reflects F(cos θi) into the mirror direction (a delta lobe, weighted by
// specular_reflectance); the rest enters, is scattered by the base and
// partly reflected back by the interface from inside, whose diffuse
// Fresnel reflectance is F_dr,int (microfacet.h). What leaves is diffuse:
//
//   f(wi, wo) = ρ' (1 - F(cos θi)) (1 - F(cos θo)) / (η² π),
//   ρ' = ρ / (1 - F_dr,int)          (nonlinear = false, the default)
//   ρ' = ρ / (1 - ρ F_dr,int)        (nonlinear = true)
//
// The default keeps the material's colour ρ, as Mitsuba's does; then its
// albedo is F(cos θi) + ρ (1 - F(cos θi)) exactly (by 1 - F_dr,ext = η²
// (1 - F_dr,int)). nonlinear = true darkens and saturates it as a real
// coating does. One-sided, as in Mitsuba: 0 unless wi and wo lie above.
//
// Parameters: Plastic::Parameters() below; the indices' defaults are
// polypropylene inside and air outside. A texture's values are clamped to
// [0, 1].
//
// Lobes: delta reflection and diffuse reflection. Evaluate and Pdf see
// the diffuse lobe only. Sample picks the specular lobe with probability
// F s / (F s + (1 - F)(1 - s)), s = mean(specular) / (mean(specular) +
// mean(ρ)) at the point as in Mitsuba, or the one lobe `allowed` leaves;
// the diffuse lobe samples the cosine-weighted hemisphere. A lobe whose
// colour is 0 at a point is not drawn there.
#include <cmath>
#include <cstdint>
#include <optional>
#include <span>
#include <string>

#include "coating.h"
#include "microfacet.h"
#include "yarf/support/scatter_rows.h"
#include "surface_properties.h"
#include "yarf/plugin.h"
#include "yarf/texture.h"
#include "yarf/support/warps.h"

namespace {

using yarf::Vec3;
namespace mf = yarf::microfacet;

constexpr uint32_t kSpecularLobe = yarf::kScatterReflect | yarf::kScatterDelta;
constexpr uint32_t kDiffuseLobe = yarf::kScatterReflect | yarf::kScatterDiffuse;

class Plastic final : public yarf::SurfaceModel {
 public:
  static yarf::ParameterSchema Parameters() {
    return yarf::JoinParameters({
        yarf::coating::CoatingParameters(),
        yarf::RelativeIndexParameters(1.49, 1.000277),
    });
  }

  explicit Plastic(const yarf::Properties& props)
      : diffuse_(yarf::TexturedValue::Color(props, "diffuse_reflectance",
                                            Vec3(0.5f, 0.5f, 0.5f), /*unit=*/true)),
        specular_(yarf::TexturedValue::Color(props, "specular_reflectance",
                                             Vec3(1.0f, 1.0f, 1.0f), /*unit=*/true)),
        eta_(yarf::ReadRelativeIndex(props, 1.49, 1.000277)),
        // A smooth coating's r̄ is F_dr,int.
        internal_reflectance_(mf::FresnelDiffuseReflectance(1.0f / eta_)),
        nonlinear_(props.Bool("nonlinear", false)) {}

  void Evaluate(yarf::TransportMode, std::span<const float> wi, std::span<const float> wo,
                const yarf::SurfacePoints& at, std::span<float> value) const override {
    const yarf::coating::Points coating(diffuse_, specular_, at, internal_reflectance_, nonlinear_, eta_);
    yarf::EvaluateEach(wi, wo, value, [&](size_t k, Vec3 in, Vec3 out) {
      return Diffuse(coating[k], in, out);
    });
  }

  void Sample(yarf::TransportMode, std::span<const float> wi, const yarf::SurfacePoints& at,
              std::span<const float> uniform, uint32_t allowed, std::span<float> wo,
              std::span<float> weight, std::span<float> pdf,
              std::span<uint32_t> flags) const override {
    const size_t count = wi.size() / 3;
    const bool can_specular = yarf::LobeAllowed(kSpecularLobe, allowed);
    const bool can_diffuse = yarf::LobeAllowed(kDiffuseLobe, allowed);
    const yarf::coating::Points coating(diffuse_, specular_, at, internal_reflectance_, nonlinear_, eta_);
    const yarf::SampleRows rows{wo, weight, pdf, flags};
    for (size_t k = 0; k < count; ++k) {
      const yarf::coating::Point local = coating[k];
      const bool specular = local.lobes.has_specular && can_specular;
      const bool diffuse = local.lobes.has_diffuse && can_diffuse;
      const Vec3 in = Vec3::Load(&wi[3 * k]);
      const float* u = &uniform[3 * k];
      const float p_specular =
          in.z > 0 ? SpecularProbability(local, in.z, specular, diffuse) : 0.0f;
      const bool pick_specular = u[0] < p_specular;
      Vec3 out, w;
      float density = 0;
      if (in.z > 0 && (specular || diffuse)) {
        if (pick_specular) {
          out = yarf::Reflect(in);
          density = p_specular;
          w = local.specular * (yarf::FresnelDielectric(in.z, eta_) / density);
        } else {
          out = yarf::SampleCosineHemisphere(u[1], u[2]);
          density = (1.0f - p_specular) * yarf::CosineHemispherePdf(out.z);
          if (density > 0) w = Diffuse(local, in, out) * (out.z / density);
        }
      }
      if (!(density > 0)) {
        rows.StoreNoSample(k);
        continue;
      }
      rows.Store(k, out, w, density, pick_specular ? kSpecularLobe : kDiffuseLobe);
    }
  }

  void Pdf(std::span<const float> wi, std::span<const float> wo, const yarf::SurfacePoints& at,
           std::span<float> pdf) const override {
    const yarf::coating::Points coating(diffuse_, specular_, at, internal_reflectance_, nonlinear_, eta_);
    yarf::PdfEach(wi, wo, pdf, [&](size_t k, Vec3 in, Vec3 out) {
      const yarf::coating::Point local = coating[k];
      return local.lobes.has_diffuse && in.z > 0 && out.z > 0
                 ? (1.0f - SpecularProbability(local, in.z, local.lobes.has_specular, true)) *
                       yarf::CosineHemispherePdf(out.z)
                 : 0.0f;
    });
  }

  uint32_t Lobes() const override {
    return (specular_.IsZero() ? 0u : kSpecularLobe) | (diffuse_.IsZero() ? 0u : kDiffuseLobe);
  }

 private:
  Vec3 Diffuse(const yarf::coating::Point& local, Vec3 wi, Vec3 wo) const {
    if (!(wi.z > 0 && wo.z > 0) || !local.lobes.has_diffuse) return Vec3();
    const float transmitted =
        (1.0f - yarf::FresnelDielectric(wi.z, eta_)) * (1.0f - yarf::FresnelDielectric(wo.z, eta_));
    return local.scaled_diffuse * (transmitted * yarf::kInvPi);
  }

  // The odds of the specular lobe among the lobes in play at cos θi > 0.
  float SpecularProbability(const yarf::coating::Point& local, float cos_i, bool specular, bool diffuse) const {
    if (!specular) return 0.0f;
    if (!diffuse) return 1.0f;
    const float fresnel = yarf::FresnelDielectric(cos_i, eta_);
    const float s = fresnel * local.lobes.specular_weight;
    const float d = (1.0f - fresnel) * (1.0f - local.lobes.specular_weight);
    return s / (s + d);
  }

  yarf::TexturedValue diffuse_;
  yarf::TexturedValue specular_;
  float eta_;
  // r̄, the coating's reflectance, from inside, of diffuse light.
  float internal_reflectance_;
  bool nonlinear_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Plastic>(registrar, "plastic", "1.0.0",
                          "Smooth plastic: a dielectric coating (delta reflection) over a "
                          "diffuse base (one-sided)");
}
