// phong — the modified Phong reflection model
//
// The energy-conserving, reciprocal Phong model of Lafortune & Willems
// (1994), a diffuse term plus a glossy lobe around the mirror direction:
//
//   f(wi, wo) = kd / π + ks · (n + 2) / (2π) · cos^n α
//
// where α is the angle between wo and the mirror direction of wi (the
// lobe is 0 beyond α = 90°). The (n + 2)/(2π) factor makes the glossy
// lobe reflect at most ks (exactly ks at normal incidence). Both sides
// reflect alike (two-sided); wi and wo on opposite sides give 0.
//
// Parameters: Phong::Parameters() below.
// kd + ks must not exceed 1 in any channel (energy conservation). Texture
// values are clamped to these ranges, and where textured kd + ks exceeds
// 1 in a channel both are scaled down to sum to 1.
//
// Lobes: diffuse reflection (unless kd is a constant 0) and glossy
// reflection (unless ks is). Sample picks one of the allowed lobes with
// probability proportional to the luminance of kd and ks at the point,
// draws wo from the
// cosine-weighted hemisphere or the cos^n lobe around the mirror
// direction, and returns the density of the mixture of the allowed lobes
// (and their value in the weight).
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <utility>

#include "yarf/support/scatter_rows.h"
#include "surface_properties.h"
#include "yarf/plugin.h"
#include "yarf/texture.h"
#include "yarf/support/warps.h"

namespace {

using yarf::Vec3;

constexpr uint32_t kDiffuseLobe = yarf::kScatterReflect | yarf::kScatterDiffuse;
constexpr uint32_t kGlossyLobe = yarf::kScatterReflect | yarf::kScatterGlossy;

// The exponent property: a finite number ≥ 0, or a texture clamped to ≥ 0.
yarf::TexturedValue ReadExponent(const yarf::Properties& props) {
  if (auto texture = props.TextureOf("exponent"))
    return yarf::TexturedValue(std::move(texture)).Clamped(0.0f, std::numeric_limits<float>::max());
  const double exponent = props.Float("exponent", 30.0);
  if (!(exponent >= 0.0 && std::isfinite(exponent)))
    throw yarf::Error("property 'exponent' must be a finite number ≥ 0");
  return yarf::TexturedValue(float(exponent));
}

class Phong final : public yarf::SurfaceModel {
 public:
  static yarf::ParameterSchema Parameters() {
    using P = yarf::Parameter;
    return {
        P::RgbTexture("diffuse_reflectance").Default(0.5).Range(0, 1).Doc("kd, per channel"),
        P::RgbTexture("specular_reflectance").Default(0.2).Range(0, 1).Doc("ks, per channel"),
        P::FloatTexture("exponent").Default(30.0).Min(0).Doc("n; larger is shinier"),
    };
  }

  explicit Phong(const yarf::Properties& props)
      : diffuse_(yarf::TexturedValue::Color(props, "diffuse_reflectance",
                                            Vec3(0.5f, 0.5f, 0.5f), /*unit=*/true)),
        specular_(yarf::TexturedValue::Color(props, "specular_reflectance",
                                             Vec3(0.2f, 0.2f, 0.2f), /*unit=*/true)),
        exponent_(ReadExponent(props)) {
    yarf::RequireEnergyConserving(diffuse_, specular_, "diffuse_reflectance",
                                  "specular_reflectance");
  }

  void Evaluate(yarf::TransportMode, std::span<const float> wi, std::span<const float> wo,
                const yarf::SurfacePoints& at, std::span<float> value) const override {
    const PointParameters parameters(*this, at);
    yarf::EvaluateEach(wi, wo, value, [&](size_t k, Vec3 in, Vec3 out) {
      return parameters[k].Value(in, out, true, true);
    });
  }

