// Package sampler holds point sets (yarf.v1.Sampler) written in Go.
package sampler

import "yarf.dev/components/go/component"

// IndependentClass is go_independent: independent uniform numbers, the
// same as yarfd's "independent" sampler gives for the same request.
//
// Parameters: none.
var IndependentClass = component.NewClass("go_independent", "1.0.0",
	"Independent uniform random numbers (stateless hash)", NewIndependent)

var _ component.Sampler = (*Independent)(nil)

// Independent makes every coordinate of every point an independent
// uniform number in [0, 1): a hash of (seed, index, dimension). It keeps
// no state, so any coordinate can be made in any order, and the same
// request always gives the same points.
type Independent struct{}

// NewIndependent makes a go_independent; it reads no property.
func NewIndependent(*component.Properties) (*Independent, error) { return &Independent{}, nil }

func (*Independent) Generate(firstIndex uint64, count, dimensions uint32, seed uint64, points []float32) error {
	for i := range uint64(count) {
		row := points[i*uint64(dimensions) : (i+1)*uint64(dimensions)]
		for d := range row {
			// The high half of the hash: its best-mixed bits.
			row[d] = unitFloat(uint32(hash(seed, firstIndex+i, uint64(d)) >> 32))
		}
	}
	return nil
}
