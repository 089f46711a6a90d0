// conductor — smooth metal
//
// An optically smooth conductor (Mitsuba 3's `conductor`): all light is
// reflected into the mirror direction, scaled by the conductor's Fresnel
// reflectance F(cos θi) for its complex index of refraction η + iκ
// (relative to the outside medium, per RGB channel) and by
// specular_reflectance. A Dirac delta lobe, so Evaluate and Pdf return 0
// and only Sample finds it. One-sided, as in Mitsuba: light arriving from
// below (wi.z ≤ 0) is not reflected.
//
// Parameters: Conductor::Parameters() below. The defaults η = 0, κ = 1
// make F = 1 at every angle: a perfect mirror, as Mitsuba's material
// "none". A texture's specular_reflectance is clamped to [0, 1].
//
// Lobes: delta reflection. Sample returns wo = (-wi.x, -wi.y, wi.z),
// weight = specular_reflectance · F(cos θi), pdf = 1 (the only lobe).
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

constexpr uint32_t kMirrorLobe = yarf::kScatterReflect | yarf::kScatterDelta;

class Conductor final : public yarf::DeltaSurfaceModel {
 public:
  static yarf::ParameterSchema Parameters() {
    return yarf::JoinParameters({
        yarf::metals::ConductorIorParameters(),
        {yarf::Parameter::RgbTexture("specular_reflectance")
             .Default(1.0)
             .Range(0, 1)
             .Doc("a factor on the Fresnel reflectance, per channel")},
    });
  }

  explicit Conductor(const yarf::Properties& props)
      : ior_(yarf::metals::ReadConductorIor(props)),
        specular_(yarf::TexturedValue::Color(props, "specular_reflectance", Vec3(1.0f, 1.0f, 1.0f),
                                             /*unit=*/true)) {}

  void Sample(yarf::TransportMode, std::span<const float> wi, const yarf::SurfacePoints& at,
              std::span<const float> uniform, uint32_t allowed, std::span<float> wo,
              std::span<float> weight, std::span<float> pdf,
              std::span<uint32_t> flags) const override {
    const size_t count = wi.size() / 3;
    const bool can_reflect = yarf::LobeAllowed(kMirrorLobe, allowed);
    const yarf::SampleRows rows{wo, weight, pdf, flags};
    const auto specular = specular_.At(at);
    const auto ior = ior_.At(at);
    for (size_t k = 0; k < count; ++k) {
      const Vec3 in = Vec3::Load(&wi[3 * k]);
      if (!can_reflect || !(in.z > 0)) {
        rows.StoreNoSample(k);
        continue;
      }
      rows.Store(k, yarf::Reflect(in),
                 specular[k] * yarf::microfacet::FresnelConductor(in.z, ior.eta[k], ior.k[k]), 1.0f,
                 kMirrorLobe);
    }
  }

  uint32_t Lobes() const override { return kMirrorLobe; }

 private:
  yarf::metals::TexturedIor ior_;
  yarf::TexturedValue specular_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Conductor>(registrar, "conductor", "1.0.0",
                            "Smooth conductor: mirror reflection with the Fresnel factor of a "
                            "complex index of refraction (one-sided)");
}
