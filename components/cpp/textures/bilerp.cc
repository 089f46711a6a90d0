// bilerp — pbrt-v4's bilinear blend of four values over uv
//
// At the mapped uv (s, t) = (u·uscale + udelta, v·vscale + vdelta) the
// value is (1−s)(1−t)·v00 + s(1−t)·v10 + (1−s)t·v01 + st·v11, as pbrt-v4's
// bilerp: exactly v00 at (0, 0), v10 at (1, 0), and so on, carried on
// linearly beyond the unit square (pbrt does not clamp either).
//
// Parameters: Bilerp::Parameters() below. Channels: 3 (a float texture's
// values in all three). Mean: the value at (s, t) of the unit square's
// centre, exact for a bilinear function.
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "texture_rows.h"
#include "uv_map.h"
#include "yarf/plugin.h"

namespace {

using yarf::Vec3;

class Bilerp final : public yarf::Texture {
 public:
  static yarf::ParameterSchema Parameters() {
    using P = yarf::Parameter;
    yarf::ParameterSchema schema = {
        P::Rgb("v00").Default(0.0).Doc("the value at (s, t) = (0, 0)"),
        P::Rgb("v10").Default(0.0).Doc("the value at (1, 0)"),
        P::Rgb("v01").Default(1.0).Doc("the value at (0, 1)"),
        P::Rgb("v11").Default(1.0).Doc("the value at (1, 1)"),
    };
    const yarf::ParameterSchema map = yarf::textures::UvMapParameters();
    schema.insert(schema.end(), map.begin(), map.end());
    return schema;
  }

  explicit Bilerp(const yarf::Properties& props)
      : corners_{Corner(props, "v00", 0), Corner(props, "v10", 0), Corner(props, "v01", 1), Corner(props, "v11", 1)},
        map_(yarf::textures::ReadUvMap(props)) {}

  uint32_t Channels() const override { return 3; }

  void Evaluate(const yarf::SurfacePoints& at, std::span<float> value) const override {
    yarf::textures::CheckShapes(at, value, 3);
    for (size_t k = 0; k < at.Count(); ++k) {
      const double u = at.uv[2 * k], v = at.uv[2 * k + 1];
      At(float(map_.U(u, v)), float(map_.V(u, v))).Store(&value[3 * k]);
    }
  }

  std::vector<float> Mean() const override {
    const Vec3 mean = At(float(map_.U(0.5, 0.5)), float(map_.V(0.5, 0.5)));
    return {mean.x, mean.y, mean.z};
  }

  bool ReadsFootprints() const override { return false; }

 private:
  static Vec3 Corner(const yarf::Properties& props, const std::string& key, float fallback) {
    const Vec3 c = props.Color(key, Vec3(fallback, fallback, fallback));
    if (!std::isfinite(c.x) || !std::isfinite(c.y) || !std::isfinite(c.z))
      throw yarf::Error("property '" + key + "' must be finite");
    return c;
  }

  Vec3 At(float s, float t) const {
    return corners_[0] * ((1 - s) * (1 - t)) + corners_[1] * (s * (1 - t)) + corners_[2] * ((1 - s) * t) +
           corners_[3] * (s * t);
  }

  std::array<Vec3, 4> corners_;
  yarf::textures::UvMap map_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Bilerp>(registrar, "bilerp", "1.0.0", "a bilinear blend of four values over uv (pbrt-v4 bilerp)");
}
