package component_test

import (
	"math"
	"slices"
	"strings"
	"testing"

	"yarf.dev/components/go/component"
	yarfv1 "yarf.dev/components/go/gen/yarfv1"
)

func TestFloat32RoundTrip(t *testing.T) {
	values := []float32{0, 1, -2.5, math.MaxFloat32, math.SmallestNonzeroFloat32, float32(math.Inf(-1))}
	array := component.EncodeFloat32(values, 2, 3)
	if array.GetDtype() != yarfv1.Array_FLOAT32 || !slices.Equal(array.GetShape(), []uint32{2, 3}) {
		t.Fatalf("encoded as %v %v", array.GetDtype(), array.GetShape())
	}
	decoded, rows, err := component.DecodeFloat32(array, "x", 3)
	if err != nil {
		t.Fatal(err)
	}
	if rows != 2 || !slices.Equal(decoded, values) {
		t.Errorf("decoded %d rows %v, want 2 rows %v", rows, decoded, values)
	}
}

func TestFloat32IsLittleEndian(t *testing.T) {
	array := component.EncodeFloat32([]float32{1}, 1)
	// 1.0f is 0x3f800000.
	if want := []byte{0x00, 0x00, 0x80, 0x3f}; !slices.Equal(array.GetData(), want) {
		t.Errorf("bytes %x, want %x", array.GetData(), want)
	}
}

func TestUint32RoundTrip(t *testing.T) {
	values := []uint32{0, 1, 9, math.MaxUint32}
	decoded, rows, err := component.DecodeUint32(component.EncodeUint32(values, 4), "flags")
	if err != nil {
		t.Fatal(err)
	}
	if rows != 4 || !slices.Equal(decoded, values) {
		t.Errorf("decoded %d rows %v, want 4 rows %v", rows, decoded, values)
	}
}

func TestEmptyBatchDecodes(t *testing.T) {
	decoded, rows, err := component.DecodeFloat32(component.EncodeFloat32(nil, 0, 3), "wi", 3)
	if err != nil || rows != 0 || len(decoded) != 0 {
		t.Errorf("got %v, %d rows, %v", decoded, rows, err)
	}
}

func TestDecodeRejectsBadArrays(t *testing.T) {
	good := component.EncodeFloat32(make([]float32, 6), 2, 3)
	tests := []struct {
		name  string
		array *yarfv1.Array
		want  string
	}{
		{"unset", nil, "wi: expected a FLOAT32 array"},
		{"dtype", &yarfv1.Array{Dtype: yarfv1.Array_UINT32, Shape: good.Shape, Data: good.Data},
			"wi: expected a FLOAT32 array, got UINT32"},
		{"rank", &yarfv1.Array{Dtype: yarfv1.Array_FLOAT32, Shape: []uint32{6}, Data: good.Data},
			"wi: expected shape [N, 3], got [6]"},
		{"trailing", &yarfv1.Array{Dtype: yarfv1.Array_FLOAT32, Shape: []uint32{3, 2}, Data: good.Data},
			"wi: dimension 1 must be 3, got 2"},
		{"short", &yarfv1.Array{Dtype: yarfv1.Array_FLOAT32, Shape: good.Shape, Data: good.Data[:23]},
			"wi: 23 bytes for shape [2, 3] (24 bytes expected)"},
		{"long", &yarfv1.Array{Dtype: yarfv1.Array_FLOAT32, Shape: good.Shape, Data: append(good.Data, 0, 0, 0, 0)},
			"wi: 28 bytes for shape [2, 3] (24 bytes expected)"},
		{"huge", &yarfv1.Array{Dtype: yarfv1.Array_FLOAT32, Shape: []uint32{math.MaxUint32, 3}},
			"wi: 0 bytes for shape [4294967295, 3]"},
	}
	for _, test := range tests {
		t.Run(test.name, func(t *testing.T) {
			_, _, err := component.DecodeFloat32(test.array, "wi", 3)
			if err == nil || !strings.HasPrefix(err.Error(), test.want) {
				t.Errorf("error %v, want %q", err, test.want)
			}
		})
	}
}

func TestDecodeRejectsOverflowingShape(t *testing.T) {
	array := &yarfv1.Array{Dtype: yarfv1.Array_UINT32, Shape: []uint32{math.MaxUint32, math.MaxUint32, math.MaxUint32}}
	_, _, err := component.DecodeUint32(array, "x", math.MaxUint32, math.MaxUint32)
	if err == nil || err.Error() != "x: shape [4294967295, 4294967295, 4294967295] is too large" {
		t.Errorf("error %v", err)
	}
}

func TestEncodePanicsOnShapeMismatch(t *testing.T) {
	defer func() {
		if recover() == nil {
			t.Error("no panic for 5 values in shape [2, 3]")
		}
	}()
	component.EncodeFloat32(make([]float32, 5), 2, 3)
}

func TestBatchRequiresEqualRows(t *testing.T) {
	var batch component.Batch
	batch.Float32(component.EncodeFloat32(make([]float32, 6), 2, 3), "wi", 3)
	batch.Float32(component.EncodeFloat32(make([]float32, 6), 3, 2), "uv", 2)
	batch.Float32(nil, "uniform", 3) // after an error: ignored
	if err := batch.Err(); err == nil || err.Error() != "uv has 3 rows, the batch 2" {
		t.Errorf("error %v", err)
	}
}

func TestBatchRows(t *testing.T) {
	var batch component.Batch
	wi := batch.Float32(component.EncodeFloat32(make([]float32, 12), 4, 3), "wi", 3)
	uv := batch.Float32(component.EncodeFloat32(make([]float32, 8), 4, 2), "uv", 2)
	if batch.Err() != nil || batch.Rows() != 4 || len(wi) != 12 || len(uv) != 8 {
		t.Errorf("rows %d, err %v, lengths %d %d", batch.Rows(), batch.Err(), len(wi), len(uv))
	}
}