  void Sample(yarf::TransportMode, std::span<const float> wi, const yarf::SurfacePoints& at,
              std::span<const float> uniform, uint32_t allowed, std::span<float> wo,
              std::span<float> weight, std::span<float> pdf,
              std::span<uint32_t> flags) const override {
    const size_t count = wi.size() / 3;
    const bool can_diffuse = yarf::LobeAllowed(kDiffuseLobe, allowed);
    const bool can_glossy = yarf::LobeAllowed(kGlossyLobe, allowed);
    const PointParameters parameters(*this, at);
    const yarf::SampleRows rows{wo, weight, pdf, flags};
    for (size_t k = 0; k < count; ++k) {
      const Local local = parameters[k];
      const bool diffuse = can_diffuse && local.diffuse_weight > 0;
      const bool glossy = can_glossy && local.specular_weight > 0;
      const float total =
          (diffuse ? local.diffuse_weight : 0.0f) + (glossy ? local.specular_weight : 0.0f);
      const float specular_probability =
          total > 0 ? (glossy ? local.specular_weight : 0.0f) / total : 0.0f;
      const Vec3 in = Vec3::Load(&wi[3 * k]);
      const float* u = &uniform[3 * k];
      Vec3 out;
      const bool specular = u[0] < specular_probability;
      if (specular) {
        // The lobe is symmetric about the mirror direction: sample it in
        // a frame whose z axis is that direction.
        const yarf::Frame mirror(yarf::Reflect(in));
        out = mirror.ToWorld(yarf::SamplePhongLobe(u[1], u[2], local.exponent));
      } else {
        out = yarf::SampleCosineHemisphere(u[1], u[2]);
        if (in.z < 0) out.z = -out.z;
      }
      // Zero when the glossy lobe dipped below the surface.
      const float density = total > 0 ? local.Density(in, out, specular_probability) : 0.0f;
      if (!(density > 0)) {
        rows.StoreNoSample(k);
        continue;
      }
      rows.Store(k, out, local.Value(in, out, diffuse, glossy) * (std::abs(out.z) / density),
                 density, specular ? kGlossyLobe : kDiffuseLobe);
    }
  }

  void Pdf(std::span<const float> wi, std::span<const float> wo, const yarf::SurfacePoints& at,
           std::span<float> pdf) const override {
    const PointParameters parameters(*this, at);
    yarf::PdfEach(wi, wo, pdf, [&](size_t k, Vec3 in, Vec3 out) {
      const Local local = parameters[k];
      return local.Density(in, out, local.specular_probability);
    });
  }

  uint32_t Lobes() const override {
    return (diffuse_.IsZero() ? 0u : kDiffuseLobe) | (specular_.IsZero() ? 0u : kGlossyLobe);
  }

 private:
  // The model at one point.
  struct Local {
    Vec3 diffuse, specular;
    float exponent = 0;
    // Luminances of kd and ks: the odds of sampling each lobe.
    float diffuse_weight = 0, specular_weight = 0;
    float specular_probability = 0;

    // f of the lobes asked for.
    Vec3 Value(Vec3 wi, Vec3 wo, bool with_diffuse, bool with_glossy) const {
      if (!(wi.z * wo.z > 0)) return Vec3();
      const float cos_alpha = CosToMirror(wi, wo);
      const float lobe = with_glossy && cos_alpha > 0 ? (exponent + 2.0f) / (2.0f * yarf::kPi) *
                                                            std::pow(cos_alpha, exponent)
                                                      : 0.0f;
      return (with_diffuse ? diffuse * yarf::kInvPi : Vec3()) + specular * lobe;
    }

    // Density of the lobe mixture Sample draws from; the part of the
    // glossy lobe below the surface is lost (Sample returns no sample
    // there).
    float Density(Vec3 wi, Vec3 wo, float p_specular) const {
      if (!(wi.z * wo.z > 0)) return 0.0f;
      return (1.0f - p_specular) * yarf::CosineHemispherePdf(std::abs(wo.z)) +
             p_specular * yarf::PhongLobePdf(CosToMirror(wi, wo), exponent);
    }
  };

  // The parameters at a call's points.
  class PointParameters {
   public:
    PointParameters(const Phong& model, const yarf::SurfacePoints& at)
        : diffuse_(model.diffuse_.At(at)),
          specular_(model.specular_.At(at)),
          exponent_(model.exponent_.FloatsAt(at)) {
      if (diffuse_.IsUniform() && specular_.IsUniform() && exponent_.IsUniform()) uniform_ = At(0);
    }

    Local operator[](size_t k) const { return uniform_ ? *uniform_ : At(k); }

   private:
    Local At(size_t k) const {
      Local out{diffuse_[k], specular_[k], exponent_[k]};
      yarf::ConserveEnergy(out.diffuse, out.specular);
      out.diffuse_weight = yarf::Luminance(out.diffuse);
      out.specular_weight = yarf::Luminance(out.specular);
      const float total = out.diffuse_weight + out.specular_weight;
      out.specular_probability = total > 0 ? out.specular_weight / total : 0.0f;
      return out;
    }

    yarf::PointValues<Vec3> diffuse_, specular_;
    yarf::PointValues<float> exponent_;
    // The model at every point, when no parameter varies.
    std::optional<Local> uniform_;
  };

  // cos α between wo and the mirror direction of wi. Symmetric in wi and
  // wo, which makes the model reciprocal, and unchanged by mirroring both
  // to the other side, which makes it two-sided.
  static float CosToMirror(Vec3 wi, Vec3 wo) { return yarf::Dot(wo, yarf::Reflect(wi)); }

  yarf::TexturedValue diffuse_;
  yarf::TexturedValue specular_;
  yarf::TexturedValue exponent_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Phong>(registrar, "phong", "1.0.0",
                        "Modified Phong (Lafortune & Willems 1994): diffuse plus a glossy lobe");
}
