// spot — a point light shining into a cone around its +z axis
//
// Intensity I inside beam_width of the axis, falling to 0 at cutoff_angle,
// and 0 beyond. The falloff between is Mitsuba's (linear in the angle) or
// pbrt-v4's (smoothstep in the cosine: pbrt's coneangle is cutoff_angle,
// coneangle − conedelta is beam_width). The light's frame comes from the
// scene's Light.to_world.
//
// Parameters: SpotLight::Parameters() below.
#include <cmath>
#include <cstdint>
#include <span>
#include <string>

#include "intensity.h"
#include "yarf/plugin.h"
#include "yarf/support/warps.h"

namespace {

using yarf::Vec3;

float Radians(double degrees) { return float(degrees * 3.14159265358979323846 / 180.0); }

class SpotLight final : public yarf::Emitter {
 public:
  static yarf::ParameterSchema Parameters() {
    using P = yarf::Parameter;
    return {
        yarf::IntensityParameter("intensity", "intensity on the axis, W·sr⁻¹").Required(),
        P::Float("cutoff_angle").Default(20).Range(0, 90).Doc("degrees from the axis where the light ends, > 0"),
        P::Float("beam_width").Range(0, 90).Doc("degrees of full intensity, <= cutoff_angle; ¾ of it when absent"),
        P::String("falloff").Default("linear").Choices({"linear", "smoothstep"}).Doc(
            "linear in the angle (Mitsuba) or smoothstep in the cosine (pbrt-v4)"),
    };
  }

  explicit SpotLight(const yarf::Properties& props)
      : intensity_(yarf::RequiredIntensity(props, "intensity")),
        cutoff_(Radians(props.Float("cutoff_angle", 20.0))),
        beam_(props.Has("beam_width") ? Radians(props.Float("beam_width", 0.0)) : 0.75f * cutoff_),
        cos_cutoff_(std::cos(cutoff_)), cos_beam_(std::cos(beam_)) {
    const std::string falloff = props.String("falloff", "linear");
    if (falloff != "linear" && falloff != "smoothstep")
      throw yarf::Error("property 'falloff' must be \"linear\" or \"smoothstep\", not \"" + falloff + "\"");
    smoothstep_ = falloff == "smoothstep";
    if (!(cutoff_ > 0 && cutoff_ <= yarf::kPi / 2 + 1e-6f))
      throw yarf::Error("property 'cutoff_angle' must be in (0, 90] degrees");
    if (!(beam_ >= 0 && beam_ <= cutoff_))
      throw yarf::Error("property 'beam_width' must be in [0, cutoff_angle] degrees");
  }

  void Radiance(std::span<const float> w, const yarf::SurfacePoints& at,
                std::span<float> radiance) const override {
    const size_t count = w.size() / 3;
    for (size_t k = 0; k < count; ++k) (intensity_ * Falloff(w[3 * k + 2])).Store(&radiance[3 * k]);
  }

  // Uniform inside the cutoff cone.
  void SampleDirection(std::span<const float> uniform, std::span<float> w,
                       std::span<float> pdf) const override {
    const size_t count = uniform.size() / 2;
    for (size_t k = 0; k < count; ++k) {
      yarf::SampleUniformCone(uniform[2 * k], uniform[2 * k + 1], cos_cutoff_).Store(&w[3 * k]);
      pdf[k] = yarf::UniformConePdf(1.0f, cos_cutoff_);
    }
  }

  void PdfDirection(std::span<const float> w, std::span<float> pdf) const override {
    const size_t count = w.size() / 3;
    for (size_t k = 0; k < count; ++k) pdf[k] = yarf::UniformConePdf(w[3 * k + 2], cos_cutoff_);
  }

 private:
  float Falloff(float cos_theta) const {
    if (cos_theta <= cos_cutoff_) return 0.0f;
    if (cos_theta >= cos_beam_) return 1.0f;
    if (smoothstep_) {
      const float t = (cos_theta - cos_cutoff_) / (cos_beam_ - cos_cutoff_);
      return t * t * (3 - 2 * t);
    }
    return (cutoff_ - std::acos(cos_theta)) / (cutoff_ - beam_);
  }

  Vec3 intensity_;
  float cutoff_, beam_;
  float cos_cutoff_, cos_beam_;
  bool smoothstep_ = false;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<SpotLight>(registrar, "spot", "1.0.0",
                            "Point light shining into a cone, its edge falling off as Mitsuba's or pbrt-v4's");
}
