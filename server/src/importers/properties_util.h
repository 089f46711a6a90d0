// Filling yarf Properties and ComponentSpecs.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "importers/matrix.h"
#include "importers/spectrum.h"
#include "yarf/v1/scene.pb.h"

namespace yarf::importers {

inline v1::Property& Slot(v1::Properties& p, const std::string& name) { return (*p.mutable_values())[name]; }

inline void SetFloat(v1::Properties& p, const std::string& name, double v) { Slot(p, name).set_float_value(v); }
inline void SetInt(v1::Properties& p, const std::string& name, int64_t v) { Slot(p, name).set_int_value(v); }
inline void SetBool(v1::Properties& p, const std::string& name, bool v) { Slot(p, name).set_bool_value(v); }
inline void SetString(v1::Properties& p, const std::string& name, const std::string& v) {
  Slot(p, name).set_string_value(v);
}
inline void SetVec3(v1::Properties& p, const std::string& name, const Vec3d& v) {
  v1::Vec3& out = *Slot(p, name).mutable_vec3_value();
  out.set_x(v.x), out.set_y(v.y), out.set_z(v.z);
}
// A list of numbers (bulk data: single precision).
inline void SetFloats(v1::Properties& p, const std::string& name, const std::vector<double>& values) {
  Slot(p, name).mutable_float_array_value()->mutable_values()->Add(values.begin(), values.end());
}
inline void SetRgb(v1::Properties& p, const std::string& name, const Rgb& c) {
  v1::Rgb& rgb = *Slot(p, name).mutable_rgb_value();
  rgb.set_r(c.r), rgb.set_g(c.g), rgb.set_b(c.b);
}

// Names a scene texture (Scene.textures) as the property's value.
inline void SetReference(v1::Properties& p, const std::string& name, const std::string& texture) {
  Slot(p, name).set_reference(texture);
}
inline void SetTransform(v1::Properties& p, const std::string& name, const Matrix4& m) {
  *Slot(p, name).mutable_transform_value() = m.ToProto();
}

// A parameter that varies over the surface or not: a scene texture, or a
// constant (grey for a float).
struct Textured {
  Rgb constant;
  std::string texture;  // its name in Scene.textures; empty for the constant

  bool IsTexture() const { return !texture.empty(); }
  static Textured Grey(double v) { return {{v, v, v}, ""}; }
};

// A colour property: the texture's name, else the constant as rgb.
inline void SetColour(v1::Properties& p, const std::string& name, const Textured& v) {
  if (v.IsTexture())
    SetReference(p, name, v.texture);
  else
    SetRgb(p, name, v.constant);
}
// A float property: the texture's name, else the constant's red channel
// (a float constant is grey).
inline void SetFloatOrTexture(v1::Properties& p, const std::string& name, const Textured& v) {
  if (v.IsTexture())
    SetReference(p, name, v.texture);
  else
    SetFloat(p, name, v.constant.r);
}

inline v1::ComponentSpec Spec(const std::string& class_name, v1::Properties properties = {}) {
  v1::ComponentSpec spec;
  spec.set_class_name(class_name);
  if (!properties.values().empty()) *spec.mutable_properties() = std::move(properties);
  return spec;
}

}  // namespace yarf::importers
