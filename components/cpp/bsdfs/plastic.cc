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
// Parameters
//   diffuse_reflectance    rgb (or float)   default 0.5        ρ, per channel in [0, 1]
//   specular_reflectance   rgb (or float)   default 1          a factor on F (for realism, 1)
//   int_ior                float            default 1.49       interior index (polypropylene)
//   ext_ior                float            default 1.000277   exterior index (air)
//   nonlinear              bool             default false      see above
//
// Lobes: delta reflection and diffuse reflection. Evaluate and Pdf see
// the diffuse lobe only. Sample picks the specular lobe with probability
// F s / (F s + (1 - F)(1 - s)), s = mean(specular) / (mean(specular) +
// mean(ρ)) as in Mitsuba, or the one lobe `allowed` leaves; the diffuse
// lobe samples the cosine-weighted hemisphere.
#include <cmath>
#include <cstdint>
#include <span>
#include <string>

#include "microfacet.h"
#include "yarf/plugin.h"
#include "yarf/warps.h"

namespace {

using yarf::Vec3;
namespace mf = yarf::microfacet;

constexpr uint32_t kSpecularLobe = yarf::kScatterReflect | yarf::kScatterDelta;
constexpr uint32_t kDiffuseLobe = yarf::kScatterReflect | yarf::kScatterDiffuse;

float Mean(Vec3 v) { return (v.x + v.y + v.z) / 3.0f; }

class Plastic final : public yarf::SurfaceModel {
 public:
  explicit Plastic(const yarf::Properties& props)
      : diffuse_(props.Reflectance("diffuse_reflectance", Vec3(0.5f, 0.5f, 0.5f))),
        specular_(props.Reflectance("specular_reflectance", Vec3(1.0f, 1.0f, 1.0f))),
        eta_(mf::ReadRelativeIndex(props, 1.49, 1.000277)) {
    const bool nonlinear = props.Bool("nonlinear", false);
    const float internal = mf::FresnelDiffuseReflectance(1.0f / eta_);
    float scaled[3];
    for (int c = 0; c < 3; ++c) {
      const float rho = diffuse_[c];
      scaled[c] = rho / (1.0f - (nonlinear ? rho * internal : internal)) / (eta_ * eta_);
    }
    scaled_diffuse_ = Vec3::Load(scaled);
    has_diffuse_ = Mean(diffuse_) > 0;
    has_specular_ = Mean(specular_) > 0;
    const float total = Mean(diffuse_) + Mean(specular_);
    specular_weight_ = total > 0 ? Mean(specular_) / total : 0.0f;
  }

  void Evaluate(yarf::TransportMode, std::span<const float> wi, std::span<const float> wo,
                std::span<const float> uv, std::span<float> value) const override {
    const size_t count = wi.size() / 3;
    for (size_t k = 0; k < count; ++k)
      Diffuse(Vec3::Load(&wi[3 * k]), Vec3::Load(&wo[3 * k])).Store(&value[3 * k]);
  }

  void Sample(yarf::TransportMode, std::span<const float> wi, std::span<const float> uv,
              std::span<const float> uniform, uint32_t allowed, std::span<float> wo,
              std::span<float> weight, std::span<float> pdf,
              std::span<uint32_t> flags) const override {
    const size_t count = wi.size() / 3;
    const bool specular = has_specular_ && yarf::LobeAllowed(kSpecularLobe, allowed);
    const bool diffuse = has_diffuse_ && yarf::LobeAllowed(kDiffuseLobe, allowed);
    for (size_t k = 0; k < count; ++k) {
      const Vec3 in = Vec3::Load(&wi[3 * k]);
      const float* u = &uniform[3 * k];
      const float p_specular =
          in.z > 0 ? SpecularProbability(in.z, specular, diffuse) : 0.0f;
      const bool pick_specular = u[0] < p_specular;
      Vec3 out, w;
      float density = 0;
      if (in.z > 0 && (specular || diffuse)) {
        if (pick_specular) {
          out = yarf::Reflect(in);
          density = p_specular;
          w = specular_ * (yarf::FresnelDielectric(in.z, eta_) / density);
        } else {
          out = yarf::SampleCosineHemisphere(u[1], u[2]);
          density = (1.0f - p_specular) * yarf::CosineHemispherePdf(out.z);
          if (density > 0) w = Diffuse(in, out) * (out.z / density);
        }
      }
      if (!(density > 0)) {
        Vec3().Store(&wo[3 * k]);
        Vec3().Store(&weight[3 * k]);
        pdf[k] = 0;
        flags[k] = yarf::kScatterNone;
        continue;
      }
      out.Store(&wo[3 * k]);
      w.Store(&weight[3 * k]);
      pdf[k] = density;
      flags[k] = pick_specular ? kSpecularLobe : kDiffuseLobe;
    }
  }

  void Pdf(std::span<const float> wi, std::span<const float> wo, std::span<const float> uv,
           std::span<float> pdf) const override {
    const size_t count = wi.size() / 3;
    for (size_t k = 0; k < count; ++k) {
      const float wi_z = wi[3 * k + 2], wo_z = wo[3 * k + 2];
      pdf[k] = has_diffuse_ && wi_z > 0 && wo_z > 0
                   ? (1.0f - SpecularProbability(wi_z, has_specular_, true)) *
                         yarf::CosineHemispherePdf(wo_z)
                   : 0.0f;
    }
  }

  uint32_t Lobes() const override {
    return (has_specular_ ? kSpecularLobe : 0u) | (has_diffuse_ ? kDiffuseLobe : 0u);
  }

 private:
  Vec3 Diffuse(Vec3 wi, Vec3 wo) const {
    if (!(wi.z > 0 && wo.z > 0) || !has_diffuse_) return Vec3();
    const float transmitted =
        (1.0f - yarf::FresnelDielectric(wi.z, eta_)) * (1.0f - yarf::FresnelDielectric(wo.z, eta_));
    return scaled_diffuse_ * (transmitted * yarf::kInvPi);
  }

  // The odds of the specular lobe among the lobes in play at cos θi > 0.
  float SpecularProbability(float cos_i, bool specular, bool diffuse) const {
    if (!specular) return 0.0f;
    if (!diffuse) return 1.0f;
    const float fresnel = yarf::FresnelDielectric(cos_i, eta_);
    const float s = fresnel * specular_weight_;
    const float d = (1.0f - fresnel) * (1.0f - specular_weight_);
    return s / (s + d);
  }

  Vec3 diffuse_;
  Vec3 specular_;
  float eta_;
  // ρ' / η² per channel: the diffuse lobe's value before the two Fresnel
  // transmissions and 1/π.
  Vec3 scaled_diffuse_;
  bool has_diffuse_ = false, has_specular_ = false;
  float specular_weight_ = 0;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Plastic>(registrar, "plastic", "1.0.0",
                          "Smooth plastic: a dielectric coating (delta reflection) over a "
                          "diffuse base (one-sided)");
}
