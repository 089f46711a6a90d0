// scale — a texture times a factor (pbrt-v4's `scale`)
//
// Parameters: Scale::Parameters() below. A colour texture given as the
// scale is read as its luminance, as pbrt's float texture parameter.
//
// Channels: 3 (a float `tex` gives its value in all three).
// Value: tex · scale at each point. Mean: mean(tex) · mean(scale), exact
// when at most one of the two varies over the surface.
#include <cstdint>
#include <span>
#include <vector>

#include "texture_input.h"
#include "texture_rows.h"
#include "yarf/plugin.h"

namespace {

using yarf::Vec3;
using yarf::textures::TextureInput;

class Scale final : public yarf::Texture {
 public:
  static yarf::ParameterSchema Parameters() {
    using P = yarf::Parameter;
    return {
        P::RgbTexture("tex").Default(1.0).Doc("the value scaled"),
        P::FloatTexture("scale").Default(1.0).Doc("the factor"),
    };
  }

  explicit Scale(const yarf::Properties& props)
      : tex_(TextureInput::Color(props, "tex", Vec3(1, 1, 1))), scale_(TextureInput::Float(props, "scale", 1.0f)) {}

  uint32_t Channels() const override { return 3; }

  void Evaluate(const yarf::SurfacePoints& at, std::span<float> value) const override {
    yarf::textures::CheckShapes(at, value, 3);
    std::vector<Vec3> tex;
    std::vector<float> scale;
    tex_.Evaluate(at, tex);
    scale_.Evaluate(at, scale);
    for (size_t k = 0; k < tex.size(); ++k) (tex[k] * scale[k]).Store(&value[3 * k]);
  }

  bool ReadsFootprints() const override { return tex_.ReadsFootprints() || scale_.ReadsFootprints(); }
  bool ReadsPositions() const override { return tex_.ReadsPositions() || scale_.ReadsPositions(); }

  std::vector<float> Mean() const override {
    const Vec3 mean = tex_.Mean() * scale_.Mean().x;
    return {mean.x, mean.y, mean.z};
  }

 private:
  TextureInput tex_, scale_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Scale>(registrar, "scale", "1.0.0", "A texture times a factor (pbrt-v4 scale)");
}
