// normalmap — another material, seen through a normal map
//
// The nested model scatters in a frame whose normal the map gives at each
// point: n' = normalize(2·rgb − 1) in the shading frame (x along ∂p/∂u,
// z the shading normal), tangent-space maps as Mitsuba's and pbrt-v4's
// `normalmap` read them. Directions go to the nested model in that frame;
// its cosine is the perturbed one, so f·|cos θo| is f'·|cos θ'o| and
// a lobe's sampling weight is the nested model's own. A direction on the
// other side of the perturbed surface than of the shading one scatters
// nothing (as Mitsuba's normalmap), so no light leaks through.
//
// Parameters
//   bsdf        material (a name of the scene's materials, defined before)
//       The model seen through the map.
//   normalmap   texture (rgb, stored linearly: a bitmap with raw = true)
//       The tangent-space normal at each uv; (0.5, 0.5, 1) leaves the
//       model as it is.
//
// Lobes: the nested model's.
#include <cmath>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "yarf/plugin.h"
#include "yarf/texture.h"

namespace {

using yarf::Frame;
using yarf::Vec3;

class NormalMap final : public yarf::SurfaceModel {
 public:
  explicit NormalMap(const yarf::Properties& props)
      : nested_(props.SurfaceModelOf("bsdf")), normals_(NormalsOf(props)) {}

  void Evaluate(yarf::TransportMode mode, std::span<const float> wi, std::span<const float> wo,
                std::span<const float> uv, std::span<float> value) const override {
    const size_t n = wi.size() / 3;
    const std::vector<Frame> frames = Frames(uv, n);
    std::vector<float> local_wi(3 * n), local_wo(3 * n);
    for (size_t k = 0; k < n; ++k) {
      frames[k].ToLocal(Vec3::Load(&wi[3 * k])).Store(&local_wi[3 * k]);
      frames[k].ToLocal(Vec3::Load(&wo[3 * k])).Store(&local_wo[3 * k]);
    }
    nested_->Evaluate(mode, local_wi, local_wo, uv, value);
    for (size_t k = 0; k < n; ++k) {
      const float cos = wo[3 * k + 2], perturbed = local_wo[3 * k + 2];
      const float scale = Agree(wi[3 * k + 2], local_wi[3 * k + 2], cos, perturbed) && cos != 0
                              ? std::abs(perturbed / cos)
                              : 0.0f;
      for (int c = 0; c < 3; ++c) value[3 * k + c] *= scale;
    }
  }

  void Sample(yarf::TransportMode mode, std::span<const float> wi, std::span<const float> uv,
              std::span<const float> uniform, uint32_t allowed, std::span<float> wo, std::span<float> weight,
              std::span<float> pdf, std::span<uint32_t> flags) const override {
    const size_t n = wi.size() / 3;
    const std::vector<Frame> frames = Frames(uv, n);
    std::vector<float> local_wi(3 * n);
    for (size_t k = 0; k < n; ++k) frames[k].ToLocal(Vec3::Load(&wi[3 * k])).Store(&local_wi[3 * k]);
    std::vector<float> local_wo(3 * n);
    nested_->Sample(mode, local_wi, uv, uniform, allowed, local_wo, weight, pdf, flags);
    for (size_t k = 0; k < n; ++k) {
      const Vec3 out = frames[k].ToWorld(Vec3::Load(&local_wo[3 * k]));
      out.Store(&wo[3 * k]);
      if (!Agree(wi[3 * k + 2], local_wi[3 * k + 2], out.z, local_wo[3 * k + 2])) {
        Vec3().Store(&wo[3 * k]);
        Vec3().Store(&weight[3 * k]);
        pdf[k] = 0;
        flags[k] = yarf::kScatterNone;
      }
    }
  }

  void Pdf(std::span<const float> wi, std::span<const float> wo, std::span<const float> uv,
           std::span<float> pdf) const override {
    const size_t n = wi.size() / 3;
    const std::vector<Frame> frames = Frames(uv, n);
    std::vector<float> local_wi(3 * n), local_wo(3 * n);
    for (size_t k = 0; k < n; ++k) {
      frames[k].ToLocal(Vec3::Load(&wi[3 * k])).Store(&local_wi[3 * k]);
      frames[k].ToLocal(Vec3::Load(&wo[3 * k])).Store(&local_wo[3 * k]);
    }
    nested_->Pdf(local_wi, local_wo, uv, pdf);
    for (size_t k = 0; k < n; ++k)
      if (!Agree(wi[3 * k + 2], local_wi[3 * k + 2], wo[3 * k + 2], local_wo[3 * k + 2])) pdf[k] = 0;
  }

  uint32_t Lobes() const override { return nested_->Lobes(); }

 private:
  static yarf::TexturedValue NormalsOf(const yarf::Properties& props) {
    auto texture = props.TextureOf("normalmap");
    if (!texture) throw yarf::Error("property 'normalmap' must name a texture of the scene");
    if (texture->Channels() != 3) throw yarf::Error("property 'normalmap': the texture must be RGB");
    return yarf::TexturedValue(std::move(texture));
  }

  // Each point's perturbed frame, in the shading frame's coordinates: z
  // the mapped normal, x the shading frame's x made perpendicular to it.
  std::vector<Frame> Frames(std::span<const float> uv, size_t n) const {
    const yarf::PointValues<Vec3> rgb = normals_.At(uv.first(2 * n));
    std::vector<Frame> frames(n, Frame(Vec3(0, 0, 1)));
    for (size_t k = 0; k < n; ++k) {
      const Vec3 m = rgb[k] * 2.0f - Vec3(1, 1, 1);
      const float length = yarf::Length(m);
      // A map texel below the surface or of no length leaves the frame be.
      if (!(length > 1e-6f) || !(m.z > 0)) continue;
      Frame& f = frames[k];
      f.n = m / length;
      const Vec3 s = Vec3(1, 0, 0) - f.n * f.n.x;
      f.s = yarf::Normalize(s);
      f.t = yarf::Cross(f.n, f.s);
    }
    return frames;
  }

  // Whether wi and wo lie on the same sides of the perturbed surface as of
  // the shading one (their z in each frame).
  static bool Agree(float wi_z, float wi_perturbed_z, float wo_z, float wo_perturbed_z) {
    return (wi_z > 0) == (wi_perturbed_z > 0) && (wo_z > 0) == (wo_perturbed_z > 0);
  }

  std::shared_ptr<const yarf::SurfaceModel> nested_;
  yarf::TexturedValue normals_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<NormalMap>(registrar, "normalmap", "1.0.0",
                            "another material seen through a tangent-space normal map");
}
