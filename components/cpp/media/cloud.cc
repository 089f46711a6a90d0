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

namespace yarf {
namespace {

// Ken Perlin's permutation of 0..255, twice, as pbrt's Perlin noise uses
// it (so that the clouds are pbrt's).
constexpr int kPermutation[512] = {
    151, 160, 137, 91,  90,  15,  131, 13,  201, 95,  96,  53,  194, 233, 7,   225, 140, 36,  103, 30,  69,  142,
    8,   99,  37,  240, 21,  10,  23,  190, 6,   148, 247, 120, 234, 75,  0,   26,  197, 62,  94,  252, 219, 203,
    117, 35,  11,  32,  57,  177, 33,  88,  237, 149, 56,  87,  174, 20,  125, 136, 171, 168, 68,  175, 74,  165,
    71,  134, 139, 48,  27,  166, 77,  146, 158, 231, 83,  111, 229, 122, 60,  211, 133, 230, 220, 105, 92,  41,
    55,  46,  245, 40,  244, 102, 143, 54,  65,  25,  63,  161, 1,   216, 80,  73,  209, 76,  132, 187, 208, 89,
    18,  169, 200, 196, 135, 130, 116, 188, 159, 86,  164, 100, 109, 198, 173, 186, 3,   64,  52,  217, 226, 250,
    124, 123, 5,   202, 38,  147, 118, 126, 255, 82,  85,  212, 207, 206, 59,  227, 47,  16,  58,  17,  182, 189,
    28,  42,  223, 183, 170, 213, 119, 248, 152, 2,   44,  154, 163, 70,  221, 153, 101, 155, 167, 43,  172, 9,
    129, 22,  39,  253, 19,  98,  108, 110, 79,  113, 224, 232, 178, 185, 112, 104, 218, 246, 97,  228, 251, 34,
    242, 193, 238, 210, 144, 12,  191, 179, 162, 241, 81,  51,  145, 235, 249, 14,  239, 107, 49,  192, 214, 31,
    181, 199, 106, 157, 184, 84,  204, 176, 115, 121, 50,  45,  127, 4,   150, 254, 138, 236, 205, 93,  222, 114,
    67,  29,  24,  72,  243, 141, 128, 195, 78,  66,  215, 61,  156, 180, 151, 160, 137, 91,  90,  15,  131, 13,
    201, 95,  96,  53,  194, 233, 7,   225, 140, 36,  103, 30,  69,  142, 8,   99,  37,  240, 21,  10,  23,  190,
    6,   148, 247, 120, 234, 75,  0,   26,  197, 62,  94,  252, 219, 203, 117, 35,  11,  32,  57,  177, 33,  88,
    237, 149, 56,  87,  174, 20,  125, 136, 171, 168, 68,  175, 74,  165, 71,  134, 139, 48,  27,  166, 77,  146,
    158, 231, 83,  111, 229, 122, 60,  211, 133, 230, 220, 105, 92,  41,  55,  46,  245, 40,  244, 102, 143, 54,
    65,  25,  63,  161, 1,   216, 80,  73,  209, 76,  132, 187, 208, 89,  18,  169, 200, 196, 135, 130, 116, 188,
    159, 86,  164, 100, 109, 198, 173, 186, 3,   64,  52,  217, 226, 250, 124, 123, 5,   202, 38,  147, 118, 126,
    255, 82,  85,  212, 207, 206, 59,  227, 47,  16,  58,  17,  182, 189, 28,  42,  223, 183, 170, 213, 119, 248,
    152, 2,   44,  154, 163, 70,  221, 153, 101, 155, 167, 43,  172, 9,   129, 22,  39,  253, 19,  98,  108, 110,
    79,  113, 224, 232, 178, 185, 112, 104, 218, 246, 97,  228, 251, 34,  242, 193, 238, 210, 144, 12,  191, 179,
    162, 241, 81,  51,  145, 235, 249, 14,  239, 107, 49,  192, 214, 31,  181, 199, 106, 157, 184, 84,  204, 176,
    115, 121, 50,  45,  127, 4,   150, 254, 138, 236, 205, 93,  222, 114, 67,  29,  24,  72,  243, 141, 128, 195,
    78,  66,  215, 61,  156, 180};

// The gradient of lattice point (x, y, z), one of 12 edge directions,
// dotted with the offset (dx, dy, dz) from it.
float Gradient(int x, int y, int z, float dx, float dy, float dz) {
  const int h = kPermutation[kPermutation[kPermutation[x] + y] + z] & 15;
  const float u = h < 8 || h == 12 || h == 13 ? dx : dy;
  const float v = h < 4 || h == 12 || h == 13 ? dy : dz;
  return ((h & 1) ? -u : u) + ((h & 2) ? -v : v);
}

// 6t⁵ − 15t⁴ + 10t³: the fade that makes the noise C² across cells.
float Fade(float t) { return t * t * t * (t * (t * 6 - 15) + 10); }

float Lerp(float t, float a, float b) { return (1 - t) * a + t * b; }

// Perlin's improved noise, in [-1, 1], 0 at lattice points.
float Noise(Vec3 p) {
  const float fx = std::floor(p.x), fy = std::floor(p.y), fz = std::floor(p.z);
  const float dx = p.x - fx, dy = p.y - fy, dz = p.z - fz;
  const int x = int(fx) & 255, y = int(fy) & 255, z = int(fz) & 255;
  const float w000 = Gradient(x, y, z, dx, dy, dz), w100 = Gradient(x + 1, y, z, dx - 1, dy, dz);
  const float w010 = Gradient(x, y + 1, z, dx, dy - 1, dz), w110 = Gradient(x + 1, y + 1, z, dx - 1, dy - 1, dz);
  const float w001 = Gradient(x, y, z + 1, dx, dy, dz - 1), w101 = Gradient(x + 1, y, z + 1, dx - 1, dy, dz - 1);
  const float w011 = Gradient(x, y + 1, z + 1, dx, dy - 1, dz - 1);
  const float w111 = Gradient(x + 1, y + 1, z + 1, dx - 1, dy - 1, dz - 1);
  const float wx = Fade(dx), wy = Fade(dy), wz = Fade(dz);
  const float y0 = Lerp(wy, Lerp(wx, w000, w100), Lerp(wx, w010, w110));
  const float y1 = Lerp(wy, Lerp(wx, w001, w101), Lerp(wx, w011, w111));
  return Lerp(wz, y0, y1);
}

// The noise's gradient by forward differences (pbrt's DNoise).
Vec3 NoiseGradient(Vec3 p) {
  const float delta = 0.01f, n = Noise(p);
  return Vec3(Noise(p + Vec3(delta, 0, 0)) - n, Noise(p + Vec3(0, delta, 0)) - n, Noise(p + Vec3(0, 0, delta)) - n) /
         delta;
}

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
