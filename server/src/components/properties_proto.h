// Conversions between the proto messages of component.proto and the C++
// component model.
#pragma once

#include "yarf/component.h"
#include "yarf/properties.h"
#include "yarf/v1/component.pb.h"

namespace yarf {

// Throws Error naming the key for a malformed value (a transform without
// 16 values, an unset oneof).
Properties FromProto(const v1::Properties& properties);
Transform FromProto(const v1::Transform& transform, const std::string& what);
v1::ComponentInfo ToProto(const ComponentInfo& info);
// A class of a component process, as its Registry.ListClasses describes it:
// throws Error when its parameters cannot be read (a default that is not
// of its parameter's type, an unknown type).
ComponentInfo FromProto(const v1::ComponentInfo& info, const std::string& origin);

// A parameter's default as ParameterInfo.default_value writes it ("0.5",
// "ggx", "1, 1, 1"), and back for a parameter of `type` (nullopt for "").
std::string DefaultText(const Properties::Value& value);
std::optional<Properties::Value> ParseDefault(ParameterType type, const std::string& text);

}  // namespace yarf
