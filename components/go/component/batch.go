package component

import (
	"fmt"

	yarfv1 "yarf.dev/components/go/gen/yarfv1"
)

// Batch decodes the arrays of one batched call, which must all have the
// same number of rows: the first array decoded sets it. The first error is
// kept and later calls do nothing, so a handler decodes every input and
// checks Err once.
type Batch struct {
	rows    int
	decoded bool
	err     error
}

// Float32 decodes a FLOAT32 array of shape [N, trailing...] of this batch.
func (b *Batch) Float32(array *yarfv1.Array, what string, trailing ...uint32) []float32 {
	if b.err != nil {
		return nil
	}
	values, rows, err := DecodeFloat32(array, what, trailing...)
	if err == nil && b.decoded && rows != b.rows {
		err = fmt.Errorf("%s has %d rows, the batch %d", what, rows, b.rows)
	}
	if err != nil {
		b.err = err
		return nil
	}
	b.rows, b.decoded = rows, true
	return values
}

// Rows is the batch size N.
func (b *Batch) Rows() int { return b.rows }

// Err is the first decoding error, or nil.
func (b *Batch) Err() error { return b.err }
