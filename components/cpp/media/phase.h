// The phase functions media share: Henyey–Greenstein (isotropic at g = 0),
// a blend of two Henyey–Greenstein lobes, Rayleigh's (small particles, as
// the sky's air), and one tabulated over the scattering angle's cosine
// (Mitsuba's tabphase), each sampled exactly, so a sample's weight p/pdf
// is 1.
//
// Directions follow Medium's convention: wi back toward where the path
// came from, wo toward where light comes from, both away from the point.
// The cosine of the scattering angle between the light's direction of
// travel before (-wo) and after (wi) is μ = -wi·wo.
#pragma once

#include <algorithm>
#include <cmath>
#include <span>
#include <string>
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

// p(μ) = 3 (1 + μ²) / (16π): scattering by particles much smaller than
// the light's wavelength.
inline float Rayleigh(float mu) { return 3 * (1 + mu * mu) / (16 * kPi); }

// μ distributed as Rayleigh(μ) for u in [0, 1): the root of the CDF's
// cubic μ³ + 3μ = 2z, z = 4u − 2 (Cardano's, one real root), made for
// |z| and given z's sign, where it loses no digits.
inline float SampleRayleighCosine(float u) {
  const double z = 4.0 * u - 2.0, a = std::cbrt(std::abs(z) + std::sqrt(z * z + 1));
  return std::clamp(float(std::copysign(a - 1 / a, z)), -1.0f, 1.0f);
}

// A phase function tabulated at evenly spaced μ from −1 to 1, linear
// between, normalised over the sphere; its μ drawn exactly (a segment by
// its area, then the point in it, inverting its linear density).
class TabulatedPhase {
 public:
  TabulatedPhase() = default;
  explicit TabulatedPhase(std::span<const float> values) : values_(values.begin(), values.end()) {
    if (values_.size() < 2) throw Error("property 'phase_values' needs at least 2 values, from μ = -1 to 1");
    for (const float v : values_)
      if (!(v >= 0 && std::isfinite(v))) throw Error("property 'phase_values' must hold finite numbers >= 0");
    // Normalised in double, so that ∫ p dω = 2π ∫ p dμ = 1 whatever the
    // values' scale (denormals included).
    const double step = Step();
    double area = 0;
    for (size_t i = 1; i < values_.size(); ++i) area += 0.5 * step * (double(values_[i - 1]) + values_[i]);
    if (!(area > 0)) throw Error("property 'phase_values' must not be all zero");
    for (float& v : values_) v = float(v / (2 * kPiDouble * area));
    cdf_.assign(values_.size(), 0.0);
    for (size_t i = 1; i < values_.size(); ++i) cdf_[i] = cdf_[i - 1] + 0.5 * step * (values_[i - 1] + values_[i]);
  }

  float Evaluate(float mu) const {
    const float x = (std::clamp(mu, -1.0f, 1.0f) + 1) / float(Step());
    const size_t i = std::min(size_t(x), values_.size() - 2);
    const float t = x - float(i);
    return (1 - t) * values_[i] + t * values_[i + 1];
  }

  float SampleCosine(float u) const {
    const double target = u * cdf_.back();
    const size_t i = std::min(size_t(std::upper_bound(cdf_.begin(), cdf_.end(), target) - cdf_.begin()),
                              cdf_.size() - 1) - 1;
    const double a = values_[i], b = values_[i + 1], step = Step();
    // The share of the segment's area below t: a t + (b − a) t² / 2 over
    // (a + b) / 2, solved in a form that holds as b → a.
    const double share = std::clamp((target - cdf_[i]) / (0.5 * step * (a + b)), 0.0, 1.0);
    const double t = share * (a + b) / (a + std::sqrt(std::max(0.0, a * a + (b * b - a * a) * share)));
    return std::clamp(float(-1 + (double(i) + t) * step), -1.0f, 1.0f);
  }

 private:
  static constexpr double kPiDouble = 3.14159265358979323846;
  double Step() const { return 2.0 / double(values_.size() - 1); }
  std::vector<float> values_;  // p at each μ, normalised
  std::vector<double> cdf_;    // the area below each value's μ
};

