// mirror — perfect specular reflector
//
// Reflects all light into the mirror direction of wi about the normal,
// scaled by the reflectance: a Dirac delta lobe, so Evaluate and Pdf
// return 0 and only Sample finds it. Both sides reflect alike.
//
// Parameters: Mirror::Parameters() below. A texture's values are clamped
// to [0, 1].
//
// Lobes: delta reflection. Sample returns wo = (-wi.x, -wi.y, wi.z),
// weight = reflectance, pdf = 1 (the probability of the only lobe).
#include <algorithm>
#include <cstdint>
#include <span>
#include <string>

#include "yarf/support/scatter_rows.h"
#include "yarf/plugin.h"
#include "yarf/texture.h"
#include "yarf/support/warps.h"

namespace {

using yarf::Vec3;

constexpr uint32_t kMirrorLobe = yarf::kScatterReflect | yarf::kScatterDelta;

class Mirror final : public yarf::DeltaSurfaceModel {
 public:
  static yarf::ParameterSchema Parameters() {
    return {yarf::Parameter::RgbTexture("reflectance")
                .Default(1.0)
                .Range(0, 1)
                .Doc("fraction of the incident light reflected, per channel")};
  }

  explicit Mirror(const yarf::Properties& props)
      : reflectance_(yarf::TexturedValue::Color(props, "reflectance", Vec3(1.0f, 1.0f, 1.0f),
                                                /*unit=*/true)) {}

  void Sample(yarf::TransportMode, std::span<const float> wi, const yarf::SurfacePoints& at,
              std::span<const float> uniform, uint32_t allowed, std::span<float> wo,
              std::span<float> weight, std::span<float> pdf,
              std::span<uint32_t> flags) const override {
    const size_t count = wi.size() / 3;
    const bool can_reflect = yarf::LobeAllowed(kMirrorLobe, allowed);
    const yarf::SampleRows rows{wo, weight, pdf, flags};
    const auto reflectance = reflectance_.At(at);
    for (size_t k = 0; k < count; ++k) {
      const Vec3 in = Vec3::Load(&wi[3 * k]);
      if (!can_reflect || in.z == 0) {
        rows.StoreNoSample(k);
        continue;
      }
      rows.Store(k, yarf::Reflect(in), reflectance[k], 1.0f, kMirrorLobe);
    }
  }

  uint32_t Lobes() const override { return kMirrorLobe; }

 private:
  yarf::TexturedValue reflectance_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Mirror>(registrar, "mirror", "1.0.0", "Perfect specular reflection");
}
