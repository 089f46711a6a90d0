// dielectric — smooth glass (an interface between two dielectrics)
//
// An optically smooth boundary between the exterior medium (index
// ext_ior, on the +z side of the surface) and the interior one (int_ior,
// the -z side). Light is reflected into the mirror direction with the
// Fresnel reflectance F and refracted by Snell's law with 1 - F; both are
// Dirac delta lobes, so Evaluate and Pdf return 0 and only Sample finds
// them. wi.z < 0 means the ray arrives from inside.
//
// Parameters: Dielectric::Parameters() below; the defaults are BK7 glass
// inside and air outside.
//
// Lobes: delta reflection and delta refraction. Sample chooses between
// them with probability F and 1 - F, so the weight is 1 for reflection
// and 1/η² for refraction, where η is the index on wo's side over the
// index on wi's side: radiance transported across the boundary is
// compressed into a smaller solid angle (pbrt, Mitsuba, Veach 1997 §5.2).
// Paths carrying importance (from the lights) refract with weight 1.
// When `allowed` excludes one lobe, the other is chosen always and its
// weight carries its Fresnel factor.
#include <algorithm>
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
constexpr uint32_t kRefractLobe = yarf::kScatterRefract | yarf::kScatterDelta;

class Dielectric final : public yarf::DeltaSurfaceModel {
 public:
  static yarf::ParameterSchema Parameters() { return yarf::RelativeIndexParameters(1.5046, 1.000277); }

  explicit Dielectric(const yarf::Properties& props)
      : eta_(yarf::ReadRelativeIndex(props, 1.5046, 1.000277)) {}

  void Sample(yarf::TransportMode mode, std::span<const float> wi, const yarf::SurfacePoints& at,
              std::span<const float> uniform, uint32_t allowed, std::span<float> wo,
              std::span<float> weight, std::span<float> pdf,
              std::span<uint32_t> flags) const override {
    const size_t count = wi.size() / 3;
    const bool can_reflect = yarf::LobeAllowed(kReflectLobe, allowed);
    const bool can_refract = yarf::LobeAllowed(kRefractLobe, allowed);
    const yarf::SampleRows rows{wo, weight, pdf, flags};
    for (size_t k = 0; k < count; ++k) {
      const Vec3 in = Vec3::Load(&wi[3 * k]);
      const float fresnel = yarf::FresnelDielectric(in.z, eta_);
      // Lobe probabilities: proportional to their Fresnel factors among
      // the allowed lobes.
      const float reflect_share = can_reflect ? fresnel : 0.0f;
      const float refract_share = can_refract ? 1.0f - fresnel : 0.0f;
      const float total = reflect_share + refract_share;
      Vec3 out;
      const bool reflect = uniform[3 * k] * total < reflect_share;
      if (!(total > 0) || in.z == 0 || (!reflect && !yarf::Refract(in, eta_, &out))) {
        rows.StoreNoSample(k);
        continue;
      }
      float factor, probability;
      if (reflect) {
        out = yarf::Reflect(in);
        factor = fresnel;
        probability = reflect_share / total;
      } else {
        // η of wo's side over wi's side; importance is not compressed.
        const float eta_rel = in.z > 0 ? eta_ : 1.0f / eta_;
        factor = 1.0f - fresnel;
        if (mode == yarf::TransportMode::kRadiance) factor /= eta_rel * eta_rel;
        probability = refract_share / total;
      }
      const float w = factor / probability;
      rows.Store(k, out, Vec3(w, w, w), probability, reflect ? kReflectLobe : kRefractLobe);
    }
  }

  uint32_t Lobes() const override { return kReflectLobe | kRefractLobe; }

 private:
  // int_ior / ext_ior: the index below the surface over the one above.
  float eta_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Dielectric>(
      registrar, "dielectric", "1.0.0",
      "Smooth dielectric interface (glass): Fresnel reflection and refraction");
}
