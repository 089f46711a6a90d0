// lambertian — ideal diffuse reflector
//
// Scatters incident light equally in all directions of the side it
// arrives on: f(wi, wo) = reflectance / π when wi and wo lie on the same
// side of the surface, 0 otherwise. Both sides reflect alike unless
// two_sided is false (DiffuseHemisphere). There is no transmission.
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

#include "diffuse_hemisphere.h"
#include "yarf/plugin.h"
#include "yarf/support/scatter_rows.h"
#include "yarf/texture.h"

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
            yarf::DiffuseHemisphere::TwoSidedParameter()};
  }

  explicit Lambertian(const yarf::Properties& props)
      : reflectance_(yarf::TexturedValue::Color(props, "reflectance", Vec3(0.5f, 0.5f, 0.5f),
                                                /*unit=*/true)),
        hemisphere_(props) {}

  void Evaluate(yarf::TransportMode, std::span<const float> wi, std::span<const float> wo,
                const yarf::SurfacePoints& at, std::span<float> value) const override {
    const auto reflectance = reflectance_.At(at);
    yarf::EvaluateEach(wi, wo, value, [&](size_t k, Vec3 in, Vec3 out) {
      return hemisphere_.Reflects(in, out) ? reflectance[k] * yarf::kInvPi : Vec3();
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
      float density;
      const Vec3 out = hemisphere_.Sample(Vec3::Load(&wi[3 * k]), uniform[3 * k + 1], uniform[3 * k + 2], density);
      if (!can_reflect || !(density > 0)) {
        rows.StoreNoSample(k);
        continue;
      }
      // f·|cos θo| / pdf = (ρ/π)·cos θo / (cos θo/π).
      rows.Store(k, out, reflectance[k], density, kLobe);
    }
  }

  void Pdf(std::span<const float> wi, std::span<const float> wo, const yarf::SurfacePoints& at,
           std::span<float> pdf) const override {
    yarf::PdfEach(wi, wo, pdf, [&](size_t, Vec3 in, Vec3 out) { return hemisphere_.Pdf(in, out); });
  }

  uint32_t Lobes() const override { return kLobe; }

 private:
  yarf::TexturedValue reflectance_;
  yarf::DiffuseHemisphere hemisphere_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Lambertian>(registrar, "lambertian", "1.0.0",
                             "Ideal diffuse (Lambertian) reflection, two-sided unless told otherwise");
}
