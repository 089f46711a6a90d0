// diffuse_area — uniform diffuse area light
//
// Emits the same radiance in every direction of the front (+z, the side
// the shape's normal points to) of the surface it is attached to, and
// nothing from the back, as Mitsuba's one-sided area emitter.
//
// Parameters
//   radiance   rgb, float or texture   required
//       Emitted radiance in W·m⁻²·sr⁻¹, per channel ≥ 0; a texture is
//       looked up at the emitting point's uv, its values clamped to ≥ 0.
#include <cmath>
#include <cstdint>
#include <span>

#include "intensity.h"
#include "yarf/plugin.h"
#include "yarf/texture.h"
#include "yarf/warps.h"

namespace {

using yarf::Vec3;

class DiffuseArea final : public yarf::Emitter {
 public:
  explicit DiffuseArea(const yarf::Properties& props)
      : radiance_(yarf::RequiredTexturedIntensity(props, "radiance")) {}

  void Radiance(std::span<const float> w, const yarf::SurfacePoints& at,
                std::span<float> radiance) const override {
    const size_t count = w.size() / 3;
    const auto emitted = radiance_.At(at);
    for (size_t k = 0; k < count; ++k)
      (w[3 * k + 2] > 0 ? emitted[k] : Vec3()).Store(&radiance[3 * k]);
  }

  // Cosine-weighted over the front hemisphere: emitted power goes as cos θ.
  void SampleDirection(std::span<const float> uniform, std::span<float> w,
                       std::span<float> pdf) const override {
    const size_t count = uniform.size() / 2;
    for (size_t k = 0; k < count; ++k) {
      const Vec3 d = yarf::SampleCosineHemisphere(uniform[2 * k], uniform[2 * k + 1]);
      d.Store(&w[3 * k]);
      pdf[k] = yarf::CosineHemispherePdf(d.z);
    }
  }

  void PdfDirection(std::span<const float> w, std::span<float> pdf) const override {
    const size_t count = w.size() / 3;
    for (size_t k = 0; k < count; ++k)
      pdf[k] = w[3 * k + 2] > 0 ? yarf::CosineHemispherePdf(w[3 * k + 2]) : 0.0f;
  }

 private:
  yarf::TexturedValue radiance_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<DiffuseArea>(registrar, "diffuse_area", "1.0.0",
                              "One-sided diffuse area light, its radiance constant or a texture");
}
