// blend — two materials mixed by a weight (Mitsuba's `blendbsdf`, pbrt-v4's
// `mix`)
//
// f = (1 − w)·f₀ + w·f₁ at each point, w a float or a texture clamped to
// [0, 1]. pbrt-v4 picks one of its two materials per point at random with
// these odds, which is the same scattering on average.
//
// Sample picks bsdf_1 with probability w (the lobe coordinate, rescaled,
// goes on to the one picked) and draws from it. A delta lobe keeps the
// picked model's weight, its density scaled by the odds of the pick; any
// other direction is weighed against both models, f·|cos θo| over the
// blended density, so the estimate has the blend's own density whichever
// model drew it.
//
// Parameters: Blend::Parameters() below.
//
// Lobes: both models' lobes.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "yarf/support/scatter_rows.h"
#include "yarf/plugin.h"
#include "yarf/texture.h"

namespace {

using yarf::Vec3;

class Blend final : public yarf::SurfaceModel {
 public:
  static yarf::ParameterSchema Parameters() {
    using P = yarf::Parameter;
    return {
        P::FloatTexture("weight").Default(0.5).Range(0, 1).Doc("the share of bsdf_1"),
        P::Material("bsdf_0").Required().Doc("a material defined before"),
        P::Material("bsdf_1").Required().Doc("a material defined before"),
    };
  }

  explicit Blend(const yarf::Properties& props)
      : weight_(yarf::TexturedValue::Float(props, "weight", 0.5f).Clamped(0.0f, 1.0f)),
        models_{props.SurfaceModelOf("bsdf_0"), props.SurfaceModelOf("bsdf_1")} {
    if (weight_.IsConstant() && !(weight_.Constant().x >= 0 && weight_.Constant().x <= 1))
      throw yarf::Error("property 'weight' must lie in [0, 1]");
  }

  void Evaluate(yarf::TransportMode mode, std::span<const float> wi, std::span<const float> wo,
                const yarf::SurfacePoints& at, std::span<float> value) const override {
    const std::vector<float> w = Weights(at);
    std::array<std::vector<float>, 2> values;
    for (int c = 0; c < 2; ++c) {
      values[c].resize(wi.size());
      models_[c]->Evaluate(mode, wi, wo, at, values[c]);
    }
    for (size_t i = 0; i < wi.size(); ++i) value[i] = Mix(values[0][i], values[1][i], w[i / 3]);
  }

  void Pdf(std::span<const float> wi, std::span<const float> wo, const yarf::SurfacePoints& at,
           std::span<float> pdf) const override {
    const std::vector<float> w = Weights(at);
    std::array<std::vector<float>, 2> pdfs;
    for (int c = 0; c < 2; ++c) {
      pdfs[c].resize(wi.size() / 3);
      models_[c]->Pdf(wi, wo, at, pdfs[c]);
    }
    for (size_t k = 0; k < wi.size() / 3; ++k) pdf[k] = Mix(pdfs[0][k], pdfs[1][k], w[k]);
  }

  void Sample(yarf::TransportMode mode, std::span<const float> wi, const yarf::SurfacePoints& at,
              std::span<const float> uniform, uint32_t allowed, std::span<float> wo, std::span<float> weight,
              std::span<float> pdf, std::span<uint32_t> flags) const override {
    const size_t count = wi.size() / 3;
    const std::vector<float> w = Weights(at);
    // Which model each point draws from, and the lobe coordinate rescaled
    // within its share; each model samples every point (one batched call
    // each), and the points keep the draw of their own.
    std::vector<int> picked(count);
    std::vector<float> rescaled(uniform.begin(), uniform.begin() + 3 * count);
    for (size_t k = 0; k < count; ++k) {
      const float u = uniform[3 * k];
      picked[k] = u < w[k] ? 1 : 0;
      rescaled[3 * k] = picked[k] ? u / w[k] : (u - w[k]) / (1 - w[k]);
      rescaled[3 * k] = std::clamp(rescaled[3 * k], 0.0f, 0x1.fffffep-1f);
    }
    std::array<std::vector<float>, 2> directions, weights, pdfs;
    std::array<std::vector<uint32_t>, 2> lobes;
    for (int c = 0; c < 2; ++c) {
      directions[c].resize(3 * count), weights[c].resize(3 * count), pdfs[c].resize(count), lobes[c].resize(count);
      models_[c]->Sample(mode, wi, at, rescaled, allowed, directions[c], weights[c], pdfs[c], lobes[c]);
    }
    std::vector<float> drawn(3 * count);
    for (size_t k = 0; k < count; ++k)
      std::copy_n(&directions[picked[k]][3 * k], 3, &drawn[3 * k]);
    // The blend's value and density toward each point's draw.
    std::vector<float> value(3 * count), density(count);
    Evaluate(mode, wi, drawn, at, value);
    Pdf(wi, drawn, at, density);
    const yarf::SampleRows rows{wo, weight, pdf, flags};
    for (size_t k = 0; k < count; ++k) {
      const int c = picked[k];
      const float odds = c ? w[k] : 1 - w[k];
      const uint32_t lobe = lobes[c][k];
      if (lobe == yarf::kScatterNone || !(pdfs[c][k] > 0) || !(odds > 0)) {
        rows.StoreNoSample(k);
        continue;
      }
      const Vec3 out = Vec3::Load(&drawn[3 * k]);
      if (lobe & yarf::kScatterDelta) {
        rows.Store(k, out, Vec3::Load(&weights[c][3 * k]), odds * pdfs[c][k], lobe);
        continue;
      }
      if (!(density[k] > 0)) {
        rows.StoreNoSample(k);
        continue;
      }
      rows.Store(k, out, Vec3::Load(&value[3 * k]) * (std::abs(out.z) / density[k]), density[k], lobe);
    }
  }

  uint32_t Lobes() const override { return models_[0]->Lobes() | models_[1]->Lobes(); }

 private:
  static float Mix(float a, float b, float w) { return a + (b - a) * w; }

  std::vector<float> Weights(const yarf::SurfacePoints& at) const {
    std::vector<float> w;
    weight_.Evaluate(at, w);
    return w;
  }

  yarf::TexturedValue weight_;
  std::array<std::shared_ptr<const yarf::SurfaceModel>, 2> models_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Blend>(registrar, "blend", "1.0.0",
                        "two materials mixed by a weight (Mitsuba's blendbsdf, pbrt's mix)");
}
