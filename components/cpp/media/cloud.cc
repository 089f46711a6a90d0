// cloud — pbrt-v4's procedural cloud (its CloudMedium): a density in
// [0, 1] from a sum of octaves of Perlin noise, the lookup point first
// perturbed by the noise's gradient (wisps), thinning with height and
// full below y = 0 of the medium's space.
//
// The medium fills the box [p0, p1] of its own space, which to_world
// places (pbrt: the CTM where the medium is declared); the density is a
// function of the point in that space, not of its place in the box, as in
// pbrt-v4. Where the density is d:
//   σ_a = scale · d · sigma_a,   σ_s = scale · d · sigma_s.
// Its majorant is scale · (sigma_a + sigma_s) over the whole box, d never
// exceeding 1. It does not emit.
//
// Parameters: Cloud::Parameters() below; g, g2 and blend give the phase
// function (phase.h). scale is not in pbrt-v4.
#include <algorithm>
#include <cmath>
#include <utility>

#include "coefficients.h"
#include "majorant_grid.h"
#include "phase.h"
#include "volume_grid.h"
#include "yarf/plugin.h"
#include "yarf/support/perlin_noise.h"

namespace yarf {
namespace {

float FiniteProperty(const Properties& props, const char* key, double fallback) {
  const float value = float(props.Float(key, fallback));
  if (!std::isfinite(value)) throw Error(std::string("property '") + key + "' must be finite");
  return value;
}

class Cloud final : public UniformPhaseMedium {
 public:
  static ParameterSchema Parameters() {
    ParameterSchema schema = {
        Parameter::Float("density").Default(1.0).Doc("the density before clamping to [0, 1]"),
        Parameter::Float("wispiness").Default(1.0).Doc("how far the noise's gradient moves lookups (≤ 0: not)"),
        Parameter::Float("frequency").Default(5.0).Doc("the noise's frequency, per unit of the medium's space"),
        Parameter::Rgb("sigma_a").Default(1.0).Min(0).Doc("absorption per unit length at density 1"),
        Parameter::Rgb("sigma_s").Default(1.0).Min(0).Doc("scattering per unit length at density 1"),
        ScaleParameter(),
        Parameter::Vector("p0").Default(Vec3(0, 0, 0)).Doc("a corner of the box, in the medium's space"),
        Parameter::Vector("p1").Default(Vec3(1, 1, 1)).Doc("the opposite corner"),
        Parameter::Matrix("to_world").Doc("the medium's space to the world; identity when left out"),
    };
    for (Parameter& parameter : PhaseFunction::Parameters()) schema.push_back(std::move(parameter));
    return schema;
  }

  explicit Cloud(const Properties& props)
      : UniformPhaseMedium(props),
        sigma_a_(NonNegativeColor(props, "sigma_a", Vec3(1, 1, 1)) * Scale(props)),
        sigma_s_(NonNegativeColor(props, "sigma_s", Vec3(1, 1, 1)) * Scale(props)),
        density_(FiniteProperty(props, "density", 1)),
        wispiness_(FiniteProperty(props, "wispiness", 1)),
        frequency_(FiniteProperty(props, "frequency", 5)) {
    const Vec3 a = props.Vector("p0", Vec3(0, 0, 0)), b = props.Vector("p1", Vec3(1, 1, 1));
    for (int i = 0; i < 3; ++i) {
      if (!std::isfinite(a[i]) || !std::isfinite(b[i])) throw Error("properties 'p0' and 'p1' must be finite");
      if (a[i] == b[i]) throw Error("properties 'p0' and 'p1' must span a box, not a flat one");
    }
    lo_ = Vec3(std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z));
    const Vec3 hi(std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z));
    extent_ = hi - lo_;
    medium_from_world_ = InverseAffine(props.Matrix("to_world", Transform::Identity()), "property 'to_world'");
  }

  void Majorants(std::span<const float> origin, std::span<const float> direction, std::span<const float> tmax,
                 MajorantSegments& out) const override {
    out.Clear();
    const Vec3 sigma_t = sigma_a_ + sigma_s_;
    for (size_t i = 0; i < tmax.size(); ++i) {
      // In the box's unit cube; t stays the world ray's.
      const Vec3 o = ToUnit(medium_from_world_.Point(Vec3::Load(&origin[3 * i])));
      const Vec3 d = medium_from_world_.Vector(Vec3::Load(&direction[3 * i]));
      const Vec3 d_unit(d.x / extent_.x, d.y / extent_.y, d.z / extent_.z);
      float t0, t1;
      if (MaxComponent(sigma_t) > 0 && ClipToUnitCube(o, d_unit, tmax[i], t0, t1))
        out.segments.push_back({t0, t1, sigma_t});
      out.offsets.push_back(uint32_t(out.segments.size()));
    }
  }

  void Coefficients(std::span<const float> position, std::span<float> sigma_a, std::span<float> sigma_s,
                    std::span<float> emission) const override {
    for (size_t k = 0; 3 * k < position.size(); ++k) {
      const Vec3 p = medium_from_world_.Point(Vec3::Load(&position[3 * k]));
      const Vec3 u = ToUnit(p);
      const bool inside = u.x >= 0 && u.y >= 0 && u.z >= 0 && u.x <= 1 && u.y <= 1 && u.z <= 1;
      const float d = inside ? Density(p) : 0;
      (sigma_a_ * d).Store(&sigma_a[3 * k]);
      (sigma_s_ * d).Store(&sigma_s[3 * k]);
      Vec3(0, 0, 0).Store(&emission[3 * k]);
    }
  }

  bool Emits() const override { return false; }

 private:
  Vec3 ToUnit(Vec3 p) const {
    return Vec3((p.x - lo_.x) / extent_.x, (p.y - lo_.y) / extent_.y, (p.z - lo_.z) / extent_.z);
  }

  // pbrt-v4's CloudMedium::Density at p, a point of the medium's space.
  float Density(Vec3 p) const {
    Vec3 pp = p * frequency_;
    if (wispiness_ > 0) {
      float omega = 0.05f * wispiness_, lambda = 10;
      for (int i = 0; i < 2; ++i) {
        pp += NoiseGradient(pp * lambda) * omega;
        omega *= 0.5f;
        lambda *= 1.99f;
      }
    }
    float d = 0, omega = 0.5f, lambda = 1;
    for (int i = 0; i < 5; ++i) {
      d += omega * Noise(pp * lambda);
      omega *= 0.5f;
      lambda *= 1.99f;
    }
    d = std::clamp((1 - p.y) * 4.5f * density_ * d, 0.0f, 1.0f);
    d += 2 * std::max(0.0f, 0.5f - p.y);
    return std::clamp(d, 0.0f, 1.0f);
  }

  Vec3 sigma_a_, sigma_s_;
  float density_, wispiness_, frequency_;
  Vec3 lo_, extent_;
  Transform medium_from_world_;
};

}  // namespace
}  // namespace yarf

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::Cloud>(registrar, "cloud", "1.0.0",
                              "pbrt-v4's procedural cloud: a density from octaves of Perlin noise in a box");
}
