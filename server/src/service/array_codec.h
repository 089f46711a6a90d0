// Dense batch arrays (proto Array) to and from C++ float and uint32 vectors.
#pragma once

#include <cstdint>
#include <initializer_list>
#include <string>
#include <vector>

#include "yarf/v1/component.pb.h"

namespace yarf {

// The elements of a FLOAT32 array whose shape is [N, trailing...]; returns
// them and sets `rows` to N. Throws Error naming `what` for another dtype,
// another trailing shape or a byte count that does not match the shape.
std::vector<float> FloatsOf(const v1::Array& array, std::initializer_list<uint32_t> trailing,
                            const std::string& what, size_t& rows);

v1::Array FloatArray(const std::vector<float>& values, std::initializer_list<uint32_t> shape);
v1::Array Uint32Array(const std::vector<uint32_t>& values, std::initializer_list<uint32_t> shape);

}  // namespace yarf
