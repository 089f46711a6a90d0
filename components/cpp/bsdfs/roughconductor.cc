// roughconductor — rough metal (GGX microfacets)
//
// A conductor whose surface is made of mirror microfacets with GGX
// (Trowbridge–Reitz) normals (Walter et al., "Microfacet models for
// refraction through rough surfaces", EGSR 2007):
//
//   f(wi, wo) = R · F(wi·h) · D(h) · G2(wi, wo) / (4 cos θi cos θo)
//
// with h = (wi + wo)/|wi + wo|, D the GGX distribution of roughness
// (αu, αv), G2 Smith's height-correlated masking-shadowing (microfacet.h),
// F the Fresnel reflectance of the complex index η + iκ per RGB channel
// (as in conductor.cc) and R = specular_reflectance. Light that the
// microsurface would scatter more than once is lost (single scattering:
// the albedo drops below R·F as roughness grows). One-sided, as Mitsuba
// 3's `roughconductor`: 0 unless wi and wo both lie above (z > 0).
//
// Parameters: RoughConductor::Parameters() below.
// A texture's values are clamped: α to ≥ 10⁻⁴ (microfacet.h), R to [0, 1].
//
// Lobes: glossy reflection. Sample draws a microfacet normal from the
// normals visible from wi (Heitz, JCGT 2018) and reflects wi about it:
// pdf = G1(wi) D(h) / (4 cos θi), weight = R · F · G2 / G1(wi). A normal
// that reflects below the horizon gives no sample.
#include <cmath>
#include <cstdint>
#include <span>
#include <string>

#include "metals.h"
#include "microfacet.h"
#include "yarf/support/scatter_rows.h"
#include "surface_properties.h"
#include "yarf/plugin.h"
#include "yarf/texture.h"
#include "yarf/support/warps.h"

namespace {

using yarf::Vec3;
namespace mf = yarf::microfacet;

constexpr uint32_t kLobe = yarf::kScatterReflect | yarf::kScatterGlossy;

class RoughConductor final : public yarf::SurfaceModel {
 public:
  static yarf::ParameterSchema Parameters() {
    return yarf::JoinParameters({
        mf::RoughnessParameters(0.1, /*anisotropic=*/true, /*textured=*/true),
        yarf::metals::ConductorIorParameters(),
        {yarf::Parameter::RgbTexture("specular_reflectance").Default(1.0).Range(0, 1).Doc("R, a factor per channel")},
    });
  }

  explicit RoughConductor(const yarf::Properties& props)
      : roughness_(mf::ReadTexturedRoughness(props, 0.1, /*anisotropic=*/true)),
        ior_(yarf::metals::ReadConductorIor(props)),
        specular_(yarf::TexturedValue::Color(props, "specular_reflectance", Vec3(1.0f, 1.0f, 1.0f),
                                             /*unit=*/true)) {}

  void Evaluate(yarf::TransportMode, std::span<const float> wi, std::span<const float> wo,
                const yarf::SurfacePoints& at, std::span<float> value) const override {
    const auto roughness = roughness_.At(at);
    const auto specular = specular_.At(at);
    const auto ior = ior_.At(at);
    yarf::EvaluateEach(wi, wo, value, [&](size_t k, Vec3 in, Vec3 out) {
      return Value(roughness[k], specular[k], {ior.eta[k], ior.k[k]}, in, out);
    });
  }

  void Sample(yarf::TransportMode, std::span<const float> wi, const yarf::SurfacePoints& at,
              std::span<const float> uniform, uint32_t allowed, std::span<float> wo,
              std::span<float> weight, std::span<float> pdf,
              std::span<uint32_t> flags) const override {
    const size_t count = wi.size() / 3;
    const bool can_reflect = yarf::LobeAllowed(kLobe, allowed);
    const auto roughnesses = roughness_.At(at);
    const auto specular = specular_.At(at);
    const auto ior = ior_.At(at);
    const yarf::SampleRows rows{wo, weight, pdf, flags};
    for (size_t k = 0; k < count; ++k) {
      const Vec3 in = Vec3::Load(&wi[3 * k]);
      const float* u = &uniform[3 * k];
      const mf::Roughness roughness = roughnesses[k];
      if (!can_reflect || !(in.z > 0)) {
        rows.StoreNoSample(k);
        continue;
      }
      const Vec3 out = mf::ReflectAbout(in, mf::SampleVisibleNormal(in, roughness, u[1], u[2]));
      if (!(out.z > 0)) {
        rows.StoreNoSample(k);
        continue;
      }
      // The density from (wi, wo), as Pdf sees it; the weight f·cos θo /
      // pdf reduces to R·F·G2 / G1(wi), without D or the cosines.
      const Vec3 h = yarf::Normalize(in + out);
      const float lambda_in = mf::SmithLambda(in, roughness);
      const float density = Density(roughness, in, h, lambda_in);
      if (!(density > 0)) {
        rows.StoreNoSample(k);
        continue;
      }
      const float g2 = mf::SmithG2OfLambdas(lambda_in, mf::SmithLambda(out, roughness));
      rows.Store(k, out,
                 Reflectance(specular[k], {ior.eta[k], ior.k[k]}, in, h) * (g2 / mf::SmithG1OfLambda(lambda_in)),
                 density, kLobe);
    }
  }

  void Pdf(std::span<const float> wi, std::span<const float> wo, const yarf::SurfacePoints& at,
           std::span<float> pdf) const override {
    const auto roughness = roughness_.At(at);
    yarf::PdfEach(wi, wo, pdf,
                  [&](size_t k, Vec3 in, Vec3 out) { return Density(roughness[k], in, out); });
  }

  uint32_t Lobes() const override { return kLobe; }

 private:
  static Vec3 Value(mf::Roughness roughness, Vec3 specular, yarf::metals::ComplexIor ior, Vec3 wi, Vec3 wo) {
    if (!(wi.z > 0 && wo.z > 0)) return Vec3();
    const Vec3 h = yarf::Normalize(wi + wo);
    const float d = mf::Ndf(h, roughness);
    const float g = mf::SmithG2(wi, wo, roughness);
    return Reflectance(specular, ior, wi, h) * (d * g / (4.0f * wi.z * wo.z));
  }

  // R·F(wi·h): what a mirror microfacet of normal h reflects of light from wi.
  static Vec3 Reflectance(Vec3 specular, yarf::metals::ComplexIor ior, Vec3 wi, Vec3 h) {
    return specular * mf::FresnelConductor(yarf::Dot(wi, h), ior.eta, ior.k);
  }

  // The density of visible normals, D_wi(h) = G1(wi) (wi·h) D(h) / cos θi,
  // times the Jacobian 1 / (4 wi·h) of reflection about h.
  static float Density(mf::Roughness roughness, Vec3 wi, Vec3 wo) {
    if (!(wi.z > 0 && wo.z > 0)) return 0.0f;
    return Density(roughness, wi, yarf::Normalize(wi + wo), mf::SmithLambda(wi, roughness));
  }
  // The same from the half vector h and Smith's Λ(wi).
  static float Density(mf::Roughness roughness, Vec3 wi, Vec3 h, float lambda_wi) {
    return mf::SmithG1OfLambda(lambda_wi) * mf::Ndf(h, roughness) / (4.0f * wi.z);
  }

  mf::TexturedRoughness roughness_;
  yarf::metals::TexturedIor ior_;
  yarf::TexturedValue specular_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<RoughConductor>(
      registrar, "roughconductor", "1.0.0",
      "Rough conductor: GGX or Beckmann microfacets with a complex-index Fresnel factor (one-sided)");
}
