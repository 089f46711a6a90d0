// phong — the modified Phong reflection model
//
// The energy-conserving, reciprocal Phong model of Lafortune & Willems
// (1994), a diffuse term plus a glossy lobe around the mirror direction:
//
//   f(wi, wo) = kd / π + ks · (n + 2) / (2π) · cos^n α
//
// where α is the angle between wo and the mirror direction of wi (the
// lobe is 0 beyond α = 90°). The (n + 2)/(2π) factor makes the glossy
// lobe reflect at most ks (exactly ks at normal incidence). Both sides
// reflect alike (two-sided); wi and wo on opposite sides give 0.
//
// Parameters
//   diffuse_reflectance    rgb (or float)   default 0.5    kd, per channel ≥ 0
//   specular_reflectance   rgb (or float)   default 0.2    ks, per channel ≥ 0
//   exponent               float            default 30     n ≥ 0; larger is shinier
// kd + ks must not exceed 1 in any channel (energy conservation).
//
// Lobes: diffuse reflection (when kd > 0) and glossy reflection (when
// ks > 0). Sample picks one of the allowed lobes with probability
// proportional to the luminance of kd and ks, draws wo from the
// cosine-weighted hemisphere or the cos^n lobe around the mirror
// direction, and returns the density of the mixture of the allowed lobes
// (and their value in the weight).
#include <cmath>
#include <cstdint>
#include <span>
#include <string>

#include "scatter_rows.h"
#include "surface_properties.h"
#include "yarf/plugin.h"
#include "yarf/warps.h"

namespace {

using yarf::Vec3;

constexpr uint32_t kDiffuseLobe = yarf::kScatterReflect | yarf::kScatterDiffuse;
constexpr uint32_t kGlossyLobe = yarf::kScatterReflect | yarf::kScatterGlossy;

float RequireExponent(double exponent) {
  if (!(exponent >= 0.0 && std::isfinite(exponent)))
    throw yarf::Error("property 'exponent' must be a finite number ≥ 0");
  return float(exponent);
}

class Phong final : public yarf::SurfaceModel {
 public:
  explicit Phong(const yarf::Properties& props)
      : diffuse_(props.Reflectance("diffuse_reflectance", Vec3(0.5f, 0.5f, 0.5f))),
        specular_(props.Reflectance("specular_reflectance", Vec3(0.2f, 0.2f, 0.2f))),
        exponent_(RequireExponent(props.Float("exponent", 30.0))) {
    yarf::RequireEnergyConserving(diffuse_, specular_, "diffuse_reflectance",
                                  "specular_reflectance");
    diffuse_weight_ = yarf::Luminance(diffuse_);
    specular_weight_ = yarf::Luminance(specular_);
    const float total = diffuse_weight_ + specular_weight_;
    specular_probability_ = total > 0 ? specular_weight_ / total : 0.0f;
  }

  void Evaluate(yarf::TransportMode, std::span<const float> wi, std::span<const float> wo,
                std::span<const float> uv, std::span<float> value) const override {
    yarf::EvaluateEach(wi, wo, value,
                       [&](Vec3 in, Vec3 out) { return Value(in, out, true, true); });
  }

  void Sample(yarf::TransportMode, std::span<const float> wi, std::span<const float> uv,
              std::span<const float> uniform, uint32_t allowed, std::span<float> wo,
              std::span<float> weight, std::span<float> pdf,
              std::span<uint32_t> flags) const override {
    const size_t count = wi.size() / 3;
    const bool diffuse = yarf::LobeAllowed(kDiffuseLobe, allowed) && diffuse_weight_ > 0;
    const bool glossy = yarf::LobeAllowed(kGlossyLobe, allowed) && specular_weight_ > 0;
    const float total = (diffuse ? diffuse_weight_ : 0.0f) + (glossy ? specular_weight_ : 0.0f);
    const float specular_probability = total > 0 ? (glossy ? specular_weight_ : 0.0f) / total : 0.0f;
    const yarf::SampleRows rows{wo, weight, pdf, flags};
    for (size_t k = 0; k < count; ++k) {
      const Vec3 in = Vec3::Load(&wi[3 * k]);
      const float* u = &uniform[3 * k];
      Vec3 out;
      const bool specular = u[0] < specular_probability;
      if (specular) {
        // The lobe is symmetric about the mirror direction: sample it in
        // a frame whose z axis is that direction.
        const yarf::Frame mirror(yarf::Reflect(in));
        out = mirror.ToWorld(yarf::SamplePhongLobe(u[1], u[2], exponent_));
      } else {
        out = yarf::SampleCosineHemisphere(u[1], u[2]);
        if (in.z < 0) out.z = -out.z;
      }
      // Zero when the glossy lobe dipped below the surface.
      const float density = total > 0 ? Density(in, out, specular_probability) : 0.0f;
      if (!(density > 0)) {
        rows.StoreNoSample(k);
        continue;
      }
      rows.Store(k, out, Value(in, out, diffuse, glossy) * (std::abs(out.z) / density), density,
                 specular ? kGlossyLobe : kDiffuseLobe);
    }
  }

  void Pdf(std::span<const float> wi, std::span<const float> wo, std::span<const float> uv,
           std::span<float> pdf) const override {
    yarf::PdfEach(wi, wo, pdf,
                  [&](Vec3 in, Vec3 out) { return Density(in, out, specular_probability_); });
  }

  uint32_t Lobes() const override {
    return (diffuse_weight_ > 0 ? kDiffuseLobe : 0u) | (specular_weight_ > 0 ? kGlossyLobe : 0u);
  }

 private:
  // cos α between wo and the mirror direction of wi. Symmetric in wi and
  // wo, which makes the model reciprocal, and unchanged by mirroring both
  // to the other side, which makes it two-sided.
  static float CosToMirror(Vec3 wi, Vec3 wo) { return yarf::Dot(wo, yarf::Reflect(wi)); }

  // f of the lobes asked for.
  Vec3 Value(Vec3 wi, Vec3 wo, bool diffuse, bool glossy) const {
    if (!(wi.z * wo.z > 0)) return Vec3();
    const float cos_alpha = CosToMirror(wi, wo);
    const float lobe = glossy && cos_alpha > 0
                           ? (exponent_ + 2.0f) / (2.0f * yarf::kPi) * std::pow(cos_alpha, exponent_)
                           : 0.0f;
    return (diffuse ? diffuse_ * yarf::kInvPi : Vec3()) + specular_ * lobe;
  }

  // Density of the lobe mixture Sample draws from; the part of the glossy
  // lobe below the surface is lost (Sample returns no sample there).
  float Density(Vec3 wi, Vec3 wo, float specular_probability) const {
    if (!(wi.z * wo.z > 0)) return 0.0f;
    return (1.0f - specular_probability) * yarf::CosineHemispherePdf(std::abs(wo.z)) +
           specular_probability * yarf::PhongLobePdf(CosToMirror(wi, wo), exponent_);
  }

  Vec3 diffuse_;
  Vec3 specular_;
  float exponent_;
  // Luminances of kd and ks: the odds of sampling each lobe.
  float diffuse_weight_ = 0, specular_weight_ = 0;
  float specular_probability_ = 0;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Phong>(registrar, "phong", "1.0.0",
                        "Modified Phong (Lafortune & Willems 1994): diffuse plus a glossy lobe");
}
