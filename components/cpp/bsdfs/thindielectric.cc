// thindielectric — a thin pane of glass
//
// Mitsuba 3's `thindielectric`: a dielectric slab so thin that light
// leaves it where it entered, with the same index on both sides (a window
// pane, a soap bubble). Each interface reflects the Fresnel fraction
// F = F(|cos θi|) of smooth glass; summing the light bounced back and
// forth inside (without absorption) gives the slab's reflectance and
// transmittance
//
//   R = F + (1 - F)² F / (1 - F²) = 2F / (1 + F),   T = 1 - R.
//
// Reflection is into the mirror direction; transmission passes straight
// through (wo = -wi: the two refractions cancel). Both are Dirac delta
// lobes, so Evaluate and Pdf return 0 and only Sample finds them. Both
// sides alike; no radiance scaling (wi and wo lie in the same medium).
//
// Parameters: ThinDielectric::Parameters() below: int_ior is the pane's
// index (default BK7 glass), ext_ior the index around it (air).
//
// Lobes: delta reflection and delta transmission (kScatterRefract: wo on
// the other side). Sample picks them with probability R and T, so the
// weight is 1; when `allowed` excludes one, the other is drawn always and
// its weight is its R or T.
#include <cmath>
#include <cstdint>
#include <span>
#include <string>

#include "yarf/support/scatter_rows.h"
#include "surface_properties.h"
#include "yarf/plugin.h"
#include "yarf/support/warps.h"

namespace {

using yarf::Vec3;

constexpr uint32_t kReflectLobe = yarf::kScatterReflect | yarf::kScatterDelta;
constexpr uint32_t kTransmitLobe = yarf::kScatterRefract | yarf::kScatterDelta;

class ThinDielectric final : public yarf::DeltaSurfaceModel {
 public:
  static yarf::ParameterSchema Parameters() { return yarf::RelativeIndexParameters(1.5046, 1.000277); }

  explicit ThinDielectric(const yarf::Properties& props)
      : eta_(yarf::ReadRelativeIndex(props, 1.5046, 1.000277)) {}

  void Sample(yarf::TransportMode, std::span<const float> wi, const yarf::SurfacePoints& at,
              std::span<const float> uniform, uint32_t allowed, std::span<float> wo,
              std::span<float> weight, std::span<float> pdf,
              std::span<uint32_t> flags) const override {
    const size_t count = wi.size() / 3;
    const bool can_reflect = yarf::LobeAllowed(kReflectLobe, allowed);
    const bool can_transmit = yarf::LobeAllowed(kTransmitLobe, allowed);
    const yarf::SampleRows rows{wo, weight, pdf, flags};
    for (size_t k = 0; k < count; ++k) {
      const Vec3 in = Vec3::Load(&wi[3 * k]);
      const float reflectance = Reflectance(std::abs(in.z));
      const float reflect_share = can_reflect ? reflectance : 0.0f;
      const float transmit_share = can_transmit ? 1.0f - reflectance : 0.0f;
      const float total = reflect_share + transmit_share;
      const bool reflect = uniform[3 * k] * total < reflect_share;
      if (!(total > 0) || in.z == 0) {
        rows.StoreNoSample(k);
        continue;
      }
      // The weight, factor / probability, is the allowed lobes' total.
      rows.Store(k, reflect ? yarf::Reflect(in) : -in, Vec3(total, total, total),
                 (reflect ? reflect_share : transmit_share) / total,
                 reflect ? kReflectLobe : kTransmitLobe);
    }
  }

  uint32_t Lobes() const override { return kReflectLobe | kTransmitLobe; }

 private:
  // R = F + T₁² F / (1 - F²) with T₁ = 1 - F: one reflection off the top,
  // or a transmission, 2k + 1 internal reflections and a transmission.
  float Reflectance(float cos_theta) const {
    const float fresnel = yarf::FresnelDielectric(cos_theta, eta_);
    if (fresnel >= 1.0f) return 1.0f;
    return fresnel + (1.0f - fresnel) * (1.0f - fresnel) * fresnel / (1.0f - fresnel * fresnel);
  }

  // int_ior / ext_ior.
  float eta_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<ThinDielectric>(registrar, "thindielectric", "1.0.0",
                                 "Thin dielectric pane: Fresnel reflection and straight "
                                 "transmission with interreflection");
}
