// Values that vary over a surface, mirroring proto/yarf/v1/texture.proto:
// a Texture answers batches of lookups at surface points, and a material
// property holds either a constant or a texture (TexturedValue) so that a
// model calls one function and never asks which.
#pragma once

#include <algorithm>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "yarf/component.h"
#include "yarf/properties.h"
#include "yarf/surface_points.h"
#include "yarf/vecmath.h"

namespace yarf {

class Texture : public virtual Component {
 public:
  static constexpr const char* kInterface = "yarf.v1.Texture";

  // 1 (a float texture) or 3 (RGB).
  virtual uint32_t Channels() const = 0;
  // value: [N, Channels()].
  virtual void Evaluate(const SurfacePoints& at, std::span<float> value) const = 0;
  // The mean over the unit square of uv, Channels() values (for methods
  // that need one number, e.g. light selection by power).
  virtual std::vector<float> Mean() const = 0;
  // Whether Evaluate reads SurfacePoints::footprint: a texture that never
  // filters over one (a lookup without a MIP map, a constant, a mesh
  // attribute) says not, and a scene whose textures all say so spares
  // transports the footprints (SceneView::FootprintsRead).
  // in-process only: a texture in another process is taken to read them.
  virtual bool ReadsFootprints() const { return true; }
  // Whether Evaluate reads SurfacePoints::position (a solid texture): a
  // scene none of whose textures does spares transports the positions of
  // surfaces without a parameterisation (SceneView::PositionsRead).
  // in-process only: a texture in another process is taken to read them.
  virtual bool ReadsPositions() const { return false; }
};

// A property's values at a batch of points (TexturedValue::At and
// FloatsAt): the constant at every point, or the texture's value at each;
// the vector is filled only for a texture, so a constant costs no
// allocation per call.
template <typename T>
class PointValues {
 public:
  explicit PointValues(T constant) : constant_(constant) {}
  explicit PointValues(std::vector<T> values) : values_(std::move(values)) {}

  // The value at point k.
  T operator[](size_t k) const { return values_.empty() ? constant_ : values_[k]; }
  // The same value at every point (a constant): what a model derives from
  // it can be derived once per call.
  bool IsUniform() const { return values_.empty(); }

 private:
  T constant_{};
  std::vector<T> values_;
};

// A property that is a constant or a texture: `channels` values per point.
// A constant is checked when it is read (the property's Error); a
// texture's values are clamped at evaluation to the range the property
// allows (Clamped), a NaN to its lower end.
class TexturedValue {
 public:
  TexturedValue() = default;
  explicit TexturedValue(Vec3 constant) : constant_(constant) {}
  explicit TexturedValue(float constant) : constant_(constant, constant, constant) {}
  explicit TexturedValue(std::shared_ptr<const Texture> texture) : texture_(std::move(texture)) {}

  // The colour property `key` (a texture reference or an RGB / float),
  // `fallback` when absent; a reflectance (`unit`) lies in [0, 1].
  static TexturedValue Color(const Properties& props, const std::string& key, Vec3 fallback, bool unit) {
    if (auto texture = props.TextureOf(key)) {
      TexturedValue value(std::move(texture));
      return unit ? value.Clamped(0.0f, 1.0f) : value;
    }
    return TexturedValue(unit ? props.Reflectance(key, fallback) : props.Color(key, fallback));
  }
  // The float property `key`: a texture (an RGB one read as its
  // luminance, as Mitsuba's eval_1) or a number.
  static TexturedValue Float(const Properties& props, const std::string& key, float fallback) {
    if (auto texture = props.TextureOf(key)) return TexturedValue(std::move(texture));
    const float value = float(props.Float(key, fallback));
    return TexturedValue(Vec3(value, value, value));
  }

  // This value with a texture's lookups clamped to [lo, hi] in every
  // channel (a constant is left as it is: its reader checked it).
  TexturedValue Clamped(float lo, float hi) const {
    TexturedValue out = *this;
    out.range_ = {lo, hi};
    return out;
  }

  bool IsConstant() const { return texture_ == nullptr; }
  Vec3 Constant() const { return constant_; }
  bool ReadsFootprints() const { return texture_ && texture_->ReadsFootprints(); }
  bool ReadsPositions() const { return texture_ && texture_->ReadsPositions(); }
  // Whether the value is 0 everywhere: a constant black (a texture is
  // taken to be non-zero somewhere), so a model can drop the lobe.
  bool IsZero() const { return IsConstant() && constant_.x == 0 && constant_.y == 0 && constant_.z == 0; }

  // One RGB value per point (a float texture's value in all three).
  void Evaluate(const SurfacePoints& at, std::vector<Vec3>& out) const {
    const size_t n = at.Count();
    out.assign(n, constant_);
    if (IsConstant()) return;
    const uint32_t channels = texture_->Channels();
    std::vector<float> values(n * channels);
    texture_->Evaluate(at, values);
    for (auto& v : values) v = Clamp(v);
    for (size_t k = 0; k < n; ++k)
      out[k] = channels == 3 ? Vec3::Load(&values[3 * k]) : Vec3(values[k], values[k], values[k]);
  }
  // One float per point: a float texture's value, an RGB one's luminance.
  void Evaluate(const SurfacePoints& at, std::vector<float>& out) const {
    const size_t n = at.Count();
    out.assign(n, constant_.x);
    if (IsConstant()) return;
    const uint32_t channels = texture_->Channels();
    std::vector<float> values(n * channels);
    texture_->Evaluate(at, values);
    for (size_t k = 0; k < n; ++k)
      out[k] = Clamp(channels == 3 ? Luminance(Vec3::Load(&values[3 * k])) : values[k]);
  }

  // The RGB values at the points, as Evaluate gives them; no lookup (and
  // no allocation) for a constant.
  PointValues<Vec3> At(const SurfacePoints& at) const {
    if (IsConstant()) return PointValues<Vec3>(constant_);
    std::vector<Vec3> values;
    Evaluate(at, values);
    return PointValues<Vec3>(std::move(values));
  }
  // The float values at the points, likewise.
  PointValues<float> FloatsAt(const SurfacePoints& at) const {
    if (IsConstant()) return PointValues<float>(constant_.x);
    std::vector<float> values;
    Evaluate(at, values);
    return PointValues<float>(std::move(values));
  }

 private:
  // max before min, so that a NaN becomes lo.
  float Clamp(float v) const { return range_ ? std::min(range_->second, std::max(range_->first, v)) : v; }

  Vec3 constant_;
  std::shared_ptr<const Texture> texture_;
  // [lo, hi] of a texture's lookups; none: as the texture gives them.
  std::optional<std::pair<float, float>> range_;
};

}  // namespace yarf
