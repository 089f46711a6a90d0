// homogeneous — a medium with the same coefficients everywhere (pbrt-v4's
// "homogeneous", Mitsuba 3's "homogeneous" once its σ_t and albedo are
// split into σ_a and σ_s).
//
// Its majorant is its own extinction, so null-scattering tracking never
// meets a null collision in it.
//
// Parameters: Homogeneous::Parameters() below; g, g2 and blend give the
// phase function (phase.h).
#include <algorithm>
#include <utility>

#include "coefficients.h"
#include "phase.h"
#include "yarf/plugin.h"

namespace yarf {
namespace {

class Homogeneous final : public UniformPhaseMedium {
 public:
  static ParameterSchema Parameters() {
    ParameterSchema schema = {
        Parameter::Rgb("sigma_a").Default(0.0).Min(0).Doc("absorption per unit length"),
        Parameter::Rgb("sigma_s").Default(0.0).Min(0).Doc("scattering per unit length"),
        ScaleParameter(),
        Parameter::Rgb("emission").Default(0.0).Min(0).Doc("radiance emitted where it absorbs (pbrt's Le)"),
    };
    for (Parameter& parameter : PhaseFunction::Parameters()) schema.push_back(std::move(parameter));
    return schema;
  }

  explicit Homogeneous(const Properties& props)
      : UniformPhaseMedium(props),
        sigma_a_(NonNegativeColor(props, "sigma_a") * Scale(props)),
        sigma_s_(NonNegativeColor(props, "sigma_s") * Scale(props)),
        emission_(NonNegativeColor(props, "emission")) {}

  void Majorants(std::span<const float> origin, std::span<const float> direction, std::span<const float> tmax,
                 MajorantSegments& out) const override {
    out.Clear();
    const Vec3 sigma_t = sigma_a_ + sigma_s_;
    for (size_t i = 0; i < tmax.size(); ++i) {
      if (MaxComponent(sigma_t) > 0 && tmax[i] > 0) out.segments.push_back({0, tmax[i], sigma_t});
      out.offsets.push_back(uint32_t(out.segments.size()));
    }
  }

  void Coefficients(std::span<const float> position, std::span<float> sigma_a, std::span<float> sigma_s,
                    std::span<float> emission) const override {
    for (size_t k = 0; 3 * k < position.size(); ++k) {
      sigma_a_.Store(&sigma_a[3 * k]);
      sigma_s_.Store(&sigma_s[3 * k]);
      emission_.Store(&emission[3 * k]);
    }
  }

  bool Emits() const override { return MaxComponent(emission_) > 0 && MaxComponent(sigma_a_) > 0; }

 private:
  Vec3 sigma_a_, sigma_s_, emission_;
};

}  // namespace
}  // namespace yarf

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::Homogeneous>(registrar, "homogeneous", "1.0.0",
                                    "a medium with the same absorption, scattering and phase function everywhere");
}
