// lambertian — ideal diffuse reflector
//
// Scatters incident light equally in all directions of the side it
// arrives on: f(wi, wo) = reflectance / π when wi and wo lie on the same
// side of the surface, 0 otherwise. Both sides reflect alike (a two-sided
// material, as pbrt's DiffuseBxDF) unless two_sided is false: then the
// back side is black (Mitsuba's diffuse, one-sided unless wrapped in its
// twosided). There is no transmission.
//
// Parameters: Lambertian::Parameters() below. A texture's values are
// clamped to [0, 1].
//
// Lobes: reflection. Sample draws wo from the cosine-weighted hemisphere
// on wi's side, so its weight is the reflectance itself.
#include <cmath>
#include <cstdint>
#include <span>
#include <string>

#include "yarf/support/scatter_rows.h"
#include "yarf/plugin.h"
#include "yarf/texture.h"
#include "yarf/support/warps.h"

namespace {

using yarf::Vec3;

constexpr uint32_t kLobe = yarf::kScatterReflect | yarf::kScatterDiffuse;

class Lambertian final : public yarf::SurfaceModel {
 public:
  static yarf::ParameterSchema Parameters() {
    return {yarf::Parameter::RgbTexture("reflectance")
                .Default(0.5)
                .Range(0, 1)
                .Doc("fraction of the incident light reflected, per channel"),
            yarf::Parameter::Bool("two_sided").Default(true).Doc(
                "whether the back side reflects like the front (false: it is black)")};
  }

  explicit Lambertian(const yarf::Properties& props)
      : reflectance_(yarf::TexturedValue::Color(props, "reflectance", Vec3(0.5f, 0.5f, 0.5f),
                                                /*unit=*/true)),
        two_sided_(props.Bool("two_sided", true)) {}

  void Evaluate(yarf::TransportMode, std::span<const float> wi, std::span<const float> wo,
                const yarf::SurfacePoints& at, std::span<float> value) const override {
    const auto reflectance = reflectance_.At(at);
    yarf::EvaluateEach(wi, wo, value, [&](size_t k, Vec3 in, Vec3 out) {
      return Reflects(in, out) ? reflectance[k] * yarf::kInvPi : Vec3();
    });
  }

  void Sample(yarf::TransportMode, std::span<const float> wi, const yarf::SurfacePoints& at,
              std::span<const float> uniform, uint32_t allowed, std::span<float> wo,
              std::span<float> weight, std::span<float> pdf,
              std::span<uint32_t> flags) const override {
    const size_t count = wi.size() / 3;
    const bool can_reflect = yarf::LobeAllowed(kLobe, allowed);
    const yarf::SampleRows rows{wo, weight, pdf, flags};
    const auto reflectance = reflectance_.At(at);
    for (size_t k = 0; k < count; ++k) {
      const float wi_z = wi[3 * k + 2];
      Vec3 out = yarf::SampleCosineHemisphere(uniform[3 * k + 1], uniform[3 * k + 2]);
      // Mirror onto wi's side: the back face reflects like the front.
      if (wi_z < 0) out.z = -out.z;
      const float density = yarf::CosineHemispherePdf(std::abs(out.z));
      if (!can_reflect || wi_z == 0 || (wi_z < 0 && !two_sided_) || density <= 0) {
        rows.StoreNoSample(k);
        continue;
      }
      // f·|cos θo| / pdf = (ρ/π)·cos θo / (cos θo/π).
      rows.Store(k, out, reflectance[k], density, kLobe);
    }
  }

  void Pdf(std::span<const float> wi, std::span<const float> wo, const yarf::SurfacePoints& at,
           std::span<float> pdf) const override {
    yarf::PdfEach(wi, wo, pdf, [&](size_t, Vec3 in, Vec3 out) {
      return Reflects(in, out) ? yarf::CosineHemispherePdf(std::abs(out.z)) : 0.0f;
    });
  }

  uint32_t Lobes() const override { return kLobe; }

 private:
  // wi and wo on one side: the front, or either when two-sided.
  bool Reflects(Vec3 in, Vec3 out) const { return in.z * out.z > 0 && (two_sided_ || in.z > 0); }

  yarf::TexturedValue reflectance_;
  bool two_sided_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Lambertian>(registrar, "lambertian", "1.0.0",
                             "Ideal diffuse (Lambertian) reflection, two-sided unless told otherwise");
}
