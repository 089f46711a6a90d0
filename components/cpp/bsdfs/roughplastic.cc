// roughplastic — rough dielectric coating over a diffuse base
//
// Mitsuba 3's `roughplastic`: plastic.cc with a rough interface. The
// coating reflects like a rough dielectric (GGX microfacets, Smith's
// height-correlated G2, microfacet.h); the light it does not reflect
// reaches a diffuse base of reflectance ρ, and what comes back out is
// diffuse, weighted by the coating's transmittance on the way in and out:
//
//   f(wi, wo) = R F(wi·h) D(h) G2(wi, wo) / (4 cos θi cos θo)
//             + ρ' t(cos θi) t(cos θo) / (η² π)
//
// with h = (wi + wo)/|wi + wo|, η = int_ior / ext_ior, R =
// specular_reflectance, t(μ) = 1 - r(μ, η) where r(μ, η) is the albedo of
// the interface's reflection at incidence μ (microfacet.h,
// RoughDielectricReflectance), and ρ' = ρ / (1 - r̄) (nonlinear = false)
// or ρ / (1 - ρ r̄) (nonlinear = true), r̄ = 2 ∫ r(μ, 1/η) μ dμ the
// interface's reflectance, from inside, of diffuse light. As in Mitsuba,
// t is tabulated at construction (64 values of μ, linearly interpolated)
// and the roughness is isotropic. At α → 0 the model becomes plastic.cc's.
// As Mitsuba's, it loses energy as α grows: r̄ leaves out the light the
// rough inside masks, which 1 / (1 - r̄) thus counts as leaving, while t
// lets less out. A white base (ρ = 1) reflects, at normal incidence, 0.998
// of the light at α = 0.02, 0.94 at 0.1, 0.83 at 0.2, 0.63 at 0.5.
// One-sided, as in Mitsuba: 0 unless wi and wo lie above.
//
// Parameters: RoughPlastic::Parameters() below; the indices' defaults are
// polypropylene inside and air outside. alpha is isotropic and a number,
// as in Mitsuba: t and r̄ are tabulated for it. A texture's values are
// clamped to [0, 1].
//
// Lobes: glossy reflection and diffuse reflection. Sample picks the glossy
// lobe with probability (1 - t) s / ((1 - t) s + t (1 - s)), s =
// mean(R) / (mean(R) + mean(ρ)) at the point as in Mitsuba, or the one
// lobe `allowed` leaves; it draws the glossy lobe from the normals visible from wi
// (Heitz 2018), the diffuse one from the cosine-weighted hemisphere, and
// returns the density and value of the mixture of the allowed lobes.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <utility>

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

constexpr uint32_t kGlossyLobe = yarf::kScatterReflect | yarf::kScatterGlossy;
constexpr uint32_t kDiffuseLobe = yarf::kScatterReflect | yarf::kScatterDiffuse;

class RoughPlastic final : public yarf::SurfaceModel {
 public:
  static yarf::ParameterSchema Parameters() {
    return yarf::JoinParameters({
        yarf::coating::CoatingParameters(),
        mf::RoughnessParameters(0.1, /*anisotropic=*/false, /*textured=*/false),
        yarf::RelativeIndexParameters(1.49, 1.000277),
    });
  }

  explicit RoughPlastic(const yarf::Properties& props)
      : diffuse_(yarf::TexturedValue::Color(props, "diffuse_reflectance",
                                            Vec3(0.5f, 0.5f, 0.5f), /*unit=*/true)),
        specular_(yarf::TexturedValue::Color(props, "specular_reflectance",
                                             Vec3(1.0f, 1.0f, 1.0f), /*unit=*/true)),
        roughness_(mf::ReadRoughness(props, 0.1, /*anisotropic=*/false)),
        eta_(yarf::ReadRelativeIndex(props, 1.49, 1.000277)),
        internal_reflectance_(InternalReflectance(roughness_, eta_)),
        nonlinear_(props.Bool("nonlinear", false)) {
    for (int i = 0; i < kTableSize; ++i)
      transmittance_[i] =
          1.0f - mf::RoughDielectricReflectance(float(i) / (kTableSize - 1), roughness_, eta_);
  }

  void Evaluate(yarf::TransportMode, std::span<const float> wi, std::span<const float> wo,
                const yarf::SurfacePoints& at, std::span<float> value) const override {
    const yarf::coating::Points coating(diffuse_, specular_, at, internal_reflectance_, nonlinear_, eta_);
    yarf::EvaluateEach(wi, wo, value, [&](size_t k, Vec3 in, Vec3 out) {
      return Value(coating[k], in, out, true, true);
    });
  }