class PhaseFunction {
 public:
  // Properties: phase, the shape ("hg", the default; "rayleigh";
  // "tabulated", with phase_values); for hg, g (the mean cosine, in
  // (-1, 1), default 0: isotropic) and, for a second lobe, g2 and blend
  // (its weight, in [0, 1], default 0): Parameters().
  static std::vector<Parameter> Parameters() {
    return {
        Parameter::String("phase")
            .Default("hg")
            .Choices({"hg", "rayleigh", "tabulated"})
            .Doc("Henyey–Greenstein lobes, Rayleigh's, or tabulated (phase_values)"),
        Parameter::Float("g").Default(0.0).Range(-1, 1).Doc("the mean cosine, in (-1, 1); > 0 scatters forward"),
        Parameter::Float("g2").Default(0.0).Range(-1, 1).Doc("the second lobe's mean cosine, in (-1, 1)"),
        Parameter::Float("blend").Default(0.0).Range(0, 1).Doc("the second lobe's weight"),
        Parameter::FloatArray("phase_values")
            .Doc("tabulated: values ≥ 0 at evenly spaced cosines of the scattering angle, from -1 (back) to 1"),
    };
  }

  explicit PhaseFunction(const Properties& props)
      : shape_(ShapeOf(props)),
        g_(Asymmetry(props, "g")),
        g2_(Asymmetry(props, "g2")),
        blend_(float(props.Float("blend", 0))) {
    if (!(blend_ >= 0 && blend_ <= 1)) throw Error("property 'blend' must lie in [0, 1]");
    if (shape_ != Shape::kHenyeyGreenstein && (g_ != 0 || blend_ != 0))
      throw Error("properties 'g', 'g2' and 'blend' belong to phase 'hg'");
    if (shape_ == Shape::kTabulated) {
      if (!props.Has("phase_values")) throw Error("phase 'tabulated' needs property 'phase_values'");
      table_ = TabulatedPhase(props.FloatArray("phase_values"));
    } else if (props.Has("phase_values")) {
      throw Error("property 'phase_values' belongs to phase 'tabulated'");
    }
  }

  // p(wi, wo), which is also the density of Sample.
  float Evaluate(Vec3 wi, Vec3 wo) const {
    const float mu = -Dot(wi, wo);
    switch (shape_) {
      case Shape::kRayleigh:
        return Rayleigh(mu);
      case Shape::kTabulated:
        return table_.Evaluate(mu);
      case Shape::kHenyeyGreenstein:
        break;
    }
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
    const float mu = shape_ == Shape::kRayleigh    ? SampleRayleighCosine(u0)
                     : shape_ == Shape::kTabulated ? table_.SampleCosine(u0)
                                                   : SampleHenyeyGreensteinCosine(g, u0);
    // The light travelled along -wo and leaves along wi: -wo lies at
    // angle acos μ around wi.
    const Vec3 travel = Frame(wi).ToWorld(SphericalDirection(SinFromCos(mu), mu, 2 * kPi * u1));
    return -travel;
  }

 private:
  enum class Shape { kHenyeyGreenstein, kRayleigh, kTabulated };
  static Shape ShapeOf(const Properties& props) {
    const std::string name = props.String("phase", "hg");
    if (name == "hg") return Shape::kHenyeyGreenstein;
    if (name == "rayleigh") return Shape::kRayleigh;
    if (name == "tabulated") return Shape::kTabulated;
    throw Error("property 'phase' must be \"hg\", \"rayleigh\" or \"tabulated\", not \"" + name + "\"");
  }
  static float Asymmetry(const Properties& props, const char* key) {
    const float g = float(props.Float(key, 0));
    if (!(g > -1 && g < 1)) throw Error(std::string("property '") + key + "' must lie in (-1, 1)");
    return g;
  }

  Shape shape_;
  float g_, g2_, blend_;
  TabulatedPhase table_;
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
