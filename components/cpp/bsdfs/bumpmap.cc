// bumpmap — another material, on a surface displaced by a height texture
//
// The surface p + h(u,v)·n moves along its shading normal by the texture's
// height h (an RGB texture's luminance), scaled; the nested model scatters
// in the frame of the displaced surface's normal (Blinn 1978), as
// Mitsuba's `bumpmap` and pbrt-v4's `displacement` define it:
//   ∂p'/∂u = ∂p/∂u + n·(scale·∂h/∂u − n·∂p/∂u), likewise for v,
//   n' = normalize(∂p'/∂u × ∂p'/∂v) on the shading normal's side,
// x along ∂p/∂u made perpendicular to n'. The height's derivatives are
// central differences of the texture (looked up with the point's footprint,
// so they are those of the filtered texture) over 10⁻⁴ of uv. The term
// h·∂n/∂u of a curved surface is left out, as Mitsuba does. Directions and
// sidedness as for normal maps (PerturbedFrameModel), without the
// terminator softening, as Mitsuba's bumpmap.
//
// Parameters: BumpMap::Parameters() below. The height texture is a float
// one, or RGB read as its luminance, in units of the scene's length per
// unit uv.
//
// Lobes: the nested model's. Points whose ∂p/∂u, ∂p/∂v the caller does
// not give are left unbumped.
#include <cmath>
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

class BumpMap final : public yarf::PerturbedFrameModel {
 public:
  static yarf::ParameterSchema Parameters() {
    using P = yarf::Parameter;
    return {
        P::Material("bsdf").Required().Doc("the model on the bumped surface, a material defined before"),
        P::FloatTexture("bumpmap").Required().Doc("a texture of the scene: the height at each uv"),
        P::Float("scale").Default(1.0).Doc("the factor applied to the height's gradient"),
    };
  }

  explicit BumpMap(const yarf::Properties& props)
      : PerturbedFrameModel(props.SurfaceModelOf("bsdf"), /*soften_terminator=*/false),
        height_(HeightOf(props)),
        scale_(float(props.Float("scale", 1.0))) {
    if (!std::isfinite(scale_)) throw yarf::Error("property 'scale' must be finite");
  }

 private:
  static yarf::TexturedValue HeightOf(const yarf::Properties& props) {
    auto texture = props.TextureOf("bumpmap");
    if (!texture) throw yarf::Error("property 'bumpmap' must name a texture of the scene");
    return yarf::TexturedValue(std::move(texture));
  }

  // The step of a central difference at parameter value x: 10⁻⁴, grown
  // with |x| so that x ± step stays apart in float.
  static float Step(float x) { return 1e-4f * std::max(1.0f, std::abs(x)); }

  std::vector<Frame> Frames(std::span<const float>, const yarf::SurfacePoints& at, size_t n) const override {
    std::vector<Frame> frames(n, Frame(Vec3(0, 0, 1)));
    if (at.dpdu.size() < 3 * n || at.dpdv.size() < 3 * n) return frames;
    // The height at uv ± (step, 0) and uv ± (0, step): four lookups of n.
    std::vector<float> shifted[4];
    std::vector<float> steps(2 * n);
    for (auto& uv : shifted) uv.assign(at.uv.begin(), at.uv.begin() + 2 * n);
    for (size_t k = 0; k < n; ++k)
      for (int c = 0; c < 2; ++c) {
        const float step = Step(at.uv[2 * k + c]);
        steps[2 * k + c] = step;
        shifted[2 * c][2 * k + c] += step;
        shifted[2 * c + 1][2 * k + c] -= step;
      }
    yarf::PointValues<float> heights[4] = {Height(at, shifted[0]), Height(at, shifted[1]),
                                            Height(at, shifted[2]), Height(at, shifted[3])};
    for (size_t k = 0; k < n; ++k) {
      const float gu = scale_ * (heights[0][k] - heights[1][k]) / (2 * steps[2 * k]);
      const float gv = scale_ * (heights[2][k] - heights[3][k]) / (2 * steps[2 * k + 1]);
      if (!std::isfinite(gu) || !std::isfinite(gv)) continue;
      const Vec3 dpdu = Vec3::Load(&at.dpdu[3 * k]), dpdv = Vec3::Load(&at.dpdv[3 * k]);
      const Vec3 bumped_u(dpdu.x, dpdu.y, gu), bumped_v(dpdv.x, dpdv.y, gv);
      Vec3 m = yarf::Cross(bumped_u, bumped_v);
      const float length = yarf::Length(m);
      if (!(length > 0) || !std::isfinite(length)) continue;
      m = m / length;
      if (m.z < 0) m = -m;
      frames[k] = FrameOf(m, dpdu);
    }
    return frames;
  }

  yarf::PointValues<float> Height(const yarf::SurfacePoints& at, const std::vector<float>& uv) const {
    yarf::SurfacePoints shifted = at;
    shifted.uv = uv;
    return height_.FloatsAt(shifted);
  }

  yarf::TexturedValue height_;
  float scale_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<BumpMap>(registrar, "bumpmap", "1.0.0", "another material on a surface bumped by a height texture");
}
