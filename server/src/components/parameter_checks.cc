#include "components/parameter_checks.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "yarf/error.h"

namespace yarf {
namespace {

using Kind = v1::Property::ValueCase;

// Insertions, deletions, substitutions and swaps of neighbours ("bpdt"
// for "bdpt" is one), each counting one.
size_t EditDistance(std::string_view a, std::string_view b) {
  const size_t columns = b.size() + 1;
  std::vector<size_t> d((a.size() + 1) * columns);
  const auto at = [&](size_t i, size_t j) -> size_t& { return d[i * columns + j]; };
  for (size_t i = 0; i <= a.size(); ++i) at(i, 0) = i;
  for (size_t j = 0; j <= b.size(); ++j) at(0, j) = j;
  for (size_t i = 1; i <= a.size(); ++i)
    for (size_t j = 1; j <= b.size(); ++j) {
      at(i, j) = std::min({at(i - 1, j) + 1, at(i, j - 1) + 1, at(i - 1, j - 1) + (a[i - 1] == b[j - 1] ? 0 : 1)});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        at(i, j) = std::min(at(i, j), at(i - 2, j - 2) + 1);
    }
  return at(a.size(), b.size());
}

bool Accepts(ParameterType type, Kind kind) {
  const bool number = kind == Kind::kFloatValue || kind == Kind::kIntValue;
  switch (type) {
    case ParameterType::kBool: return kind == Kind::kBoolValue;
    case ParameterType::kInt: return kind == Kind::kIntValue;
    case ParameterType::kFloat: return number;
    case ParameterType::kString:
    case ParameterType::kFile: return kind == Kind::kStringValue;
    case ParameterType::kRgb: return number || kind == Kind::kRgbValue;
    case ParameterType::kVector: return kind == Kind::kVec3Value;
    case ParameterType::kTransform: return kind == Kind::kTransformValue;
    case ParameterType::kFloatArray: return kind == Kind::kFloatArrayValue;
    case ParameterType::kFloatTexture: return number || kind == Kind::kReference;
    case ParameterType::kRgbTexture: return number || kind == Kind::kRgbValue || kind == Kind::kReference;
    case ParameterType::kMaterial: return kind == Kind::kReference;
    case ParameterType::kRgbGrid: return number || kind == Kind::kRgbValue || kind == Kind::kFloatArrayValue;
  }
  return false;
}

// Whether a default value is one the parameter's type takes.
bool Accepts(ParameterType type, const Properties::Value& value) {
  if (std::holds_alternative<double>(value)) return Accepts(type, Kind::kFloatValue);
  if (std::holds_alternative<int64_t>(value)) return Accepts(type, Kind::kIntValue);
  if (std::holds_alternative<bool>(value)) return type == ParameterType::kBool;
  if (std::holds_alternative<std::string>(value)) return Accepts(type, Kind::kStringValue);
  if (std::holds_alternative<Vec3>(value)) return type == ParameterType::kVector;
  if (std::holds_alternative<Rgb>(value)) return Accepts(type, Kind::kRgbValue);
  return false;
}

const char* KindName(Kind kind) {
  switch (kind) {
    case Kind::kFloatValue: return "a float";
    case Kind::kIntValue: return "an int";
    case Kind::kBoolValue: return "a bool";
    case Kind::kStringValue: return "a string";
    case Kind::kVec3Value: return "a vector";
    case Kind::kRgbValue: return "an rgb";
    case Kind::kTransformValue: return "a transform";
    case Kind::kReference: return "a reference";
    case Kind::kFloatArrayValue: return "a float array";
    default: return "no value";
  }
}

// A bound or value as people write it: whole numbers in full (a photon
// count of 50000000, not 5e+07).
std::string Number(double value) {
  char text[32];
  if (value == std::floor(value) && std::fabs(value) < 1e15)
    std::snprintf(text, sizeof text, "%.0f", value);
  else
    std::snprintf(text, sizeof text, "%g", value);
  return text;
}

void CheckRange(const Parameter& parameter, double value, const std::string& where) {
  if (parameter.min && !(value >= *parameter.min))
    throw Error(where + ": " + Number(value) + " is below " + Number(*parameter.min) + ", the least it may be");
  if (parameter.max && !(value <= *parameter.max))
    throw Error(where + ": " + Number(value) + " is above " + Number(*parameter.max) + ", the most it may be");
}

void CheckValue(const Parameter& parameter, const v1::Property& value, const std::string& where) {
  switch (value.value_case()) {
    case Kind::kFloatValue: return CheckRange(parameter, value.float_value(), where);
    case Kind::kIntValue: return CheckRange(parameter, double(value.int_value()), where);
    case Kind::kRgbValue:
      for (const double channel : {value.rgb_value().r(), value.rgb_value().g(), value.rgb_value().b()})
        CheckRange(parameter, channel, where);
      return;
    case Kind::kStringValue: {
      const auto& choices = parameter.choices;
      if (choices.empty() || std::find(choices.begin(), choices.end(), value.string_value()) != choices.end()) return;
      std::string listed;
      for (const std::string& choice : choices) listed += (listed.empty() ? "'" : ", '") + choice + "'";
      const std::string nearest = DidYouMean(value.string_value(), choices);
      throw Error(where + ": '" + value.string_value() + "' is not one of " + listed +
                  (nearest.empty() ? "" : "; did you mean '" + nearest + "'?"));
    }
    default: return;
  }
}

// Whether a scene gives `parameter`: a file named `...filename` may come as
// the hash of an uploaded asset, `...asset`, which the server resolves.
bool Given(const v1::Properties& properties, const Parameter& parameter) {
  if (properties.values().contains(parameter.name)) return true;
  const std::string asset = parameter.type == ParameterType::kFile ? AssetKeyOf(parameter.name) : "";
  return !asset.empty() && properties.values().contains(asset);
}

std::vector<std::string> NamesOf(const std::vector<Parameter>& parameters) {
  std::vector<std::string> names;
  for (const Parameter& parameter : parameters) names.push_back(parameter.name);
  return names;
}

}  // namespace

std::string DidYouMean(std::string_view name, const std::vector<std::string>& candidates) {
  // Near enough: a few letters wrong, fewer for short names.
  const size_t most = std::max<size_t>(1, std::min<size_t>(3, name.size() / 3));
  std::string nearest;
  size_t best = most + 1;
  for (const std::string& candidate : candidates) {
    const size_t distance = EditDistance(name, candidate);
    if (distance < best) {
      best = distance;
      nearest = candidate;
    }
  }
  return nearest;
}

void CheckProperties(const ComponentInfo& info, const v1::Properties& properties, const std::string& where) {
  if (!info.declares_parameters) return;
  // In name order, so that the first problem reported does not depend on the map's order.
  const std::map<std::string, v1::Property> sorted(properties.values().begin(), properties.values().end());
  for (const auto& [key, value] : sorted) {
    const std::string place = where + "." + key;
    const auto parameter = std::find_if(info.parameters.begin(), info.parameters.end(),
                                        [&](const Parameter& p) { return p.name == key; });
    if (parameter == info.parameters.end()) {
      const std::string nearest = DidYouMean(key, NamesOf(info.parameters));
      throw Error(place + ": '" + info.class_name + "' has no parameter '" + key + "'" +
                  (nearest.empty() ? "" : "; did you mean '" + nearest + "'?") + " (`yarf classes -v " +
                  info.class_name + "` lists its parameters)");
    }
    if (!Accepts(parameter->type, value.value_case()))
      throw Error(place + ": must be " + ParameterTypeName(parameter->type) + ", not " +
                  KindName(value.value_case()));
    CheckValue(*parameter, value, place);
  }
  for (const Parameter& parameter : info.parameters)
    if (parameter.required && !Given(properties, parameter))
      throw Error(where + ": '" + info.class_name + "' needs parameter '" + parameter.name + "' (" +
                  ParameterTypeName(parameter.type) + (parameter.doc.empty() ? "" : ": " + parameter.doc) + ")");
}

void CheckSchema(const ComponentInfo& info) {
  for (const std::string& capability : info.capabilities)
    if (std::find(kCapabilities.begin(), kCapabilities.end(), capability) == kCapabilities.end()) {
      std::string known;
      for (const std::string& name : kCapabilities) known += (known.empty() ? "" : ", ") + name;
      throw Error("class '" + info.class_name + "' declares an unknown capability '" + capability +
                  "' (there are " + known + ")");
    }
  std::set<std::string> seen;
  for (const Parameter& parameter : info.parameters) {
    const std::string what = "class '" + info.class_name + "', parameter '" + parameter.name + "'";
    if (parameter.name.empty()) throw Error("class '" + info.class_name + "' declares a parameter without a name");
    if (!seen.insert(parameter.name).second) throw Error(what + " is declared twice");
    if (parameter.default_value && !Accepts(parameter.type, *parameter.default_value))
      throw Error(what + ": its default is not " + ParameterTypeName(parameter.type));
    if (parameter.min && parameter.max && !(*parameter.min <= *parameter.max))
      throw Error(what + ": its least value is above its most");
    if (!parameter.choices.empty() && parameter.type != ParameterType::kString)
      throw Error(what + ": only a string has choices");
    if (!parameter.default_value) continue;
    // The default must pass the checks a scene's value passes.
    const Properties::Value& value = *parameter.default_value;
    const std::string place = what + "'s default";
    if (const auto* f = std::get_if<double>(&value)) CheckRange(parameter, *f, place);
    if (const auto* i = std::get_if<int64_t>(&value)) CheckRange(parameter, double(*i), place);
    if (const auto* c = std::get_if<Rgb>(&value))
      for (int channel = 0; channel < 3; ++channel) CheckRange(parameter, c->value[channel], place);
    if (const auto* s = std::get_if<std::string>(&value)) {
      v1::Property text;
      text.set_string_value(*s);
      CheckValue(parameter, text, place);
    }
  }
}

}  // namespace yarf
