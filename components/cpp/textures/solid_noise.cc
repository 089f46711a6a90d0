// fbm, wrinkled, windy, marble — pbrt-v4's solid noise textures
//
// Each is a function of the point's position in its own texture space,
// p = to_texture · (world position), built of Perlin noise
// (yarf/support/perlin_noise.h): a wood grain or a marble runs through an object, not
// over its uv.
//   fbm: FBm(p, roughness, octaves), fractional Brownian motion, about
//     [−1, 1] (a bump map's or a mix's amount, as pbrt's float fbm).
//   wrinkled: Turbulence(p, roughness, octaves), ≥ 0.
//   windy: |FBm(p/10, ½, 3)| · FBm(p, ½, 6), waves under gusts of wind.
//   marble: pbrt's marble colour: t = ½ + ½ sin(y + variation·FBm(p,
//     roughness, octaves)) of p = scale · to_texture · x, through a
//     Bézier spline of pbrt's nine greys and blue-greys, times 1.5.
// Points whose position is not known (a point on a light, seen by its
// uv) are taken at the world's origin.
//
// Parameters: SolidNoise::Parameters() below. Channels: 1 (marble: 3).
// Mean: estimated over a cube of 16³ lattice cells (marble: its spline's
// colours over a sine, the same way).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "texture_rows.h"
#include "texture_space.h"
#include "yarf/plugin.h"
#include "yarf/support/perlin_noise.h"

namespace {

using yarf::Vec3;
using yarf::FBm;
using yarf::Turbulence;

enum class Pattern { kFbm, kWrinkled, kWindy, kMarble };

// pbrt's marble spline: nine control points, evaluated four at a time.
constexpr std::array<Vec3, 9> kMarbleColours = {
    Vec3(0.58f, 0.58f, 0.6f), Vec3(0.58f, 0.58f, 0.6f), Vec3(0.58f, 0.58f, 0.6f),
    Vec3(0.5f, 0.5f, 0.5f),   Vec3(0.6f, 0.59f, 0.58f), Vec3(0.58f, 0.58f, 0.6f),
    Vec3(0.58f, 0.58f, 0.6f), Vec3(0.2f, 0.2f, 0.33f),  Vec3(0.58f, 0.58f, 0.6f)};

Vec3 Lerp(float t, Vec3 a, Vec3 b) { return a * (1 - t) + b * t; }

// The cubic Bézier segment of the spline t ∈ [0, 1] falls in, by de
// Casteljau's construction, times pbrt's 1.5.
Vec3 MarbleColour(float t) {
  constexpr int kSegments = int(kMarbleColours.size()) - 3;
  t = t > 0 ? std::min(t, 1.0f) : 0.0f;  // a NaN (a point far out) too
  const int first = std::clamp(int(std::floor(t * kSegments)), 0, kSegments - 1);
  t = t * kSegments - float(first);
  const Vec3* c = &kMarbleColours[size_t(first)];
  const Vec3 s0 = Lerp(t, c[0], c[1]), s1 = Lerp(t, c[1], c[2]), s2 = Lerp(t, c[2], c[3]);
  return Lerp(t, Lerp(t, s0, s1), Lerp(t, s1, s2)) * 1.5f;
}

template <Pattern kPattern>
class SolidNoise final : public yarf::Texture {
 public:
  static yarf::ParameterSchema Parameters() {
    using P = yarf::Parameter;
    yarf::ParameterSchema schema = {yarf::textures::TextureSpace::ToTextureParameter()};
    if (kPattern == Pattern::kWindy) return schema;
    schema.push_back(P::Int("octaves").Default(8).Min(1).Max(64).Doc("octaves of noise summed"));
    schema.push_back(P::Float("roughness").Default(0.5).Min(0).Max(1).Doc(
        "each octave's weight over the one before (pbrt's omega)"));
    if (kPattern == Pattern::kMarble) {
      schema.push_back(P::Float("scale").Default(1).Doc("multiplies the texture-space point"));
      schema.push_back(P::Float("variation").Default(0.2).Doc("how far the noise bends the veins"));
    }
    return schema;
  }

