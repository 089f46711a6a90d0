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

}  // namespace yarf
