// As components/cpp/bsdfs/lambertian.cc, with a constant reflectance and
// only the installed headers: a plugin built outside yarf's tree.
#include <cmath>
#include <span>
#include "yarf/plugin.h"
#include "yarf/support/warps.h"

namespace {
constexpr uint32_t kLobe = yarf::kScatterReflect | yarf::kScatterDiffuse;

class Grey final : public yarf::SurfaceModel {
 public:
  explicit Grey(const yarf::Properties& props) : reflectance_(props.Reflectance("reflectance", yarf::Vec3(0.5f, 0.5f, 0.5f))) {}
  void Evaluate(yarf::TransportMode, std::span<const float> wi, std::span<const float> wo,
                const yarf::SurfacePoints&, std::span<float> value) const override {
    for (size_t k = 0; k < wi.size() / 3; ++k) {
      const yarf::Vec3 f = wi[3 * k + 2] * wo[3 * k + 2] > 0 ? reflectance_ * yarf::kInvPi : yarf::Vec3();
      f.Store(&value[3 * k]);
    }
  }
  void Sample(yarf::TransportMode, std::span<const float> wi, const yarf::SurfacePoints&,
              std::span<const float> uniform, uint32_t allowed, std::span<float> wo, std::span<float> weight,
              std::span<float> pdf, std::span<uint32_t> flags) const override {
    for (size_t k = 0; k < wi.size() / 3; ++k) {
      yarf::Vec3 out = yarf::SampleCosineHemisphere(uniform[3 * k + 1], uniform[3 * k + 2]);
      if (wi[3 * k + 2] < 0) out.z = -out.z;
      const float density = yarf::CosineHemispherePdf(std::abs(out.z));
      const bool drawn = yarf::LobeAllowed(kLobe, allowed) && wi[3 * k + 2] != 0 && density > 0;
      (drawn ? out : yarf::Vec3()).Store(&wo[3 * k]);
      (drawn ? reflectance_ : yarf::Vec3()).Store(&weight[3 * k]);
      pdf[k] = drawn ? density : 0;
      flags[k] = drawn ? kLobe : 0;
    }
  }
  void Pdf(std::span<const float> wi, std::span<const float> wo, const yarf::SurfacePoints&,
           std::span<float> pdf) const override {
    for (size_t k = 0; k < wi.size() / 3; ++k)
      pdf[k] = wi[3 * k + 2] * wo[3 * k + 2] > 0 ? yarf::CosineHemispherePdf(std::abs(wo[3 * k + 2])) : 0;
  }
  uint32_t Lobes() const override { return kLobe; }

 private:
  yarf::Vec3 reflectance_;
};
}  // namespace

YARF_PLUGIN(registrar) { yarf::Register<Grey>(registrar, "oot_grey", "1.0.0", "grey, built out of tree"); }
