// normalmap — another material, seen through a normal map
//
// The nested model scatters in a frame whose normal the map gives at each
// point: n' = normalize(2·rgb − 1) in the shading frame (x along ∂p/∂u,
// z the shading normal), tangent-space maps as Mitsuba's and pbrt-v4's
// `normalmap` read them. As Mitsuba's normalmap: a mapped normal that
// faces away from wi is mirrored about the shading normal (its x and y
// negated), and the shadow terminator is softened (PerturbedFrameModel).
//
// Parameters: NormalMap::Parameters() below. The map is an RGB texture
// stored linearly (a bitmap with raw = true); (0.5, 0.5, 1) leaves the
// model as it is.
//
// Lobes: the nested model's.
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "perturbed_frame.h"
#include "yarf/plugin.h"
#include "yarf/texture.h"

namespace {

using yarf::Frame;
using yarf::Vec3;

class NormalMap final : public yarf::PerturbedFrameModel {
 public:
  static yarf::ParameterSchema Parameters() {
    using P = yarf::Parameter;
    return {
        P::Material("bsdf").Required().Doc("the model seen through the map, a material defined before"),
        P::RgbTexture("normalmap").Required().Doc("a texture of the scene: the tangent-space normal at each uv"),
    };
  }

  explicit NormalMap(const yarf::Properties& props)
      : PerturbedFrameModel(props.SurfaceModelOf("bsdf"), /*soften_terminator=*/true),
        normals_(NormalsOf(props)) {}

 private:
  static yarf::TexturedValue NormalsOf(const yarf::Properties& props) {
    auto texture = props.TextureOf("normalmap");
    if (!texture) throw yarf::Error("property 'normalmap' must name a texture of the scene");
    if (texture->Channels() != 3) throw yarf::Error("property 'normalmap': the texture must be RGB");
    return yarf::TexturedValue(std::move(texture));
  }

  // z the mapped normal (mirrored to face wi), x the shading frame's x
  // made perpendicular to it.
  std::vector<Frame> Frames(std::span<const float> wi, const yarf::SurfacePoints& at, size_t n) const override {
    const yarf::PointValues<Vec3> rgb = normals_.At(at);
    std::vector<Frame> frames(n, Frame(Vec3(0, 0, 1)));
    for (size_t k = 0; k < n; ++k) {
      Vec3 m = rgb[k] * 2.0f - Vec3(1, 1, 1);
      const float length = yarf::Length(m);
      if (!(length > 1e-6f)) continue;  // a map texel of no length leaves the frame be
      const Vec3 in = Vec3::Load(&wi[3 * k]);
      if (in.z * yarf::Dot(in, m) <= 0) m = Vec3(-m.x, -m.y, m.z);
      frames[k] = FrameOf(m / length, Vec3(1, 0, 0));
    }
    return frames;
  }

  yarf::TexturedValue normals_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<NormalMap>(registrar, "normalmap", "1.0.0",
                            "another material seen through a tangent-space normal map");
}
