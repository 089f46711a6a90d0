// Parameter schemas: what a component class accepts, declared once beside
// the class. The one declaration drives Describe's answer (ParameterInfo),
// `yarf classes -v`, the plugin reference (docs/plugins.md), the checks of
// Submit (an unknown or ill-typed property is refused with the scene path
// of its value) and the Properties the class reads: a declared default
// reaches the constructor for a key the scene leaves out.
//
//   static yarf::ParameterSchema Parameters() {
//     return {
//         yarf::Parameter::RgbTexture("reflectance").Default(0.5).Range(0, 1).Doc("diffuse albedo"),
//         yarf::Parameter::String("distribution").Default("ggx").Choices({"ggx", "beckmann"}),
//     };
//   }
#pragma once

#include <concepts>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "yarf/properties.h"

namespace yarf {

// What values a parameter takes: the kinds of proto Property it accepts.
enum class ParameterType {
  kBool,          // bool_value
  kInt,           // int_value
  kFloat,         // float_value or int_value
  kString,        // string_value
  kRgb,           // rgb_value, or a float/int as grey
  kVector,        // vec3_value
  kTransform,     // transform_value
  kFloatArray,    // float_array_value
  kFloatTexture,  // a float/int, or a reference to a scene texture
  kRgbTexture,    // an rgb or float/int, or a reference to a scene texture
  kMaterial,      // a reference to a material of the scene defined before
  kRgbGrid,       // an rgb or float/int (a value everywhere), or a float array (a voxel grid)
  kFile,          // string_value: a file the server resolves for the class
};

// "bool", "float or texture", ...: as Describe and the reference name it.
inline const char* ParameterTypeName(ParameterType type) {
  switch (type) {
    case ParameterType::kBool: return "bool";
    case ParameterType::kInt: return "int";
    case ParameterType::kFloat: return "float";
    case ParameterType::kString: return "string";
    case ParameterType::kRgb: return "rgb";
    case ParameterType::kVector: return "vector";
    case ParameterType::kTransform: return "transform";
    case ParameterType::kFloatArray: return "float array";
    case ParameterType::kFloatTexture: return "float or texture";
    case ParameterType::kRgbTexture: return "rgb or texture";
    case ParameterType::kMaterial: return "material";
    case ParameterType::kRgbGrid: return "rgb or grid";
    case ParameterType::kFile: return "file";
  }
  return "unknown";
}

struct Parameter {
  std::string name;
  ParameterType type = ParameterType::kFloat;
  // Given to the class when the scene leaves the key out; none: the key
  // may be left out only if the doc says what then happens.
  std::optional<Properties::Value> default_value;
  bool required = false;
  // Bounds of a number, or of every channel of a colour (inclusive).
  std::optional<double> min, max;
  // The values a string may take; empty: any.
  std::vector<std::string> choices;
  std::string doc;

  static Parameter Of(std::string name, ParameterType type) {
    Parameter p;
    p.name = std::move(name);
    p.type = type;
    return p;
  }
  static Parameter Bool(std::string name) { return Of(std::move(name), ParameterType::kBool); }
  static Parameter Int(std::string name) { return Of(std::move(name), ParameterType::kInt); }
  static Parameter Float(std::string name) { return Of(std::move(name), ParameterType::kFloat); }
  static Parameter String(std::string name) { return Of(std::move(name), ParameterType::kString); }
  static Parameter Rgb(std::string name) { return Of(std::move(name), ParameterType::kRgb); }
  static Parameter Vector(std::string name) { return Of(std::move(name), ParameterType::kVector); }
  static Parameter Matrix(std::string name) { return Of(std::move(name), ParameterType::kTransform); }
  static Parameter FloatArray(std::string name) { return Of(std::move(name), ParameterType::kFloatArray); }
  static Parameter FloatTexture(std::string name) { return Of(std::move(name), ParameterType::kFloatTexture); }
  static Parameter RgbTexture(std::string name) { return Of(std::move(name), ParameterType::kRgbTexture); }
  static Parameter Material(std::string name) { return Of(std::move(name), ParameterType::kMaterial); }
  static Parameter RgbGrid(std::string name) { return Of(std::move(name), ParameterType::kRgbGrid); }
  static Parameter File(std::string name) { return Of(std::move(name), ParameterType::kFile); }

  Parameter&& Default(bool value) && { return WithDefault(value); }
  Parameter&& Default(int value) && {
    return type == ParameterType::kInt ? WithDefault(int64_t(value)) : WithDefault(double(value));
  }
  Parameter&& Default(int64_t value) && { return WithDefault(value); }
  Parameter&& Default(double value) && { return WithDefault(value); }
  Parameter&& Default(const char* value) && { return WithDefault(std::string(value)); }
  Parameter&& Default(std::string value) && { return WithDefault(std::move(value)); }
  // A colour default; a float default of an rgb parameter is its grey.
  Parameter&& Default(float r, float g, float b) && { return WithDefault(yarf::Rgb{Vec3(r, g, b)}); }
  Parameter&& Default(Vec3 value) && { return WithDefault(value); }
  Parameter&& Required() && {
    required = true;
    return std::move(*this);
  }
  Parameter&& Min(double value) && {
    min = value;
    return std::move(*this);
  }
  Parameter&& Max(double value) && {
    max = value;
    return std::move(*this);
  }
  Parameter&& Range(double lo, double hi) && { return std::move(*this).Min(lo).Max(hi); }
  Parameter&& Choices(std::vector<std::string> values) && {
    choices = std::move(values);
    return std::move(*this);
  }
  Parameter&& Doc(std::string text) && {
    doc = std::move(text);
    return std::move(*this);
  }

 private:
  Parameter&& WithDefault(Properties::Value value) {
    default_value = std::move(value);
    return std::move(*this);
  }
};

using ParameterSchema = std::vector<Parameter>;

// A file parameter named ...filename may instead be given as the hash of
// an uploaded asset, under ...asset ("filename" → "asset",
// "albedo_filename" → "albedo_asset"); empty for any other name.
inline std::string AssetKeyOf(std::string_view file_key) {
  constexpr std::string_view kFile = "filename";
  if (!file_key.ends_with(kFile)) return "";
  return std::string(file_key.substr(0, file_key.size() - kFile.size())) + "asset";
}

// A class declares its parameters with `static ParameterSchema Parameters()`.
template <typename T>
concept DeclaresParameters = requires {
  { T::Parameters() } -> std::convertible_to<ParameterSchema>;
};

}  // namespace yarf
