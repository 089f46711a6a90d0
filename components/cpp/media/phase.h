// The phase functions media share: Henyey–Greenstein (isotropic at g = 0)
// and a blend of two Henyey–Greenstein lobes, each sampled exactly, so a
// sample's weight p/pdf is 1.
//
// Directions follow Medium's convention: wi back toward where the path
// came from, wo toward where light comes from, both away from the point.
// The cosine of the scattering angle between the light's direction of
// travel before (-wo) and after (wi) is μ = -wi·wo.
#pragma once

#include <cmath>
#include <vector>

#include "yarf/error.h"
#include "yarf/medium.h"
#include "yarf/parameters.h"
#include "yarf/properties.h"
#include "yarf/support/warps.h"

namespace yarf {

// p(μ) = (1 − g²) / (4π (1 + g² − 2gμ)^{3/2}); g > 0 scatters forward.
inline float HenyeyGreenstein(float mu, float g) {
  const float denominator = 1 + g * g - 2 * g * mu;
  return (1 - g * g) / (4 * kPi * denominator * std::sqrt(std::max(denominator, 1e-12f)));
}

// μ distributed as HenyeyGreenstein(μ, g) for u in [0, 1).
inline float SampleHenyeyGreensteinCosine(float g, float u) {
  if (std::abs(g) < 1e-3f) return 1 - 2 * u;
  const float s = (1 - g * g) / (1 - g + 2 * g * u);
  return std::clamp((1 + g * g - s * s) / (2 * g), -1.0f, 1.0f);
}

class PhaseFunction {
 public:
  // Properties: g (the mean cosine, in (-1, 1), default 0: isotropic);
  // for a second lobe, g2 and blend (its weight, in [0, 1], default 0):
  // Parameters().
  static std::vector<Parameter> Parameters() {
    return {
        Parameter::Float("g").Default(0.0).Range(-1, 1).Doc("the mean cosine, in (-1, 1); > 0 scatters forward"),
        Parameter::Float("g2").Default(0.0).Range(-1, 1).Doc("the second lobe's mean cosine, in (-1, 1)"),
        Parameter::Float("blend").Default(0.0).Range(0, 1).Doc("the second lobe's weight"),
    };
  }

  explicit PhaseFunction(const Properties& props)
      : g_(Asymmetry(props, "g")), g2_(Asymmetry(props, "g2")), blend_(float(props.Float("blend", 0))) {
    if (!(blend_ >= 0 && blend_ <= 1)) throw Error("property 'blend' must lie in [0, 1]");
  }

  // p(wi, wo), which is also the density of Sample.
  float Evaluate(Vec3 wi, Vec3 wo) const {
    const float mu = -Dot(wi, wo);
    const float p = HenyeyGreenstein(mu, g_);
    return blend_ > 0 ? (1 - blend_) * p + blend_ * HenyeyGreenstein(mu, g2_) : p;
  }

  // wo for uniform (u0, u1); u0 also picks the lobe.
  Vec3 Sample(Vec3 wi, float u0, float u1) const {
    float g = g_;
    if (blend_ > 0) {
      if (u0 < blend_) {
        g = g2_;
        u0 /= blend_;
      } else {
        u0 = (u0 - blend_) / (1 - blend_);
      }
      u0 = std::min(u0, 0x1.fffffep-1f);
    }
    const float mu = SampleHenyeyGreensteinCosine(g, u0);
    // The light travelled along -wo and leaves along wi: -wo lies at
    // angle acos μ around wi.
    const Vec3 travel = Frame(wi).ToWorld(SphericalDirection(SinFromCos(mu), mu, 2 * kPi * u1));
    return -travel;
  }

 private:
  static float Asymmetry(const Properties& props, const char* key) {
    const float g = float(props.Float(key, 0));
    if (!(g > -1 && g < 1)) throw Error(std::string("property '") + key + "' must lie in (-1, 1)");
    return g;
  }

  float g_, g2_, blend_;
};

// A Medium with one phase function everywhere (its properties g, g2,
// blend): the phase half of the interface, for every such medium.
class UniformPhaseMedium : public Medium {
 public:
  explicit UniformPhaseMedium(const Properties& props) : phase_(props) {}

  void EvaluatePhase(std::span<const float> wi, std::span<const float> wo, std::span<const float> position,
                     std::span<float> value, std::span<float> pdf) const final {
    for (size_t k = 0; k < value.size(); ++k)
      pdf[k] = value[k] = phase_.Evaluate(Vec3::Load(&wi[3 * k]), Vec3::Load(&wo[3 * k]));
  }
  void SamplePhase(std::span<const float> wi, std::span<const float> position, std::span<const float> uniform,
                   std::span<float> wo, std::span<float> weight, std::span<float> pdf) const final {
    for (size_t k = 0; k < weight.size(); ++k) {
      const Vec3 in = Vec3::Load(&wi[3 * k]);
      const Vec3 out = phase_.Sample(in, uniform[2 * k], uniform[2 * k + 1]);
      out.Store(&wo[3 * k]);
      pdf[k] = phase_.Evaluate(in, out);
      weight[k] = 1;
    }
  }

 private:
  PhaseFunction phase_;
};

}  // namespace yarf
