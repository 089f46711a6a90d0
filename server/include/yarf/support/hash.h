// Deterministic integer hashing for stateless samplers: a sample is a
// pure function of (seed, index, dimension, ...), so any thread can make
// any coordinate of any point, in any order, and get the same number.
#pragma once

#include <concepts>
#include <cstdint>

namespace yarf {

// The finaliser of splitmix64 (Steele, Lea & Flood 2014): a bijection of
// 64-bit integers in which every output bit depends on every input bit, so
// nearby inputs (consecutive indices) give unrelated outputs.
constexpr uint64_t MixBits(uint64_t v) {
  v ^= v >> 30;
  v *= 0xbf58476d1ce4e5b9ull;
  v ^= v >> 27;
  v *= 0x94d049bb133111ebull;
  v ^= v >> 31;
  return v;
}

// Hash's state before any value.
inline constexpr uint64_t kHashStart = 0x243f6a8885a308d3ull;

// `values` folded into a running hash state, each in turn: Hash(a, b, c)
// is HashOnto(Hash(a, b), c), so hashes sharing leading values can share
// their work.
template <std::integral... Values>
constexpr uint64_t HashOnto(uint64_t state, Values... values) {
  // Golden-ratio increment (as splitmix64's) keeps an all-zero input from
  // mapping to the fixed point MixBits(0) = 0.
  constexpr uint64_t kIncrement = 0x9e3779b97f4a7c15ull;
  ((state = MixBits(state + kIncrement + static_cast<uint64_t>(values))), ...);
  return state;
}

// One 64-bit hash of several integers; the order of the arguments matters.
// Each value is folded into the running state and the state re-mixed, so
// (a, b) and (b, a) hash differently.
template <std::integral... Values>
constexpr uint64_t Hash(Values... values) {
  return HashOnto(kHashStart, values...);
}

// A float in [0, 1) from 32 random bits. Only the top 24 bits are used:
// a float has 24 significant bits, and dropping the rest (instead of
// rounding) keeps the result strictly below 1 and keeps every dyadic
// interval [k/2^m, (k+1)/2^m), m ≤ 24, exactly where the bits put it.
constexpr float ToUnitFloat(uint32_t bits) {
  return static_cast<float>(bits >> 8) * 0x1p-24f;
}

}  // namespace yarf
