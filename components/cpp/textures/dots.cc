// dots — pbrt-v4's polka dots: randomly placed dots over the uv plane
//
// The mapped uv (s, t) = (u·uscale + udelta, v·vscale + vdelta) is cut
// into cells of side 1 centred on the integer points; a cell holds a dot
// where Perlin noise at its centre (+½, +½) is positive, of radius 0.35,
// its centre moved from the cell's by up to 0.15 along each axis by two
// more noise values, all as pbrt-v4 places them (the same noise,
// yarf/support/perlin_noise.h, so the same dots). `inside` within a dot,
// `outside` elsewhere; each may itself be a texture. Point lookups (no
// filtering over a footprint, as pbrt's dots).
//
// Parameters: Dots::Parameters() below. Channels: 3. Mean: the blend of
// the two means by the share of the unit square of uv in dots (a 512²
// grid).
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "texture_input.h"
#include "texture_rows.h"
#include "uv_map.h"
#include "yarf/plugin.h"
#include "yarf/support/perlin_noise.h"

namespace {

using yarf::Vec3;
using yarf::textures::TextureInput;

// Whether (s, t) lies in a dot.
bool InDot(double s, double t) {
  const float cell_s = std::floor(float(s) + 0.5f), cell_t = std::floor(float(t) + 0.5f);
  if (!(yarf::Noise(Vec3(cell_s + 0.5f, cell_t + 0.5f, 0.5f)) > 0)) return false;
  constexpr float kRadius = 0.35f, kMaxShift = 0.5f - kRadius;
  const float centre_s = cell_s + kMaxShift * yarf::Noise(Vec3(cell_s + 1.5f, cell_t + 2.8f, 0.5f));
  const float centre_t = cell_t + kMaxShift * yarf::Noise(Vec3(cell_s + 4.5f, cell_t + 9.8f, 0.5f));
  const float ds = float(s) - centre_s, dt = float(t) - centre_t;
  return ds * ds + dt * dt < kRadius * kRadius;
}

class Dots final : public yarf::Texture {
 public:
  static yarf::ParameterSchema Parameters() {
    using P = yarf::Parameter;
    yarf::ParameterSchema schema = {
        P::RgbTexture("inside").Default(1.0).Doc("the value within the dots"),
        P::RgbTexture("outside").Default(0.0).Doc("the value between them"),
    };
    const yarf::ParameterSchema map = yarf::textures::UvMapParameters();
    schema.insert(schema.end(), map.begin(), map.end());
    return schema;
  }

  explicit Dots(const yarf::Properties& props)
      : inside_(TextureInput::Color(props, "inside", Vec3(1, 1, 1))),
        outside_(TextureInput::Color(props, "outside", Vec3(0, 0, 0))),
        map_(yarf::textures::ReadUvMap(props)) {}

  uint32_t Channels() const override { return 3; }

  void Evaluate(const yarf::SurfacePoints& at, std::span<float> value) const override {
    yarf::textures::Blend(at, value, outside_, inside_, [&](size_t k) {
      const double u = at.uv[2 * k], v = at.uv[2 * k + 1];
      return InDot(map_.U(u, v), map_.V(u, v)) ? 1.0f : 0.0f;
    });
  }

  std::vector<float> Mean() const override {
    constexpr int kGrid = 512;
    int64_t in = 0;
    for (int i = 0; i < kGrid; ++i)
      for (int j = 0; j < kGrid; ++j) {
        const double u = (i + 0.5) / kGrid, v = (j + 0.5) / kGrid;
        in += InDot(map_.U(u, v), map_.V(u, v));
      }
    const float f = float(double(in) / (double(kGrid) * kGrid));
    const Vec3 mean = inside_.Mean() * f + outside_.Mean() * (1 - f);
    return {mean.x, mean.y, mean.z};
  }

  bool ReadsFootprints() const override { return inside_.ReadsFootprints() || outside_.ReadsFootprints(); }
  bool ReadsPositions() const override { return inside_.ReadsPositions() || outside_.ReadsPositions(); }

 private:
  TextureInput inside_, outside_;
  yarf::textures::UvMap map_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Dots>(registrar, "dots", "1.0.0", "randomly placed polka dots over uv (pbrt-v4 dots)");
}
