// roughdiffuse — a rough diffuse reflector (Oren and Nayar, 1994)
//
// A surface of V-shaped grooves, each a Lambertian reflector, whose slopes
// are normally distributed with standard deviation σ: at grazing views it
// turns back toward the light (the back-scattering of the moon, of clay,
// of plaster) where a Lambertian surface darkens. As Mitsuba 0.6's
// roughdiffuse (which Mitsuba 3 dropped; pbrt-v3's matte is its fast
// model): alpha is the grooves' RMS slope in Beckmann's sense,
// σ² = alpha²/2 (a fit of the two models up to alpha ≈ 0.5); the full
// model has Oren and Nayar's single-scattering terms C1, C2, C3 and their
// approximation of light reflected twice in a groove (which grows with
// reflectance²), the fast one only their qualitative A + B form. alpha = 0
// is Lambertian. Both sides reflect alike unless two_sided is false
// (DiffuseHemisphere).
//
// Parameters: RoughDiffuse::Parameters() below. Lobes: diffuse reflection,
// sampled from the cosine-weighted hemisphere on wi's side.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>

#include "diffuse_hemisphere.h"
#include "yarf/plugin.h"
#include "yarf/support/scatter_rows.h"
#include "yarf/texture.h"

namespace {

using yarf::Vec3;

constexpr uint32_t kLobe = yarf::kScatterReflect | yarf::kScatterDiffuse;

class RoughDiffuse final : public yarf::SurfaceModel {
 public:
  static yarf::ParameterSchema Parameters() {
    using P = yarf::Parameter;
    return {P::RgbTexture("reflectance").Default(0.5).Range(0, 1).Doc("reflectance of the grooves' faces"),
            P::FloatTexture("alpha").Default(0.2).Min(0).Doc(
                "RMS slope of the grooves (Beckmann's roughness; Oren and Nayar's σ is alpha/√2)"),
            P::Bool("use_fast_approx")
                .Default(false)
                .Doc("Oren and Nayar's qualitative model, without interreflection"),
            yarf::DiffuseHemisphere::TwoSidedParameter()};
  }

  explicit RoughDiffuse(const yarf::Properties& props)
      : reflectance_(yarf::TexturedValue::Color(props, "reflectance", Vec3(0.5f, 0.5f, 0.5f), /*unit=*/true)),
        alpha_(ReadSlope(props)),
        fast_(props.Bool("use_fast_approx", false)),
        hemisphere_(props) {}

  void Evaluate(yarf::TransportMode, std::span<const float> wi, std::span<const float> wo,
                const yarf::SurfacePoints& at, std::span<float> value) const override {
    const auto reflectance = reflectance_.At(at);
    const auto alpha = alpha_.FloatsAt(at);
    yarf::EvaluateEach(wi, wo, value, [&](size_t k, Vec3 in, Vec3 out) {
      return hemisphere_.Reflects(in, out) ? Value(reflectance[k], alpha[k], in, out) : Vec3();
    });
  }

  void Sample(yarf::TransportMode, std::span<const float> wi, const yarf::SurfacePoints& at,
              std::span<const float> uniform, uint32_t allowed, std::span<float> wo, std::span<float> weight,
              std::span<float> pdf, std::span<uint32_t> flags) const override {
    const yarf::SampleRows rows{wo, weight, pdf, flags};
    const auto reflectance = reflectance_.At(at);
    const auto alpha = alpha_.FloatsAt(at);
    for (size_t k = 0; k < wi.size() / 3; ++k) {
      const Vec3 in = Vec3::Load(&wi[3 * k]);
      float density;
      const Vec3 out = hemisphere_.Sample(in, uniform[3 * k + 1], uniform[3 * k + 2], density);
      if (!yarf::LobeAllowed(kLobe, allowed) || !(density > 0)) {
        rows.StoreNoSample(k);
        continue;
      }
      rows.Store(k, out, Value(reflectance[k], alpha[k], in, out) * (std::abs(out.z) / density), density, kLobe);
    }
  }

  void Pdf(std::span<const float> wi, std::span<const float> wo, const yarf::SurfacePoints&,
           std::span<float> pdf) const override {
    yarf::PdfEach(wi, wo, pdf, [&](size_t, Vec3 in, Vec3 out) { return hemisphere_.Pdf(in, out); });
  }

