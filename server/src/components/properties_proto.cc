#include "components/properties_proto.h"

#include <charconv>
#include <cmath>
#include <sstream>

namespace yarf {

Transform FromProto(const v1::Transform& transform, const std::string& what) {
  if (transform.m_size() != 16)
    throw Error(what + ": a transform needs 16 values, got " + std::to_string(transform.m_size()));
  Transform t;
  for (int i = 0; i < 16; ++i) {
    if (!std::isfinite(transform.m(i))) throw Error(what + ": transform has a non-finite value");
    t.m[i] = transform.m(i);
  }
  return t;
}

Properties FromProto(const v1::Properties& properties) {
  Properties out;
  for (const auto& [key, value] : properties.values()) {
    switch (value.value_case()) {
      case v1::Property::kFloatValue:
        out.Set(key, value.float_value());
        break;
      case v1::Property::kIntValue:
        out.Set(key, value.int_value());
        break;
      case v1::Property::kBoolValue:
        out.Set(key, value.bool_value());
        break;
      case v1::Property::kStringValue:
        out.Set(key, value.string_value());
        break;
      case v1::Property::kVec3Value: {
        const auto& v = value.vec3_value();
        out.Set(key, Vec3(float(v.x()), float(v.y()), float(v.z())));
        break;
      }
      case v1::Property::kRgbValue: {
        const auto& c = value.rgb_value();
        out.Set(key, Rgb{Vec3(float(c.r()), float(c.g()), float(c.b()))});
        break;
      }
      case v1::Property::kTransformValue:
        out.Set(key, FromProto(value.transform_value(), "property '" + key + "'"));
        break;
      case v1::Property::kReference:
        out.Set(key, Reference{value.reference()});
        break;
      case v1::Property::kFloatArrayValue: {
        const auto& values = value.float_array_value().values();
        out.Set(key, std::vector<float>(values.begin(), values.end()));
        break;
      }
      default:
        throw Error("property '" + key + "' has no value");
    }
  }
  return out;
}

namespace {

std::string Shortest(double value) {
  char text[32];
  const auto end = std::to_chars(text, text + sizeof text, value).ptr;
  return std::string(text, end);
}

std::string Triple(Vec3 v) { return Shortest(v.x) + ", " + Shortest(v.y) + ", " + Shortest(v.z); }

std::optional<ParameterType> TypeNamed(const std::string& name) {
  for (int t = int(ParameterType::kBool); t <= int(ParameterType::kFile); ++t)
    if (name == ParameterTypeName(ParameterType(t))) return ParameterType(t);
  return std::nullopt;
}

// Numbers separated by commas; none when one does not parse whole.
std::optional<std::vector<double>> Numbers(const std::string& text) {
  std::vector<double> numbers;
  std::stringstream items(text);
  for (std::string item; std::getline(items, item, ',');) {
    const size_t first = item.find_first_not_of(' '), last = item.find_last_not_of(' ');
    if (first == std::string::npos) return std::nullopt;
    double value = 0;
    const char* begin = item.data() + first;
    const char* end = item.data() + last + 1;
    const auto [ptr, error] = std::from_chars(begin, end, value);
    if (error != std::errc() || ptr != end || !std::isfinite(value)) return std::nullopt;
    numbers.push_back(value);
  }
  return numbers;
}

}  // namespace

std::string DefaultText(const Properties::Value& value) {
  if (const auto* f = std::get_if<double>(&value)) return Shortest(*f);
  if (const auto* i = std::get_if<int64_t>(&value)) return std::to_string(*i);
  if (const auto* b = std::get_if<bool>(&value)) return *b ? "true" : "false";
  if (const auto* s = std::get_if<std::string>(&value)) return *s;
  if (const auto* v = std::get_if<Vec3>(&value)) return Triple(*v);
  if (const auto* c = std::get_if<Rgb>(&value)) return Triple(c->value);
  return "";
}

std::optional<Properties::Value> ParseDefault(ParameterType type, const std::string& text) {
  if (text.empty()) return std::nullopt;
  const auto bad = [&]() -> Error {
    return Error("default '" + text + "' is not " + ParameterTypeName(type));
  };
  switch (type) {
    case ParameterType::kBool:
      if (text == "true" || text == "false") return Properties::Value(text == "true");
      throw bad();
    case ParameterType::kString:
    case ParameterType::kFile: return Properties::Value(text);
    case ParameterType::kInt: {
      int64_t value = 0;
      const auto [ptr, error] = std::from_chars(text.data(), text.data() + text.size(), value);
      if (error != std::errc() || ptr != text.data() + text.size()) throw bad();
      return Properties::Value(value);
    }
    case ParameterType::kFloat:
    case ParameterType::kFloatTexture:
    case ParameterType::kRgb:
    case ParameterType::kRgbTexture:
    case ParameterType::kRgbGrid:
    case ParameterType::kVector: {
      const auto numbers = Numbers(text);
      const bool colour =
          type == ParameterType::kRgb || type == ParameterType::kRgbTexture || type == ParameterType::kRgbGrid;
      if (numbers && numbers->size() == 1 && type != ParameterType::kVector) return Properties::Value((*numbers)[0]);
      if (numbers && numbers->size() == 3 && (colour || type == ParameterType::kVector)) {
        const std::vector<double>& n = *numbers;
        const Vec3 v{float(n[0]), float(n[1]), float(n[2])};
        return colour ? Properties::Value(Rgb{v}) : Properties::Value(v);
      }
      throw bad();
    }
    default: throw Error(std::string("a ") + ParameterTypeName(type) + " parameter has no default");
  }
}

v1::ComponentInfo ToProto(const ComponentInfo& info) {
  v1::ComponentInfo out;
  out.set_class_name(info.class_name);
  out.set_version(info.version);
  for (const auto& name : info.interfaces) out.add_interfaces(name);
  out.set_summary(info.summary);
  out.set_origin(info.origin);
  out.set_declares_parameters(info.declares_parameters);
  for (const std::string& capability : info.capabilities) out.add_capabilities(capability);
  for (const Parameter& parameter : info.parameters) {
    v1::ParameterInfo* p = out.add_parameters();
    p->set_name(parameter.name);
    p->set_type(ParameterTypeName(parameter.type));
    if (parameter.default_value) p->set_default_value(DefaultText(*parameter.default_value));
    p->set_required(parameter.required);
    if (parameter.min) p->set_min(*parameter.min);
    if (parameter.max) p->set_max(*parameter.max);
    for (const std::string& choice : parameter.choices) p->add_choices(choice);
    p->set_doc(parameter.doc);
  }
  return out;
}

ComponentInfo FromProto(const v1::ComponentInfo& info, const std::string& origin) {
  ComponentInfo out;
  out.class_name = info.class_name();
  out.version = info.version();
  out.summary = info.summary();
  out.origin = origin;
  out.interfaces.assign(info.interfaces().begin(), info.interfaces().end());
  out.declares_parameters = info.declares_parameters();
  out.capabilities.assign(info.capabilities().begin(), info.capabilities().end());
  for (const v1::ParameterInfo& p : info.parameters()) {
    const std::string what = "class '" + info.class_name() + "', parameter '" + p.name() + "'";
    const std::optional<ParameterType> type = TypeNamed(p.type());
    if (!type) throw Error(what + ": unknown type '" + p.type() + "'");
    Parameter parameter = Parameter::Of(p.name(), *type);
    try {
      parameter.default_value = ParseDefault(*type, p.default_value());
    } catch (const Error& e) {
      throw Error(what + ": " + e.what());
    }
    parameter.required = p.required();
    if (p.has_min()) parameter.min = p.min();
    if (p.has_max()) parameter.max = p.max();
    parameter.choices.assign(p.choices().begin(), p.choices().end());
    parameter.doc = p.doc();
    out.parameters.push_back(std::move(parameter));
  }
  return out;
}

}  // namespace yarf
