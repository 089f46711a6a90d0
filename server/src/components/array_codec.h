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

// The arrays of one batched call, which must all have the same number of
// rows; the first array decoded sets it.
class BatchDecoder {
 public:
  std::vector<float> Floats(const v1::Array& array, std::initializer_list<uint32_t> trailing,
                            const std::string& what);
  // A UINT32 array of shape [N].
  std::vector<uint32_t> Uint32s(const v1::Array& array, const std::string& what);
  uint32_t rows() const { return uint32_t(rows_); }

 private:
  void CheckRows(size_t rows, const std::string& what);

  size_t rows_ = 0;
  bool first_ = true;
};

v1::Array FloatArray(const std::vector<float>& values, std::initializer_list<uint32_t> shape);
v1::Array Uint32Array(const std::vector<uint32_t>& values, std::initializer_list<uint32_t> shape);

}  // namespace yarf
