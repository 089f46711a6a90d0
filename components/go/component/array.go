package component

import (
	"encoding/binary"
	"fmt"
	"math"
	"math/bits"
	"strings"

	yarfv1 "yarf.dev/components/go/gen/yarfv1"
)

// A yarf.v1.Array is a dense batch: 4-byte little-endian elements,
// row-major, shape[0] the batch size N. These functions convert it to and
// from Go slices with one pass over the bytes.

const bytesPerElement = 4

// DecodeFloat32 returns the elements of a FLOAT32 array of shape
// [N, trailing...] and N. The error names the array as `what` and says what
// is wrong: another dtype, another shape, or a byte count that does not
// match the shape.
func DecodeFloat32(array *yarfv1.Array, what string, trailing ...uint32) ([]float32, int, error) {
	data, rows, err := checkArray(array, yarfv1.Array_FLOAT32, what, trailing)
	if err != nil {
		return nil, 0, err
	}
	values := make([]float32, len(data)/bytesPerElement)
	for i := range values {
		values[i] = math.Float32frombits(binary.LittleEndian.Uint32(data[bytesPerElement*i:]))
	}
	return values, rows, nil
}

// DecodeUint32 is DecodeFloat32 for UINT32 arrays.
func DecodeUint32(array *yarfv1.Array, what string, trailing ...uint32) ([]uint32, int, error) {
	data, rows, err := checkArray(array, yarfv1.Array_UINT32, what, trailing)
	if err != nil {
		return nil, 0, err
	}
	values := make([]uint32, len(data)/bytesPerElement)
	for i := range values {
		values[i] = binary.LittleEndian.Uint32(data[bytesPerElement*i:])
	}
	return values, rows, nil
}

// EncodeFloat32 makes a FLOAT32 array of the given shape. It panics when
// the shape does not hold exactly len(values) elements: that is a bug in
// the caller, not bad input.
func EncodeFloat32(values []float32, shape ...uint32) *yarfv1.Array {
	checkShape(len(values), shape)
	data := make([]byte, 0, bytesPerElement*len(values))
	for _, v := range values {
		data = binary.LittleEndian.AppendUint32(data, math.Float32bits(v))
	}
	return &yarfv1.Array{Dtype: yarfv1.Array_FLOAT32, Shape: shape, Data: data}
}

// EncodeUint32 is EncodeFloat32 for UINT32 arrays.
func EncodeUint32(values []uint32, shape ...uint32) *yarfv1.Array {
	checkShape(len(values), shape)
	data := make([]byte, 0, bytesPerElement*len(values))
	for _, v := range values {
		data = binary.LittleEndian.AppendUint32(data, v)
	}
	return &yarfv1.Array{Dtype: yarfv1.Array_UINT32, Shape: shape, Data: data}
}

// checkArray validates dtype, shape [N, trailing...] and byte count, and
// returns the data and N.
func checkArray(array *yarfv1.Array, dtype yarfv1.Array_DType, what string, trailing []uint32) ([]byte, int, error) {
	if array.GetDtype() != dtype {
		return nil, 0, fmt.Errorf("%s: expected a %s array, got %s", what, dtype, array.GetDtype())
	}
	shape := array.GetShape()
	if len(shape) != len(trailing)+1 {
		return nil, 0, fmt.Errorf("%s: expected shape %s, got %s", what, shapeText(trailing), dimsText(shape))
	}
	for axis, extent := range trailing {
		if shape[axis+1] != extent {
			return nil, 0, fmt.Errorf("%s: dimension %d must be %d, got %d", what, axis+1, extent, shape[axis+1])
		}
	}
	count, ok := elementCount(shape)
	if !ok {
		return nil, 0, fmt.Errorf("%s: shape %s is too large", what, dimsText(shape))
	}
	data := array.GetData()
	if uint64(len(data)) != count*bytesPerElement {
		return nil, 0, fmt.Errorf("%s: %d bytes for shape %s (%d bytes expected)",
			what, len(data), dimsText(shape), count*bytesPerElement)
	}
	return data, int(shape[0]), nil
}

// elementCount is the product of the extents; false when it cannot be the
// element count of any message (over 2^61, so its byte count overflows).
func elementCount(shape []uint32) (uint64, bool) {
	count := uint64(1)
	for _, extent := range shape {
		hi, lo := bits.Mul64(count, uint64(extent))
		if hi != 0 || lo > math.MaxUint64/bytesPerElement {
			return 0, false
		}
		count = lo
	}
	return count, true
}

func checkShape(length int, shape []uint32) {
	if count, ok := elementCount(shape); !ok || count != uint64(length) {
		panic(fmt.Sprintf("component: %d values do not fill shape %s", length, dimsText(shape)))
	}
}

// shapeText writes an expected shape, e.g. "[N, 3]".
func shapeText(trailing []uint32) string {
	parts := []string{"N"}
	for _, extent := range trailing {
		parts = append(parts, fmt.Sprint(extent))
	}
	return "[" + strings.Join(parts, ", ") + "]"
}

// dimsText writes an actual shape, e.g. "[4, 3]".
func dimsText(shape []uint32) string {
	parts := make([]string, len(shape))
	for i, extent := range shape {
		parts[i] = fmt.Sprint(extent)
	}
	return "[" + strings.Join(parts, ", ") + "]"
}
