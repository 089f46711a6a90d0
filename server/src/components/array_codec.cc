#include "components/array_codec.h"

#include <cstring>

#include "yarf/error.h"

namespace yarf {
namespace {

template <typename T>
v1::Array Encode(const std::vector<T>& values, std::initializer_list<uint32_t> shape, v1::Array::DType dtype) {
  v1::Array array;
  array.set_dtype(dtype);
  for (uint32_t extent : shape) array.add_shape(extent);
  // Little-endian hosts only (x86-64, arm64): the bytes are the values.
  array.set_data(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
  return array;
}

}  // namespace

std::vector<float> FloatsOf(const v1::Array& array, std::initializer_list<uint32_t> trailing,
                            const std::string& what, size_t& rows) {
  if (array.dtype() != v1::Array::FLOAT32) throw Error(what + ": expected a FLOAT32 array");
  if (array.shape_size() != int(trailing.size()) + 1) {
    std::string expected = "[N";
    for (uint32_t extent : trailing) expected += ", " + std::to_string(extent);
    throw Error(what + ": expected shape " + expected + "]");
  }
  size_t count = array.shape(0);
  int axis = 1;
  for (uint32_t extent : trailing) {
    if (array.shape(axis++) != extent)
      throw Error(what + ": dimension " + std::to_string(axis - 1) + " must be " + std::to_string(extent));
    count *= extent;
  }
  if (array.data().size() != count * sizeof(float))
    throw Error(what + ": " + std::to_string(array.data().size()) + " bytes for " + std::to_string(count) +
                " float32 values");
  std::vector<float> values(count);
  std::memcpy(values.data(), array.data().data(), array.data().size());
  rows = array.shape(0);
  return values;
}

std::vector<float> BatchDecoder::Floats(const v1::Array& array, std::initializer_list<uint32_t> trailing,
                                        const std::string& what) {
  size_t rows = 0;
  std::vector<float> values = FloatsOf(array, trailing, what, rows);
  CheckRows(rows, what);
  return values;
}

std::vector<uint32_t> BatchDecoder::Uint32s(const v1::Array& array, const std::string& what) {
  if (array.dtype() != v1::Array::UINT32 || array.shape_size() != 1)
    throw Error(what + ": expected a UINT32 array of shape [N]");
  const size_t rows = array.shape(0);
  if (array.data().size() != rows * sizeof(uint32_t))
    throw Error(what + ": " + std::to_string(array.data().size()) + " bytes for " + std::to_string(rows) +
                " uint32 values");
  CheckRows(rows, what);
  std::vector<uint32_t> values(rows);
  std::memcpy(values.data(), array.data().data(), array.data().size());
  return values;
}

void BatchDecoder::CheckRows(size_t rows, const std::string& what) {
  if (!first_ && rows != rows_)
    throw Error(what + " has " + std::to_string(rows) + " rows, the batch " + std::to_string(rows_));
  rows_ = rows;
  first_ = false;
}

v1::Array FloatArray(const std::vector<float>& values, std::initializer_list<uint32_t> shape) {
  return Encode(values, shape, v1::Array::FLOAT32);
}

v1::Array Uint32Array(const std::vector<uint32_t>& values, std::initializer_list<uint32_t> shape) {
  return Encode(values, shape, v1::Array::UINT32);
}

}  // namespace yarf
