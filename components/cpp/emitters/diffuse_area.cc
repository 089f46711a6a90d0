// diffuse_area — uniform diffuse area light
//
// Emits the same radiance in every direction of the front (+z, the side
// the shape's normal points to) of the surface it is attached to, and
// nothing from the back, as Mitsuba's one-sided area emitter; or from both
// sides alike (pbrt-v4's "twosided" area light, twice the power).
//
// Parameters: DiffuseArea::Parameters() below.
// A radiance texture is looked up at the emitting point's uv, its values
// clamped to >= 0.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>

#include "intensity.h"
#include "yarf/plugin.h"
#include "yarf/texture.h"
#include "yarf/support/warps.h"

namespace {

using yarf::Vec3;

class DiffuseArea final : public yarf::Emitter {
 public:
  static yarf::ParameterSchema Parameters() {
    return {
        yarf::TexturedIntensityParameter("radiance", "emitted radiance, W·m⁻²·sr⁻¹").Required(),
        yarf::Parameter::Bool("two_sided").Default(false).Doc("emits from the back as from the front"),
    };
  }

  explicit DiffuseArea(const yarf::Properties& props)
      : radiance_(yarf::RequiredTexturedIntensity(props, "radiance")),
        two_sided_(props.Bool("two_sided", false)) {}

  void Radiance(std::span<const float> w, const yarf::SurfacePoints& at,
                std::span<float> radiance) const override {
    const size_t count = w.size() / 3;
    const auto emitted = radiance_.At(at);
    for (size_t k = 0; k < count; ++k)
      (Emits(w[3 * k + 2]) ? emitted[k] : Vec3()).Store(&radiance[3 * k]);
  }

  // Cosine-weighted over the front hemisphere (emitted power goes as
  // cos θ); two-sided, over either hemisphere with probability ½, the
  // first number choosing it and rescaled.
  void SampleDirection(std::span<const float> uniform, std::span<float> w,
                       std::span<float> pdf) const override {
    const size_t count = uniform.size() / 2;
    for (size_t k = 0; k < count; ++k) {
      float u0 = uniform[2 * k];
      const bool back = two_sided_ && u0 >= 0.5f;
      if (two_sided_) u0 = std::min(2 * (back ? u0 - 0.5f : u0), 0x1.fffffep-1f);
      Vec3 d = yarf::SampleCosineHemisphere(u0, uniform[2 * k + 1]);
      if (back) d.z = -d.z;
      d.Store(&w[3 * k]);
      pdf[k] = Pdf(d.z);
    }
  }

  void PdfDirection(std::span<const float> w, std::span<float> pdf) const override {
    const size_t count = w.size() / 3;
    for (size_t k = 0; k < count; ++k) pdf[k] = Pdf(w[3 * k + 2]);
  }

 private:
  bool Emits(float cos_theta) const { return cos_theta > 0 || (two_sided_ && cos_theta < 0); }
  float Pdf(float cos_theta) const {
    if (!Emits(cos_theta)) return 0.0f;
    return yarf::CosineHemispherePdf(std::abs(cos_theta)) * (two_sided_ ? 0.5f : 1.0f);
  }

  yarf::TexturedValue radiance_;
  bool two_sided_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<DiffuseArea>(registrar, "diffuse_area", "1.0.0",
                              "One-sided diffuse area light, its radiance constant or a texture");
}
