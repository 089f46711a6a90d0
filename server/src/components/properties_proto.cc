#include "components/properties_proto.h"

#include <cmath>

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

v1::ComponentInfo ToProto(const ComponentInfo& info) {
  v1::ComponentInfo out;
  out.set_class_name(info.class_name);
  out.set_version(info.version);
  for (const auto& name : info.interfaces) out.add_interfaces(name);
  out.set_summary(info.summary);
  out.set_origin(info.origin);
  return out;
}

}  // namespace yarf
