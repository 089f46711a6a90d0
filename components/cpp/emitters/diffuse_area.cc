// diffuse_area — uniform diffuse area light
//
// Emits the same radiance in every direction of the front (+z, the side
// the shape's normal points to) of the surface it is attached to, and
// nothing from the back, as Mitsuba's one-sided area emitter.
//
// Parameters
//   radiance   rgb (or float)   required
//       Emitted radiance in W·m⁻²·sr⁻¹, per channel ≥ 0.
#include <cmath>
#include <cstdint>
#include <span>

#include "yarf/plugin.h"

namespace {

using yarf::Vec3;

Vec3 RequiredRadiance(const yarf::Properties& props) {
  const Vec3 radiance = props.Color("radiance");
  for (int c = 0; c < 3; ++c)
    if (!(radiance[c] >= 0.0f && std::isfinite(radiance[c])))
      throw yarf::Error("property 'radiance' must be finite and non-negative in every channel");
  return radiance;
}

class DiffuseArea final : public yarf::Emitter {
 public:
  explicit DiffuseArea(const yarf::Properties& props) : radiance_(RequiredRadiance(props)) {}

  void Radiance(std::span<const float> w, std::span<const float> uv,
                std::span<float> radiance) const override {
    const size_t count = w.size() / 3;
    for (size_t k = 0; k < count; ++k)
      (w[3 * k + 2] > 0 ? radiance_ : Vec3()).Store(&radiance[3 * k]);
  }

 private:
  Vec3 radiance_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<DiffuseArea>(registrar, "diffuse_area", "1.0.0",
                              "One-sided diffuse area light of constant radiance");
}
