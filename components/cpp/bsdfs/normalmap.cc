// normalmap — another material, seen through a normal map
//
// The nested model scatters in a frame whose normal the map gives at each
// point: n' = normalize(2·rgb − 1) in the shading frame (x along ∂p/∂u,
// z the shading normal), tangent-space maps as Mitsuba's and pbrt-v4's
// `normalmap` read them. As Mitsuba's normalmap: a mapped normal that
// faces away from wi is mirrored about the shading normal (its x and y
// negated); directions go to the nested model in the perturbed frame,
// whose cosine replaces the shading one (f·|cos θo| is f'·|cos θ'o|); a
// wo on the other side of the perturbed surface than of the shading one
// scatters nothing, so no light leaks through; and Conty Estevez et
// al.'s shadowing function (Ray Tracing Gems, 2019) of the tilt softens
// the shadow terminator the tilted normals would make.
//
// Parameters
//   bsdf        material (a name of the scene's materials, defined before)
//       The model seen through the map.
//   normalmap   texture (rgb, stored linearly: a bitmap with raw = true)
//       The tangent-space normal at each uv; (0.5, 0.5, 1) leaves the
//       model as it is.
//
// Lobes: the nested model's.
#include <algorithm>
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
    const std::vector<Frame> frames = Frames(wi, uv, n);
    const std::vector<float> local_wi = InFrames(frames, wi), local_wo = InFrames(frames, wo);
    nested_->Evaluate(mode, local_wi, local_wo, uv, value);
    for (size_t k = 0; k < n; ++k) {
      const float cos = wo[3 * k + 2], perturbed = local_wo[3 * k + 2];
      const float scale = Agree(cos, perturbed) && cos != 0
                              ? std::abs(perturbed / cos) * Shadowing(frames[k].n, cos)
                              : 0.0f;
      for (int c = 0; c < 3; ++c) value[3 * k + c] *= scale;
    }
  }

  void Sample(yarf::TransportMode mode, std::span<const float> wi, std::span<const float> uv,
              std::span<const float> uniform, uint32_t allowed, std::span<float> wo, std::span<float> weight,
              std::span<float> pdf, std::span<uint32_t> flags) const override {
    const size_t n = wi.size() / 3;
    const std::vector<Frame> frames = Frames(wi, uv, n);
    const std::vector<float> local_wi = InFrames(frames, wi);
    std::vector<float> local_wo(3 * n);
    nested_->Sample(mode, local_wi, uv, uniform, allowed, local_wo, weight, pdf, flags);
    for (size_t k = 0; k < n; ++k) {
      const Vec3 out = frames[k].ToWorld(Vec3::Load(&local_wo[3 * k]));
      out.Store(&wo[3 * k]);
      const float shadowing = Shadowing(frames[k].n, out.z);
      for (int c = 0; c < 3; ++c) weight[3 * k + c] *= shadowing;
      if (!Agree(out.z, local_wo[3 * k + 2])) {
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
    const std::vector<Frame> frames = Frames(wi, uv, n);
    const std::vector<float> local_wi = InFrames(frames, wi), local_wo = InFrames(frames, wo);
    nested_->Pdf(local_wi, local_wo, uv, pdf);
    for (size_t k = 0; k < n; ++k)
      if (!Agree(wo[3 * k + 2], local_wo[3 * k + 2])) pdf[k] = 0;
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
  // the mapped normal (mirrored to face wi), x the shading frame's x made
  // perpendicular to it.
  std::vector<Frame> Frames(std::span<const float> wi, std::span<const float> uv, size_t n) const {
    const yarf::PointValues<Vec3> rgb = normals_.At(uv.first(2 * n));
    std::vector<Frame> frames(n, Frame(Vec3(0, 0, 1)));
    for (size_t k = 0; k < n; ++k) {
      Vec3 m = rgb[k] * 2.0f - Vec3(1, 1, 1);
      const float length = yarf::Length(m);
      if (!(length > 1e-6f)) continue;  // a map texel of no length leaves the frame be
      const Vec3 in = Vec3::Load(&wi[3 * k]);
      if (in.z * yarf::Dot(in, m) <= 0) m = Vec3(-m.x, -m.y, m.z);
      Frame& f = frames[k];
      f.n = m / length;
      f.s = yarf::Normalize(Vec3(1, 0, 0) - f.n * f.n.x);
      f.t = yarf::Cross(f.n, f.s);
    }
    return frames;
  }

  // Directions [N,3] of the shading frames in each point's perturbed one.
  static std::vector<float> InFrames(const std::vector<Frame>& frames, std::span<const float> w) {
    std::vector<float> local(3 * frames.size());
    for (size_t k = 0; k < frames.size(); ++k) frames[k].ToLocal(Vec3::Load(&w[3 * k])).Store(&local[3 * k]);
    return local;
  }

  // Whether wo lies on the same side of the perturbed surface as of the
  // shading one (its z in each frame).
  static bool Agree(float wo_z, float wo_perturbed_z) { return wo_z * wo_perturbed_z > 0; }

  // Conty Estevez et al.'s shadowing of a normal tilted to `n` (shading
  // frame) toward a direction of cosine `cos_o`: 1 for an untilted one.
  static float Shadowing(Vec3 n, float cos_o) {
    const float cos_d = std::min(std::abs(n.z), 1.0f);
    if (!(cos_d > 0)) return 0;
    const float alpha2 = std::clamp(0.125f * (1 - cos_d * cos_d) / (cos_d * cos_d), 0.0f, 1.0f);
    const float cos2_o = std::max(cos_o * cos_o, 1e-12f);
    return 2 / (1 + std::sqrt(1 + alpha2 * (1 - cos2_o) / cos2_o));
  }

  std::shared_ptr<const yarf::SurfaceModel> nested_;
  yarf::TexturedValue normals_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<NormalMap>(registrar, "normalmap", "1.0.0",
                            "another material seen through a tangent-space normal map");
}
