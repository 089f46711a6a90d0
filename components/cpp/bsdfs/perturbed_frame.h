// A material seen in another shading frame at each point: what normal maps
// and bump maps share. Directions go to the nested model in the perturbed
// frame, whose cosine replaces the shading one (f·|cos θo| is f'·|cos θ'o|),
// and a wo on the other side of the perturbed surface than of the shading
// one scatters nothing, so no light leaks through. Optionally, Conty
// Estevez et al.'s shadowing function (Ray Tracing Gems, 2019) of the tilt
// softens the shadow terminator the tilted normals would make.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include "yarf/surface.h"
#include "yarf/vecmath.h"

namespace yarf {

class PerturbedFrameModel : public SurfaceModel {
 public:
  PerturbedFrameModel(std::shared_ptr<const SurfaceModel> nested, bool soften_terminator)
      : nested_(std::move(nested)), soften_terminator_(soften_terminator) {}

  void Evaluate(TransportMode mode, std::span<const float> wi, std::span<const float> wo,
                const SurfacePoints& at, std::span<float> value) const final {
    const size_t n = wi.size() / 3;
    const std::vector<Frame> frames = Frames(wi, at, n);
    const std::vector<float> local_wi = InFrames(frames, wi), local_wo = InFrames(frames, wo);
    nested_->Evaluate(mode, local_wi, local_wo, at, value);
    for (size_t k = 0; k < n; ++k) {
      const float cos = wo[3 * k + 2], perturbed = local_wo[3 * k + 2];
      const float scale =
          Agree(cos, perturbed) && cos != 0 ? std::abs(perturbed / cos) * Shadowing(frames[k].n, cos) : 0.0f;
      for (int c = 0; c < 3; ++c) value[3 * k + c] *= scale;
    }
  }

  void Sample(TransportMode mode, std::span<const float> wi, const SurfacePoints& at,
              std::span<const float> uniform, uint32_t allowed, std::span<float> wo, std::span<float> weight,
              std::span<float> pdf, std::span<uint32_t> flags) const final {
    const size_t n = wi.size() / 3;
    const std::vector<Frame> frames = Frames(wi, at, n);
    const std::vector<float> local_wi = InFrames(frames, wi);
    std::vector<float> local_wo(3 * n);
    nested_->Sample(mode, local_wi, at, uniform, allowed, local_wo, weight, pdf, flags);
    for (size_t k = 0; k < n; ++k) {
      const Vec3 out = frames[k].ToWorld(Vec3::Load(&local_wo[3 * k]));
      out.Store(&wo[3 * k]);
      const float shadowing = Shadowing(frames[k].n, out.z);
      for (int c = 0; c < 3; ++c) weight[3 * k + c] *= shadowing;
      if (!Agree(out.z, local_wo[3 * k + 2])) {
        Vec3().Store(&wo[3 * k]);
        Vec3().Store(&weight[3 * k]);
        pdf[k] = 0;
        flags[k] = kScatterNone;
      }
    }
  }

  void Pdf(std::span<const float> wi, std::span<const float> wo, const SurfacePoints& at,
           std::span<float> pdf) const final {
    const size_t n = wi.size() / 3;
    const std::vector<Frame> frames = Frames(wi, at, n);
    const std::vector<float> local_wi = InFrames(frames, wi), local_wo = InFrames(frames, wo);
    nested_->Pdf(local_wi, local_wo, at, pdf);
    for (size_t k = 0; k < n; ++k)
      if (!Agree(wo[3 * k + 2], local_wo[3 * k + 2])) pdf[k] = 0;
  }

  uint32_t Lobes() const final { return nested_->Lobes(); }

 protected:
  // Each point's perturbed frame, in the shading frame's coordinates.
  virtual std::vector<Frame> Frames(std::span<const float> wi, const SurfacePoints& at, size_t n) const = 0;

  // The frame of normal m (shading-frame coordinates, unit) whose x is
  // `tangent` made perpendicular to m; the shading frame itself when the
  // two are degenerate.
  static Frame FrameOf(Vec3 m, Vec3 tangent) {
    const Vec3 s = tangent - m * Dot(m, tangent);
    const float length = Length(s);
    if (!(length > 1e-7f) || !std::isfinite(length)) return Frame(Vec3(0, 0, 1));
    Frame f(Vec3(0, 0, 1));
    f.n = m;
    f.s = s / length;
    f.t = Cross(m, f.s);
    return f;
  }

 private:
  // Directions [N,3] of the shading frames in each point's perturbed one.
  static std::vector<float> InFrames(const std::vector<Frame>& frames, std::span<const float> w) {
    std::vector<float> local(3 * frames.size());
    for (size_t k = 0; k < frames.size(); ++k) frames[k].ToLocal(Vec3::Load(&w[3 * k])).Store(&local[3 * k]);
    return local;
  }

  // Whether wo lies on the same side of the perturbed surface as of the
  // shading one (its z in each frame).
  static bool Agree(float wo_z, float wo_perturbed_z) { return wo_z * wo_perturbed_z > 0; }

  // The shadowing of a normal tilted to `n` (shading frame) toward a
  // direction of cosine `cos_o`: 1 for an untilted one, or when the
  // terminator is not softened.
  float Shadowing(Vec3 n, float cos_o) const {
    if (!soften_terminator_) return 1;
    const float cos_d = std::min(std::abs(n.z), 1.0f);
    if (!(cos_d > 0)) return 0;
    const float alpha2 = std::clamp(0.125f * (1 - cos_d * cos_d) / (cos_d * cos_d), 0.0f, 1.0f);
    const float cos2_o = std::max(cos_o * cos_o, 1e-12f);
    return 2 / (1 + std::sqrt(1 + alpha2 * (1 - cos2_o) / cos2_o));
  }

  std::shared_ptr<const SurfaceModel> nested_;
  bool soften_terminator_;
};

}  // namespace yarf