  explicit SolidNoise(const yarf::Properties& props)
      : space_(props),
        octaves_(kPattern == Pattern::kWindy ? 0 : int(props.Int("octaves", 8, 1, 64))),
        omega_(Finite(props, "roughness", 0.5)),
        scale_(Finite(props, "scale", 1)),
        variation_(Finite(props, "variation", 0.2)) {
    if (kPattern != Pattern::kWindy && !(omega_ >= 0 && omega_ <= 1))
      throw yarf::Error("property 'roughness' must lie in [0, 1]");
  }

  uint32_t Channels() const override { return kPattern == Pattern::kMarble ? 3 : 1; }

  void Evaluate(const yarf::SurfacePoints& at, std::span<float> value) const override {
    yarf::textures::CheckShapes(at, value, Channels());
    for (size_t k = 0; k < at.Count(); ++k) {
      const Vec3 p = space_.At(at, k);
      if constexpr (kPattern == Pattern::kMarble) {
        MarbleAt(p).Store(&value[3 * k]);
      } else {
        value[k] = At(p);
      }
    }
  }

  std::vector<float> Mean() const override {
    // A lattice of 16³ cells, 2 points a cell along each axis, offset
    // from the lattice (where noise is 0).
    constexpr int kSide = 32;
    Vec3 sum(0, 0, 0);
    for (int i = 0; i < kSide; ++i)
      for (int j = 0; j < kSide; ++j)
        for (int l = 0; l < kSide; ++l) {
          const Vec3 p((i + 0.37f) / 2, (j + 0.61f) / 2, (l + 0.23f) / 2);
          if constexpr (kPattern == Pattern::kMarble) {
            sum += MarbleAt(p);
          } else {
            sum += Vec3(At(p), 0, 0);
          }
        }
    const Vec3 mean = sum * (1.0f / float(kSide * kSide * kSide));
    if constexpr (kPattern == Pattern::kMarble) return {mean.x, mean.y, mean.z};
    return {mean.x};
  }

  bool ReadsFootprints() const override { return false; }
  bool ReadsPositions() const override { return true; }

 private:
  static float Finite(const yarf::Properties& props, const std::string& key, double fallback) {
    const double x = props.Float(key, fallback);
    if (!std::isfinite(x) || std::abs(x) > 1e30) throw yarf::Error("property '" + key + "' must be finite");
    return float(x);
  }

  // The float patterns at texture-space point p.
  float At(Vec3 p) const {
    switch (kPattern) {
      case Pattern::kFbm:
        return FBm(p, omega_, octaves_);
      case Pattern::kWrinkled:
        return Turbulence(p, omega_, octaves_);
      default:
        return std::abs(FBm(p * 0.1f, 0.5f, 3)) * FBm(p, 0.5f, 6);
    }
  }

  Vec3 MarbleAt(Vec3 p) const {
    p = p * scale_;
    const float marble = p.y + variation_ * FBm(p, omega_, octaves_);
    return MarbleColour(0.5f + 0.5f * std::sin(marble));
  }

  yarf::textures::TextureSpace space_;
  int octaves_;
  float omega_, scale_, variation_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<SolidNoise<Pattern::kFbm>>(registrar, "fbm", "1.0.0",
                                            "fractional Brownian motion of Perlin noise in space (pbrt fbm)");
  yarf::Register<SolidNoise<Pattern::kWrinkled>>(registrar, "wrinkled", "1.0.0",
                                                 "turbulence, the sum of |Perlin noise| octaves (pbrt wrinkled)");
  yarf::Register<SolidNoise<Pattern::kWindy>>(registrar, "windy", "1.0.0",
                                              "waves of noise under gusts of noise (pbrt windy)");
  yarf::Register<SolidNoise<Pattern::kMarble>>(registrar, "marble", "1.0.0",
                                               "veined marble colour of noise in space (pbrt marble)");
}
