// checkerboard3d — pbrt-v4's solid checkerboard (`dimension` 3)
//
// Unit cubes in the texture's own space, p = to_texture · (world
// position): tex1 where ⌊x⌋ + ⌊y⌋ + ⌊z⌋ is even, tex2 where it is odd, so
// that an object seems carved from a block of alternating cubes. Point
// lookups (pbrt-v4 filters the solid checkerboard no more). Points whose
// position is not known (a point on a light, seen by its uv) are taken at
// the world's origin.
//
// Parameters: Checkerboard3d::Parameters() below. Channels: 3. Mean: the
// two colours' means alike (half of space is each).
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "texture_input.h"
#include "texture_rows.h"
#include "texture_space.h"
#include "yarf/plugin.h"

namespace {

using yarf::Vec3;
using yarf::textures::TextureInput;

class Checkerboard3d final : public yarf::Texture {
 public:
  static yarf::ParameterSchema Parameters() {
    using P = yarf::Parameter;
    return {
        P::RgbTexture("tex1").Default(1.0).Doc("the colour of even cubes"),
        P::RgbTexture("tex2").Default(0.0).Doc("the colour of odd cubes"),
        yarf::textures::TextureSpace::ToTextureParameter(),
    };
  }

  explicit Checkerboard3d(const yarf::Properties& props)
      : even_(TextureInput::Color(props, "tex1", Vec3(1, 1, 1))),
        odd_(TextureInput::Color(props, "tex2", Vec3(0, 0, 0))),
        space_(props) {}

  uint32_t Channels() const override { return 3; }

  void Evaluate(const yarf::SurfacePoints& at, std::span<float> value) const override {
    yarf::textures::Blend(at, value, even_, odd_, [&](size_t k) {
      const Vec3 p = space_.At(at, k);
      // Summed in double, three floors of floats stay exact integers,
      // whose parity fmod reads (an int would overflow far out).
      const double cubes = std::floor(double(p.x)) + std::floor(double(p.y)) + std::floor(double(p.z));
      return std::fmod(cubes, 2.0) == 0 ? 0.0f : 1.0f;
    });
  }

  std::vector<float> Mean() const override {
    const Vec3 mean = (even_.Mean() + odd_.Mean()) * 0.5f;
    return {mean.x, mean.y, mean.z};
  }

  bool ReadsFootprints() const override { return even_.ReadsFootprints() || odd_.ReadsFootprints(); }
  bool ReadsPositions() const override { return true; }

 private:
  TextureInput even_, odd_;
  yarf::textures::TextureSpace space_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Checkerboard3d>(registrar, "checkerboard3d", "1.0.0",
                                 "alternating unit cubes in space (pbrt-v4 checkerboard, dimension 3)");
}
