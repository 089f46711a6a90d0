// Randomization of stratified and low-discrepancy point sets, shared by
// the sampler plugins: Owen scrambling in base 2 (hash-based) and in any
// prime base, random permutations of strata, and placing a float exactly
// inside a stratum. Everything is a pure function of its arguments, so
// samplers built on it stay stateless.
#pragma once

#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "yarf/support/hash.h"

namespace yarf {

// Byte swap (one instruction), then the bits within each byte.
constexpr uint32_t ReverseBits(uint32_t v) {
  v = __builtin_bswap32(v);
  v = ((v >> 4) & 0x0f0f0f0fu) | ((v & 0x0f0f0f0fu) << 4);
  v = ((v >> 2) & 0x33333333u) | ((v & 0x33333333u) << 2);
  return ((v >> 1) & 0x55555555u) | ((v & 0x55555555u) << 1);
}

// Burley's nested uniform scramble (2020, after Laine & Karras 2011): in
// bit-reversed order, each step (add, multiply by an odd constant, xor
// with a multiple by an even constant) changes a bit only as a function
// of itself and less significant bits. Read back in normal order, every
// digit is flipped as a function of the digits above it: an Owen
// scramble, which maps each elementary interval onto one of the same
// shape and so keeps (0, m, 2)-nets nets.
// The scramble on bit-reversed values: each bit depends on the lower ones.
constexpr uint32_t LaineKarrasPermutation(uint32_t v, uint32_t seed) {
  v ^= v * 0x3d20adeau;
  v += seed;
  v *= (seed >> 16) | 1u;
  v ^= v * 0x05526c56u;
  v ^= v * 0x53a22864u;
  return v;
}

constexpr uint32_t NestedUniformScramble(uint32_t v, uint32_t seed) {
  return ReverseBits(LaineKarrasPermutation(ReverseBits(v), seed));
}

// Element `i` of a pseudo-random permutation of {0, ..., n-1} chosen by
// `seed`, which must be well-mixed bits (a hash), without building the
// whole permutation. Requires i < n, n ≥ 1.
// Small n (digits of small bases, where a biased permutation would show
// as a biased coordinate): a forward Fisher–Yates shuffle whose draws are
// taken from the seed one after another (multiply by the range, keep the
// high part as the draw and the low part for the next one; 16! < 2^45,
// so 64 bits suffice). Position i is final after step i, so π(i) costs
// i + 1 draws. Larger n: a Feistel network on the k bits of n - 1 (every
// round xors one half with a hash of the other, so each round, and the
// whole, is a bijection of [0, 2^k)), iterated until it lands below n
// ("cycle walking"), which restricts it to a bijection of [0, n) in fewer
// than two passes on average. Eight rounds, not the four of the
// Luby–Rackoff bound: on domains of a few bits four rounds leave pairs
// (π(a), π(b)) visibly non-uniform; eight pass a χ² test from n = 17 up.
constexpr uint32_t RandomPermutation(uint32_t i, uint32_t n, uint64_t seed) {
  constexpr uint64_t kGolden = 0x9e3779b97f4a7c15ull;
  constexpr uint32_t kShuffled = 16;
  constexpr uint64_t kRounds = 8;
  if (n <= kShuffled) {
    // The arrangement as 16 nibbles in a register: nibble k holds order[k].
    uint64_t order = 0xfedcba9876543210ull;
    uint64_t draws = seed;
    for (uint32_t k = 0; k <= i; ++k) {
      const unsigned __int128 product = (unsigned __int128)draws * (n - k);
      const uint32_t pick = k + uint32_t(product >> 64);
      draws = uint64_t(product);
      const uint64_t differ = ((order >> (4 * k)) ^ (order >> (4 * pick))) & 0xf;
      order ^= (differ << (4 * k)) | (differ << (4 * pick));
    }
    return uint32_t(order >> (4 * i)) & 0xf;
  }
  const int bits = std::bit_width(n - 1);
  const int right_bits = (bits + 1) / 2, left_bits = bits - right_bits;
  const uint32_t right_mask = (1u << right_bits) - 1, left_mask = (1u << left_bits) - 1;
  // Round r's function of the other half: distinct for every (r, half).
  auto feistel = [seed](uint64_t r, uint32_t half) {
    return uint32_t(MixBits(seed + ((r << 32) | half) * kGolden) >> 32);
  };
  do {
    uint32_t left = i >> right_bits, right = i & right_mask;
    for (uint64_t r = 0; r < kRounds; r += 2) {
      left ^= feistel(r, right) & left_mask;
      right ^= feistel(r + 1, left) & right_mask;
    }
    i = (left << right_bits) | right;
  } while (i >= n);
  return i;
}

// A float in [stratum/count, (stratum+1)/count), at `bits` (32 random
// bits, the top 24 used) of the way across. Rounding to float can carry
// a value over a stratum's edge; the result is stepped back inside, so
// that floor(double(x) * count) == stratum holds exactly. A stratum at
// least one float spacing wide always holds a float: count ≤ 2^24.
inline float StratumFloat(uint32_t stratum, uint32_t count, uint32_t bits) {
  const double jitter = double(bits >> 8) * 0x1p-24;
  float x = float((double(stratum) + jitter) / double(count));
  // Both products are exact: 24-bit significand times count ≤ 2^24.
  if (double(x) * count >= double(stratum) + 1) x = std::nextafter(x, 0.0f);
  if (double(x) * count < double(stratum)) x = std::nextafter(x, 1.0f);
  return x;
}

// The first 1024 primes (up to 8161): the bases of Halton and Hammersley
// coordinates.
template <size_t Count>
constexpr std::array<uint32_t, Count> FirstPrimes() {
  std::array<uint32_t, Count> primes{};
  size_t found = 0;
  for (uint32_t candidate = 2; found < Count; ++candidate) {
    bool prime = true;
    for (size_t k = 0; k < found && primes[k] * primes[k] <= candidate; ++k)
      if (candidate % primes[k] == 0) {
        prime = false;
        break;
      }
    if (prime) primes[found++] = candidate;
  }
  return primes;
}
inline constexpr std::array<uint32_t, 1024> kPrimes = FirstPrimes<1024>();

// The radical inverse of `index` in `base` (its digits mirrored about the
// radix point), Owen-scrambled: output digit k is digit k of the index
// put through a random permutation of {0..base-1} chosen by hash of the
// seed and of the k digits below it. Nested permutations map each
// elementary interval [j/b^k, (j+1)/b^k) onto one of the same size, so
// any b^k consecutive indices from a multiple of b^k still put one point
// in each, and each point is uniform on [0, 1) over seeds. Digits are
// taken while base^k ≤ 2^24, so that every k-digit interval holds a
// float; those past that resolution are scrambled all at once: a uniform
// offset hashed from the whole index. Base 2 takes the hash-based bitwise
// scramble. `seed` must be well-mixed bits (a hash).
inline float OwenScrambledRadicalInverse(uint64_t index, uint32_t base, uint64_t seed) {
  constexpr uint64_t kGolden = 0x9e3779b97f4a7c15ull;
  if (base == 2)
    return ToUnitFloat(NestedUniformScramble(ReverseBits(uint32_t(index)), uint32_t(MixBits(seed))));
  uint64_t rest = index;
  uint32_t scale = 1;   // base^k
  uint32_t prefix = 0;  // index mod base^k: the digits below digit k
  uint32_t value = 0;   // the scrambled digits, as an integer over base^k
  while (uint64_t(scale) * base <= (1u << 24)) {
    // Digits past the index's last nonzero one are 0: no division.
    uint32_t digit = 0;
    if (rest != 0) {
      digit = uint32_t(rest % base);
      rest /= base;
    }
    // scale + prefix names (k, lower digits) uniquely: prefix < scale.
    const uint64_t digit_seed = MixBits(seed + (scale + prefix) * kGolden);
    value = value * base + RandomPermutation(digit, base, digit_seed);
    prefix += digit * scale;
    scale *= base;
  }
  return StratumFloat(value, scale, uint32_t(Hash(seed, index) >> 32));
}

}  // namespace yarf
