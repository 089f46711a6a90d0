// point — an isotropic point light; directional — a light from infinitely
// far; constant — the same radiance from every direction
//
// point: a light with no extent placed by the scene's Light.to_world. It
// has no radiance, only intensity: Radiance returns I in W·sr⁻¹ toward
// every direction, and total power is 4π·I.
//
// directional (a Light of kind DIRECTIONAL): Radiance returns the
// irradiance E in W·m⁻² that a surface facing the light receives; it
// travels along +z of its frame only, so the kernel never asks it for a
// direction.
//
// constant (a Light of kind ENVIRONMENT): radiance L in W·m⁻²·sr⁻¹
// arriving from every direction; directions are sampled uniformly.
//
// Parameters: IsotropicLight::Parameters() below (each class its one
// power property: intensity, irradiance or radiance).
#include <cstdint>
#include <span>

#include "intensity.h"
#include "yarf/plugin.h"
#include "yarf/support/warps.h"

namespace {

using yarf::Vec3;

// The same in every direction; `power` names the property, `doc` says
// what it is.
template <const char* power, const char* doc>
class IsotropicLight final : public yarf::Emitter {
 public:
  static yarf::ParameterSchema Parameters() { return {yarf::IntensityParameter(power, doc).Required()}; }

  explicit IsotropicLight(const yarf::Properties& props)
      : intensity_(yarf::RequiredIntensity(props, power)) {}

  void Radiance(std::span<const float> w, const yarf::SurfacePoints& at,
                std::span<float> radiance) const override {
    const size_t count = w.size() / 3;
    for (size_t k = 0; k < count; ++k) intensity_.Store(&radiance[3 * k]);
  }

  void SampleDirection(std::span<const float> uniform, std::span<float> w,
                       std::span<float> pdf) const override {
    const size_t count = uniform.size() / 2;
    for (size_t k = 0; k < count; ++k) {
      yarf::SampleUniformSphere(uniform[2 * k], uniform[2 * k + 1]).Store(&w[3 * k]);
      pdf[k] = yarf::UniformSpherePdf();
    }
  }

  void PdfDirection(std::span<const float> w, std::span<float> pdf) const override {
    std::fill(pdf.begin(), pdf.begin() + w.size() / 3, yarf::UniformSpherePdf());
  }

 private:
  Vec3 intensity_;
};

constexpr char kIntensity[] = "intensity";
constexpr char kIntensityDoc[] = "intensity toward every direction, W·sr⁻¹";
constexpr char kIrradiance[] = "irradiance";
constexpr char kIrradianceDoc[] = "irradiance on a surface facing the light, W·m⁻²";
constexpr char kRadiance[] = "radiance";
constexpr char kRadianceDoc[] = "radiance from every direction, W·m⁻²·sr⁻¹";

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<IsotropicLight<kIntensity, kIntensityDoc>>(registrar, "point", "1.0.0",
                                                            "Isotropic point light of given intensity");
  yarf::Register<IsotropicLight<kIrradiance, kIrradianceDoc>>(registrar, "directional", "1.0.0",
                                                              "Light from infinitely far, of given irradiance");
  yarf::Register<IsotropicLight<kRadiance, kRadianceDoc>>(
      registrar, "constant", "1.0.0", "Uniform environment: the same radiance from every direction");
}