  void Sample(yarf::TransportMode, std::span<const float> wi, const yarf::SurfacePoints& at,
              std::span<const float> uniform, uint32_t allowed, std::span<float> wo,
              std::span<float> weight, std::span<float> pdf,
              std::span<uint32_t> flags) const override {
    const size_t count = wi.size() / 3;
    const bool can_glossy = yarf::LobeAllowed(kGlossyLobe, allowed);
    const bool can_diffuse = yarf::LobeAllowed(kDiffuseLobe, allowed);
    const yarf::coating::Points coating(diffuse_, specular_, at, internal_reflectance_, nonlinear_, eta_);
    const yarf::SampleRows rows{wo, weight, pdf, flags};
    for (size_t k = 0; k < count; ++k) {
      const yarf::coating::Point local = coating[k];
      const bool glossy = local.lobes.has_specular && can_glossy;
      const bool diffuse = local.lobes.has_diffuse && can_diffuse;
      const Vec3 in = Vec3::Load(&wi[3 * k]);
      const float* u = &uniform[3 * k];
      const float p_glossy = in.z > 0 ? GlossyProbability(local, in.z, glossy, diffuse) : 0.0f;
      const bool pick_glossy = u[0] < p_glossy;
      Vec3 out;
      float density = 0;
      if (in.z > 0 && (glossy || diffuse)) {
        if (pick_glossy)
          out = mf::ReflectAbout(in, mf::SampleVisibleNormal(in, roughness_, u[1], u[2]));
        else
          out = yarf::SampleCosineHemisphere(u[1], u[2]);
        density = yarf::coating::RoughCoatingDensity(roughness_, in, out, p_glossy);
      }
      if (!(density > 0)) {
        rows.StoreNoSample(k);
        continue;
      }
      rows.Store(k, out, Value(local, in, out, glossy, diffuse) * (out.z / density), density,
                 pick_glossy ? kGlossyLobe : kDiffuseLobe);
    }
  }

  void Pdf(std::span<const float> wi, std::span<const float> wo, const yarf::SurfacePoints& at,
           std::span<float> pdf) const override {
    const yarf::coating::Points coating(diffuse_, specular_, at, internal_reflectance_, nonlinear_, eta_);
    yarf::PdfEach(wi, wo, pdf, [&](size_t k, Vec3 in, Vec3 out) {
      const yarf::coating::Point local = coating[k];
      const bool glossy = local.lobes.has_specular, diffuse = local.lobes.has_diffuse;
      const float p_glossy = in.z > 0 ? GlossyProbability(local, in.z, glossy, diffuse) : 0.0f;
      return glossy || diffuse ? yarf::coating::RoughCoatingDensity(roughness_, in, out, p_glossy) : 0.0f;
    });
  }

  uint32_t Lobes() const override {
    return (specular_.IsZero() ? 0u : kGlossyLobe) | (diffuse_.IsZero() ? 0u : kDiffuseLobe);
  }

 private:
  static constexpr int kTableSize = 64;

  // r̄ = 2 ∫ r(μ, 1/η) μ dμ = ∫ r(√s, 1/η) ds, by the midpoint rule in s
  // on each side of s_c = 1 - 1/η², below which a smooth interface
  // reflects all (total internal reflection): the integrand's step as
  // α → 0 falls on a boundary of the rule.
  static double InternalReflectance(const mf::Roughness& roughness, float eta) {
    constexpr int kSteps = 64, kStrata = 32;
    const double critical = eta > 1.0f ? 1.0 - 1.0 / (double(eta) * eta) : 0.5;
    double sum = 0;
    for (const auto& [from, to] : {std::pair{0.0, critical}, std::pair{critical, 1.0}})
      for (int i = 0; i < kSteps; ++i) {
        const double s = from + (i + 0.5) * (to - from) / kSteps;
        sum += (to - from) / kSteps *
               mf::RoughDielectricReflectance(float(std::sqrt(s)), roughness, 1.0f / eta, kStrata);
      }
    return sum;
  }

  // t(μ), linearly interpolated in the table.
  float Transmittance(float cos_theta) const {
    const float x = std::clamp(cos_theta, 0.0f, 1.0f) * (kTableSize - 1);
    const int i = std::min(int(x), kTableSize - 2);
    const float w = x - float(i);
    return (1.0f - w) * transmittance_[i] + w * transmittance_[i + 1];
  }

  // The odds of the glossy lobe among the lobes in play at cos θi > 0.
  float GlossyProbability(const yarf::coating::Point& local, float cos_i, bool glossy, bool diffuse) const {
    if (!glossy) return 0.0f;
    if (!diffuse) return 1.0f;
    const float t = Transmittance(cos_i);
    const float g = (1.0f - t) * local.lobes.specular_weight;
    const float d = t * (1.0f - local.lobes.specular_weight);
    return g + d > 0 ? g / (g + d) : 0.0f;
  }

  // f of the lobes asked for.
  Vec3 Value(const yarf::coating::Point& local, Vec3 wi, Vec3 wo, bool glossy, bool diffuse) const {
    if (!(wi.z > 0 && wo.z > 0)) return Vec3();
    Vec3 out;
    if (glossy && local.lobes.has_specular)
      out += local.specular * yarf::coating::RoughCoatingReflection(roughness_, eta_, wi, wo);
    if (diffuse && local.lobes.has_diffuse)
      out += local.scaled_diffuse * (Transmittance(wi.z) * Transmittance(wo.z) * yarf::kInvPi);
    return out;
  }

  yarf::TexturedValue diffuse_;
  yarf::TexturedValue specular_;
  mf::Roughness roughness_;
  float eta_;
  // r̄, the interface's reflectance, from inside, of diffuse light.
  double internal_reflectance_;
  bool nonlinear_;
  std::array<float, kTableSize> transmittance_{};
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<RoughPlastic>(registrar, "roughplastic", "1.0.0",
                               "Rough plastic: a GGX dielectric coating over a diffuse base "
                               "(one-sided)");
}