  uint32_t Lobes() const override { return kLobe; }

 private:
  // alpha: a finite number ≥ 0, or a texture clamped to ≥ 0 where looked up.
  static yarf::TexturedValue ReadSlope(const yarf::Properties& props) {
    if (auto texture = props.TextureOf("alpha"))
      return yarf::TexturedValue(std::move(texture)).Clamped(0.0f, std::numeric_limits<float>::max());
    const double alpha = props.Float("alpha", 0.2);
    if (!(alpha >= 0 && std::isfinite(alpha))) throw yarf::Error("property 'alpha' must be a finite number >= 0");
    return yarf::TexturedValue(Vec3(float(alpha), float(alpha), float(alpha)));
  }

  // f for wi and wo on one side (the back mirrored onto the front). The
  // model is symmetric in the two directions: it reads only the larger
  // polar angle θ (α in Oren and Nayar), the smaller (β), and the cosine
  // of the azimuth between them.
  Vec3 Value(Vec3 reflectance, float alpha, Vec3 in, Vec3 out) const {
    // The model's terms have long saturated by α = 100 (σ² = 5000): larger
    // slopes, which would overflow σ², are taken as that.
    const float slope = std::min(alpha, 100.0f), sigma2 = 0.5f * slope * slope;
    const float cos_in = std::min(std::abs(in.z), 1.0f), cos_out = std::min(std::abs(out.z), 1.0f);
    const float sin_in = std::sqrt(1 - cos_in * cos_in), sin_out = std::sqrt(1 - cos_out * cos_out);
    // Where a direction has no azimuth (at the normal), any will do: the
    // terms that read it vanish there.
    const float across = sin_in * sin_out;
    const float cos_phi =
        across > 0 ? std::clamp((in.x * out.x + in.y * out.y) / across, -1.0f, 1.0f) : 1.0f;
    // The larger angle's sine, the smaller's sine and tangent.
    const bool in_steeper = cos_in < cos_out;
    const float sin_max = in_steeper ? sin_in : sin_out;
    const float sin_min = in_steeper ? sin_out : sin_in, cos_min = in_steeper ? cos_out : cos_in;
    const float tan_min = cos_min > 0 ? sin_min / cos_min : 0.0f;
    const float a = 1 - 0.5f * sigma2 / (sigma2 + 0.33f);
    const float groove = sigma2 / (sigma2 + 0.09f);
    if (fast_)
      return reflectance * (yarf::kInvPi * (a + 0.45f * groove * std::max(cos_phi, 0.0f) * sin_max * tan_min));
    const float theta_max = std::acos(in_steeper ? cos_in : cos_out), theta_min = std::acos(cos_min);
    const float two_beta_over_pi = 2 * theta_min * yarf::kInvPi;
    const float four_ab = 4 * yarf::kInvPi * yarf::kInvPi * theta_max * theta_min;
    const float c2 = 0.45f * groove * (cos_phi > 0 ? sin_max : sin_max - std::pow(two_beta_over_pi, 3.0f));
    const float c3 = 0.125f * groove * four_ab * four_ab;
    // tan((α + β) / 2), by the half-angle identity.
    const float cos_max = std::sqrt(std::max(0.0f, 1 - sin_max * sin_max));
    const float tan_half = (sin_max + sin_min) / std::max(cos_max + cos_min, 1e-7f);
    const float single = a + cos_phi * c2 * tan_min + (1 - std::abs(cos_phi)) * c3 * tan_half;
    const float twice = 0.17f * sigma2 / (sigma2 + 0.13f) * (1 - cos_phi * two_beta_over_pi * two_beta_over_pi);
    return (reflectance * single + reflectance * reflectance * twice) * yarf::kInvPi;
  }

  yarf::TexturedValue reflectance_, alpha_;
  bool fast_;
  yarf::DiffuseHemisphere hemisphere_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<RoughDiffuse>(
      registrar, "roughdiffuse", "1.0.0",
      "Rough diffuse reflection (Oren-Nayar), as Mitsuba 0.6's roughdiffuse and pbrt-v3's matte");
}
