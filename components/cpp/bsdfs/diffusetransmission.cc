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
// Parameters: DiffuseTransmission::Parameters() below.
// reflectance + transmittance must not exceed 1 in any channel (energy
// conservation). Texture values are clamped to [0, 1], and where a
// textured pair sums to more than 1 both are scaled down to sum to 1.
//
// Lobes: diffuse reflection and diffuse transmission (kScatterRefract:
// wo on the other side), each present unless its colour is a constant
// black.
// Sample picks one with probability proportional to the maximum channel
// of its colour (as pbrt), among the lobes `allowed` leaves, and draws wo
// from the cosine-weighted hemisphere of that side: the weight is the
// lobe's colour over its probability.
#include <cmath>
#include <cstdint>
#include <optional>
#include <span>
#include <string>

#include "yarf/support/scatter_rows.h"
#include "surface_properties.h"
#include "yarf/plugin.h"
#include "yarf/texture.h"
#include "yarf/support/warps.h"

namespace {

using yarf::Vec3;

constexpr uint32_t kReflectLobe = yarf::kScatterReflect | yarf::kScatterDiffuse;
constexpr uint32_t kTransmitLobe = yarf::kScatterRefract | yarf::kScatterDiffuse;

class DiffuseTransmission final : public yarf::SurfaceModel {
 public:
  static yarf::ParameterSchema Parameters() {
    using P = yarf::Parameter;
    return {
        P::RgbTexture("reflectance").Default(0.25).Range(0, 1).Doc("diffuse reflection, per channel"),
        P::RgbTexture("transmittance").Default(0.25).Range(0, 1).Doc("diffuse transmission, per channel"),
    };
  }

  explicit DiffuseTransmission(const yarf::Properties& props)
      : reflectance_(yarf::TexturedValue::Color(props, "reflectance", Vec3(0.25f, 0.25f, 0.25f),
                                                /*unit=*/true)),
        transmittance_(yarf::TexturedValue::Color(props, "transmittance",
                                                  Vec3(0.25f, 0.25f, 0.25f), /*unit=*/true)) {
    yarf::RequireEnergyConserving(reflectance_, transmittance_, "reflectance", "transmittance");
  }

  void Evaluate(yarf::TransportMode, std::span<const float> wi, std::span<const float> wo,
                const yarf::SurfacePoints& at, std::span<float> value) const override {
    const Colours colours(*this, at);
    yarf::EvaluateEach(wi, wo, value, [&](size_t k, Vec3 in, Vec3 out) {
      const Local lobes = colours[k];
      const float product = in.z * out.z;
      const Vec3 f = product > 0 ? lobes.reflectance : (product < 0 ? lobes.transmittance : Vec3());
      return f * yarf::kInvPi;
    });
  }

  void Sample(yarf::TransportMode, std::span<const float> wi, const yarf::SurfacePoints& at,
              std::span<const float> uniform, uint32_t allowed, std::span<float> wo,
              std::span<float> weight, std::span<float> pdf,
              std::span<uint32_t> flags) const override {
    const size_t count = wi.size() / 3;
    const bool can_reflect = yarf::LobeAllowed(kReflectLobe, allowed);
    const bool can_transmit = yarf::LobeAllowed(kTransmitLobe, allowed);
    const Colours colours(*this, at);
    const yarf::SampleRows rows{wo, weight, pdf, flags};
    for (size_t k = 0; k < count; ++k) {
      const Local lobes = colours[k];
      const float reflect_share = can_reflect ? lobes.reflect_weight : 0.0f;
      const float transmit_share = can_transmit ? lobes.transmit_weight : 0.0f;
      const float total = reflect_share + transmit_share;
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
      rows.Store(k, out, (reflect ? lobes.reflectance : lobes.transmittance) / probability, density,
                 reflect ? kReflectLobe : kTransmitLobe);
    }
  }

  void Pdf(std::span<const float> wi, std::span<const float> wo, const yarf::SurfacePoints& at,
           std::span<float> pdf) const override {
    const Colours colours(*this, at);
    yarf::PdfEach(wi, wo, pdf, [&](size_t k, Vec3 in, Vec3 out) {
      const Local lobes = colours[k];
      const float total = lobes.reflect_weight + lobes.transmit_weight;
      const float product = in.z * out.z;
      const float share =
          product > 0 ? lobes.reflect_weight : (product < 0 ? lobes.transmit_weight : 0.0f);
      return total > 0 ? share / total * yarf::CosineHemispherePdf(std::abs(out.z)) : 0.0f;
    });
  }

  uint32_t Lobes() const override {
    return (reflectance_.IsZero() ? 0u : kReflectLobe) |
           (transmittance_.IsZero() ? 0u : kTransmitLobe);
  }

 private:
  // The two colours at one point, and the max channel of each: the odds
  // of sampling each lobe.
  struct Local {
    Vec3 reflectance, transmittance;
    float reflect_weight = 0, transmit_weight = 0;
  };

  // The colours at a call's points.
  class Colours {
   public:
    Colours(const DiffuseTransmission& model, const yarf::SurfacePoints& at)
        : reflectance_(model.reflectance_.At(at)),
          transmittance_(model.transmittance_.At(at)) {
      if (reflectance_.IsUniform() && transmittance_.IsUniform()) uniform_ = At(0);
    }

    Local operator[](size_t k) const { return uniform_ ? *uniform_ : At(k); }

   private:
    Local At(size_t k) const {
      Local out{reflectance_[k], transmittance_[k]};
      yarf::ConserveEnergy(out.reflectance, out.transmittance);
      out.reflect_weight = yarf::MaxComponent(out.reflectance);
      out.transmit_weight = yarf::MaxComponent(out.transmittance);
      return out;
    }

    yarf::PointValues<Vec3> reflectance_, transmittance_;
    // The colours at every point, when neither varies.
    std::optional<Local> uniform_;
  };

  yarf::TexturedValue reflectance_;
  yarf::TexturedValue transmittance_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<DiffuseTransmission>(
      registrar, "diffusetransmission", "1.0.0",
      "Diffuse reflection and diffuse transmission (pbrt-v4's diffusetransmission), two-sided");
}
