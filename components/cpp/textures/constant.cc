// constant_texture — the same value everywhere (pbrt-v4's `constant`
// texture; registered under a longer name because "constant" is the
// constant environment emitter's, as in Mitsuba)
//
// Parameters: Constant::Parameters() below.
//
// Channels: 3 (a float value is returned in all three). Mean: the value.
#include <cstdint>
#include <span>
#include <vector>

#include "texture_input.h"
#include "texture_rows.h"
#include "yarf/plugin.h"

namespace {

using yarf::Vec3;

class Constant final : public yarf::Texture {
 public:
  static yarf::ParameterSchema Parameters() {
    return {yarf::Parameter::RgbTexture("value").Default(1.0).Doc(
        "the value at every point (a texture given here is passed through)")};
  }

  explicit Constant(const yarf::Properties& props)
      : value_(yarf::textures::TextureInput::Color(props, "value", Vec3(1, 1, 1))) {}

  uint32_t Channels() const override { return 3; }

  void Evaluate(const yarf::SurfacePoints& at, std::span<float> value) const override {
    yarf::textures::CheckShapes(at, value, 3);
    std::vector<Vec3> rows;
    value_.Evaluate(at, rows);
    for (size_t k = 0; k < rows.size(); ++k) rows[k].Store(&value[3 * k]);
  }

  bool ReadsFootprints() const override { return value_.ReadsFootprints(); }
  bool ReadsPositions() const override { return value_.ReadsPositions(); }

  std::vector<float> Mean() const override {
    const Vec3 mean = value_.Mean();
    return {mean.x, mean.y, mean.z};
  }

 private:
  yarf::textures::TextureInput value_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Constant>(registrar, "constant_texture", "1.0.0", "A constant value (pbrt-v4 constant)");
}
