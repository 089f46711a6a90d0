// null — a surface that does not scatter: light passes straight through,
// unchanged. It bounds a medium (Mitsuba's null BSDF, pbrt-v4's
// "interface" material): methods that know media step through it without
// counting a bounce; the others see a delta transmission of weight 1.
//
// Parameters: Null::Parameters() below (none).
//
// Lobes: null (with refract and delta). Sample returns wo = -wi,
// weight = 1, pdf = 1.
#include <cstdint>
#include <span>

#include "yarf/support/scatter_rows.h"
#include "yarf/plugin.h"

namespace {

using yarf::Vec3;

constexpr uint32_t kNullLobe = yarf::kScatterNull | yarf::kScatterRefract | yarf::kScatterDelta;

class Null final : public yarf::DeltaSurfaceModel {
 public:
  static yarf::ParameterSchema Parameters() { return {}; }

  explicit Null(const yarf::Properties&) {}

  void Sample(yarf::TransportMode, std::span<const float> wi, const yarf::SurfacePoints&,
              std::span<const float>, uint32_t allowed, std::span<float> wo, std::span<float> weight,
              std::span<float> pdf, std::span<uint32_t> flags) const override {
    const bool can_pass = yarf::LobeAllowed(kNullLobe, allowed);
    const yarf::SampleRows rows{wo, weight, pdf, flags};
    for (size_t k = 0; k < wi.size() / 3; ++k) {
      const Vec3 in = Vec3::Load(&wi[3 * k]);
      if (!can_pass || in.z == 0) {
        rows.StoreNoSample(k);
        continue;
      }
      rows.Store(k, -in, Vec3(1, 1, 1), 1.0f, kNullLobe);
    }
  }

  uint32_t Lobes() const override { return kNullLobe; }
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Null>(registrar, "null", "1.0.0", "a boundary that passes light through unchanged (media only)");
}
