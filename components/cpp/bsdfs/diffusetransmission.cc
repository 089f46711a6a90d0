// diffusetransmission — diffuse reflection and diffuse transmission
//
// pbrt-v4's `diffusetransmission` (DiffuseTransmissionBxDF): a thin
// scattering sheet (paper, a lampshade, leaves) that sends light into the
// cosine-weighted hemisphere of either side:
//
//   f(wi, wo) = reflectance / π     when wi and wo lie on the same side,
//               transmittance / π   when they lie on opposite sides.
//
// Both sides alike; no radiance scaling (the same medium on both sides),
// so f is symmetric and the two transport modes agree.
//
// Parameters
//   reflectance     rgb (or float)   default 0.25   per channel in [0, 1]
//   transmittance   rgb (or float)   default 0.25   per channel in [0, 1]
// reflectance + transmittance must not exceed 1 in any channel (energy
// conservation).
//
// Lobes: diffuse reflection and diffuse transmission (kScatterRefract:
// wo on the other side), each present when its colour is not black.
// Sample picks one with probability proportional to the maximum channel
// of its colour (as pbrt), among the lobes `allowed` leaves, and draws wo
// from the cosine-weighted hemisphere of that side: the weight is the
// lobe's colour over its probability.
#include <cmath>
#include <cstdint>
#include <span>
#include <string>

#include "scatter_rows.h"
#include "surface_properties.h"
#include "yarf/plugin.h"
#include "yarf/warps.h"

namespace {

using yarf::Vec3;

constexpr uint32_t kReflectLobe = yarf::kScatterReflect | yarf::kScatterDiffuse;
constexpr uint32_t kTransmitLobe = yarf::kScatterRefract | yarf::kScatterDiffuse;

class DiffuseTransmission final : public yarf::SurfaceModel {
 public:
  explicit DiffuseTransmission(const yarf::Properties& props)
      : reflectance_(props.Reflectance("reflectance", Vec3(0.25f, 0.25f, 0.25f))),
        transmittance_(props.Reflectance("transmittance", Vec3(0.25f, 0.25f, 0.25f))) {
    yarf::RequireEnergyConserving(reflectance_, transmittance_, "reflectance", "transmittance");
    reflect_weight_ = yarf::MaxComponent(reflectance_);
    transmit_weight_ = yarf::MaxComponent(transmittance_);
  }

  void Evaluate(yarf::TransportMode, std::span<const float> wi, std::span<const float> wo,
                std::span<const float> uv, std::span<float> value) const override {
    yarf::EvaluateEach(wi, wo, value, [&](Vec3 in, Vec3 out) {
      const float product = in.z * out.z;
      const Vec3 f = product > 0 ? reflectance_ : (product < 0 ? transmittance_ : Vec3());
      return f * yarf::kInvPi;
    });
  }

  void Sample(yarf::TransportMode, std::span<const float> wi, std::span<const float> uv,
              std::span<const float> uniform, uint32_t allowed, std::span<float> wo,
              std::span<float> weight, std::span<float> pdf,
              std::span<uint32_t> flags) const override {
    const size_t count = wi.size() / 3;
    const float reflect_share =
        yarf::LobeAllowed(kReflectLobe, allowed) ? reflect_weight_ : 0.0f;
    const float transmit_share =
        yarf::LobeAllowed(kTransmitLobe, allowed) ? transmit_weight_ : 0.0f;
    const float total = reflect_share + transmit_share;
    const yarf::SampleRows rows{wo, weight, pdf, flags};
    for (size_t k = 0; k < count; ++k) {
      const float wi_z = wi[3 * k + 2];
      const float* u = &uniform[3 * k];
      const bool reflect = u[0] * total < reflect_share;
      Vec3 out = yarf::SampleCosineHemisphere(u[1], u[2]);
      // Onto wi's side for a reflection, the other side for a transmission.
      if ((wi_z < 0) == reflect) out.z = -out.z;
      const float probability = (reflect ? reflect_share : transmit_share) / total;
      const float density = total > 0 && wi_z != 0
                                ? probability * yarf::CosineHemispherePdf(std::abs(out.z))
                                : 0.0f;
      if (!(density > 0)) {
        rows.StoreNoSample(k);
        continue;
      }
      // f·|cos θo| / pdf = (colour/π)·|cos θo| / (probability·|cos θo|/π).
      rows.Store(k, out, (reflect ? reflectance_ : transmittance_) / probability, density,
                 reflect ? kReflectLobe : kTransmitLobe);
    }
  }

  void Pdf(std::span<const float> wi, std::span<const float> wo, std::span<const float> uv,
           std::span<float> pdf) const override {
    const float total = reflect_weight_ + transmit_weight_;
    yarf::PdfEach(wi, wo, pdf, [&](Vec3 in, Vec3 out) {
      const float product = in.z * out.z;
      const float share = product > 0 ? reflect_weight_ : (product < 0 ? transmit_weight_ : 0.0f);
      return total > 0 ? share / total * yarf::CosineHemispherePdf(std::abs(out.z)) : 0.0f;
    });
  }

  uint32_t Lobes() const override {
    return (reflect_weight_ > 0 ? kReflectLobe : 0u) | (transmit_weight_ > 0 ? kTransmitLobe : 0u);
  }

 private:
  Vec3 reflectance_;
  Vec3 transmittance_;
  // Max channels of the two colours: the odds of sampling each lobe.
  float reflect_weight_ = 0, transmit_weight_ = 0;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<DiffuseTransmission>(
      registrar, "diffusetransmission", "1.0.0",
      "Diffuse reflection and diffuse transmission (pbrt-v4's diffusetransmission), two-sided");
}
