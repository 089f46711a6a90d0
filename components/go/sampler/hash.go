package sampler

// Deterministic integer hashing for stateless samplers, bit for bit as
// yarfd's (server/include/yarf/support/hash.h), so that a Go sampler and a C++
// one agree on the same request.

// mixBits is the finaliser of splitmix64 (Steele, Lea & Flood 2014): a
// bijection in which every output bit depends on every input bit.
func mixBits(v uint64) uint64 {
	v ^= v >> 30
	v *= 0xbf58476d1ce4e5b9
	v ^= v >> 27
	v *= 0x94d049bb133111eb
	v ^= v >> 31
	return v
}

// hash folds the values, in order, into one 64-bit hash.
func hash(values ...uint64) uint64 {
	// The golden-ratio increment keeps an all-zero input off MixBits'
	// fixed point 0.
	const increment = 0x9e3779b97f4a7c15
	state := uint64(0x243f6a8885a308d3)
	for _, v := range values {
		state = mixBits(state + increment + v)
	}
	return state
}

// unitFloat is a float in [0, 1) from the top 24 of 32 random bits: a
// float32 has 24 significant bits, and dropping the rest keeps the result
// below 1.
func unitFloat(bits uint32) float32 {
	return float32(bits>>8) * 0x1p-24
}
