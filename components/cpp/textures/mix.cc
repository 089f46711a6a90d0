// mix — a blend of two textures (pbrt-v4's `mix`)
//
// Parameters: Mix::Parameters() below. Any finite amount is accepted
// (pbrt does not bound it either); a colour texture there is read as its
// luminance.
//
// Channels: 3. Value: (1 − amount) · tex1 + amount · tex2 at each point.
// Mean: the same blend of the means, exact unless `amount` and one of
// tex1 / tex2 both vary over the surface.
#include <cstdint>
#include <span>
#include <vector>

#include "texture_input.h"
#include "texture_rows.h"
#include "yarf/plugin.h"

namespace {

using yarf::Vec3;
using yarf::textures::TextureInput;

class Mix final : public yarf::Texture {
 public:
  static yarf::ParameterSchema Parameters() {
    using P = yarf::Parameter;
    return {
        P::RgbTexture("tex1").Default(0.0).Doc("the value where amount is 0"),
        P::RgbTexture("tex2").Default(1.0).Doc("the value where amount is 1"),
        P::FloatTexture("amount").Default(0.5).Doc("the weight of tex2"),
    };
  }

  explicit Mix(const yarf::Properties& props)
      : tex1_(TextureInput::Color(props, "tex1", Vec3(0, 0, 0))),
        tex2_(TextureInput::Color(props, "tex2", Vec3(1, 1, 1))),
        amount_(TextureInput::Float(props, "amount", 0.5f)) {}

  uint32_t Channels() const override { return 3; }

  void Evaluate(const yarf::SurfacePoints& at, std::span<float> value) const override {
    std::vector<float> amount;
    amount_.Evaluate(at, amount);
    yarf::textures::Blend(at, value, tex1_, tex2_, [&](size_t k) { return amount[k]; });
  }

  bool ReadsPositions() const override {
    return tex1_.ReadsPositions() || tex2_.ReadsPositions() || amount_.ReadsPositions();
  }
  bool ReadsFootprints() const override {
    return tex1_.ReadsFootprints() || tex2_.ReadsFootprints() || amount_.ReadsFootprints();
  }

  std::vector<float> Mean() const override {
    const float a = amount_.Mean().x;
    const Vec3 mean = (1.0f - a) * tex1_.Mean() + a * tex2_.Mean();
    return {mean.x, mean.y, mean.z};
  }

 private:
  TextureInput tex1_, tex2_, amount_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Mix>(registrar, "mix", "1.0.0", "A blend of two textures by an amount (pbrt-v4 mix)");
}
