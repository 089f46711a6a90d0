// An operand of a composite texture (checkerboard's colours, mix's and
// scale's inputs): a constant or a texture, as TexturedValue, together
// with its mean over the unit square, which Texture::Mean of the
// composite needs and TexturedValue does not keep.
#pragma once

#include <cmath>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "texture_rows.h"
#include "yarf/error.h"
#include "yarf/properties.h"
#include "yarf/texture.h"
#include "yarf/vecmath.h"

namespace yarf::textures {

class TextureInput {
 public:
  // The colour property `key` (an RGB, a float or a texture).
  static TextureInput Color(const Properties& props, const std::string& key, Vec3 fallback) {
    TextureInput input(TexturedValue::Color(props, key, fallback, false));
    const auto texture = props.TextureOf(key);
    input.mean_ = texture ? MeanColor(*texture) : input.value_.Constant();
    input.RequireFiniteConstant(key);
    return input;
  }
  // The float property `key` (a number or a texture, an RGB one read as
  // its luminance); its mean is held in all three channels.
  static TextureInput Float(const Properties& props, const std::string& key, float fallback) {
    TextureInput input(TexturedValue::Float(props, key, fallback));
    const auto texture = props.TextureOf(key);
    const float mean = texture ? MeanFloat(*texture) : input.value_.Constant().x;
    input.mean_ = Vec3(mean, mean, mean);
    input.RequireFiniteConstant(key);
    return input;
  }

  bool IsConstant() const { return value_.IsConstant(); }
  bool ReadsFootprints() const { return value_.ReadsFootprints(); }
  bool ReadsPositions() const { return value_.ReadsPositions(); }
  Vec3 Constant() const { return value_.Constant(); }
  Vec3 Mean() const { return mean_; }
  void Evaluate(const SurfacePoints& at, std::vector<Vec3>& out) const { value_.Evaluate(at, out); }
  void Evaluate(const SurfacePoints& at, std::vector<float>& out) const { value_.Evaluate(at, out); }

 private:
  explicit TextureInput(TexturedValue value) : value_(std::move(value)) {}

  static Vec3 MeanColor(const Texture& texture) {
    const std::vector<float> mean = texture.Mean();
    if (mean.size() == 3) return Vec3::Load(mean.data());
    return mean.size() == 1 ? Vec3(mean[0], mean[0], mean[0]) : Vec3();
  }
  static float MeanFloat(const Texture& texture) {
    const std::vector<float> mean = texture.Mean();
    if (mean.size() == 3) return Luminance(Vec3::Load(mean.data()));
    return mean.size() == 1 ? mean[0] : 0.0f;
  }
  void RequireFiniteConstant(const std::string& key) const {
    const Vec3 c = value_.Constant();
    if (IsConstant() && !(std::isfinite(c.x) && std::isfinite(c.y) && std::isfinite(c.z)))
      throw Error("property '" + key + "' must be finite in every channel");
  }

  TexturedValue value_;
  Vec3 mean_;
};

// The value of a two-input pattern (checkerboard, dots, mix): both inputs
// looked up at the points, blended at each as (1 − w)·first + w·second
// with w = second_weight(k), into `value` ([N,3]).
template <typename SecondWeight>
void Blend(const SurfacePoints& at, std::span<float> value, const TextureInput& first, const TextureInput& second,
           SecondWeight&& second_weight) {
  CheckShapes(at, value, 3);
  std::vector<Vec3> a, b;
  first.Evaluate(at, a);
  second.Evaluate(at, b);
  for (size_t k = 0; k < at.Count(); ++k) {
    const float w = second_weight(k);
    ((1.0f - w) * a[k] + w * b[k]).Store(&value[3 * k]);
  }
}

}  // namespace yarf::textures
