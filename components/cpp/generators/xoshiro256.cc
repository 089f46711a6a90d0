// xoshiro256starstar — Blackman & Vigna's xoshiro256**
//
// A 256-bit xor/shift/rotate linear engine with period 2^256 - 1 and the
// "**" scrambler (rotate the second word times 5 by 7, times 9) on its
// output (Blackman & Vigna, "Scrambled linear pseudorandom number
// generators", 2021). The number in [0, 1) is made from the output's top
// 24 bits.
//
// Seeds and streams: independent streams by seeding, as the authors
// recommend. The state is four successive outputs of splitmix64 started
// from yarf::Hash(seed, stream), i.e. word i is
// MixBits(Hash(seed, stream) + (i + 1)·0x9e3779b97f4a7c15); it is never
// all zero, and distinct (seed, stream) pairs start at unrelated points
// of the one 2^256 - 1 cycle, which no realistic run can make overlap.
//
// Skipping `offset` outputs: short skips by stepping; longer ones in
// O(log offset) by polynomial jump-ahead. The engine is a linear map M
// on 256-bit vectors over GF(2) with characteristic polynomial P, so
// M^n = (x^n mod P)(M): x^n mod P is built by squaring, and applying a
// polynomial of degree < 256 to the state takes 256 steps (the same way
// the authors' jump() skips 2^128). P itself is recovered at compile time
// from the engine by the Berlekamp–Massey algorithm, and checked there by
// rebuilding the authors' jump polynomial for 2^128 steps.
//
// Deterministic and stateless between calls: the same (seed, stream,
// offset) always gives the same numbers.
//
// Parameters: none (Xoshiro256StarStar::Parameters() below).
#include <array>
#include <bit>
#include <cstdint>
#include <span>

#include "yarf/support/hash.h"
#include "yarf/plugin.h"

namespace {

using State = std::array<uint64_t, 4>;

// One step of the linear engine (the scrambler is applied on output).
constexpr void Step(State& s) {
  const uint64_t t = s[1] << 17;
  s[2] ^= s[0];
  s[3] ^= s[1];
  s[1] ^= s[2];
  s[0] ^= s[3];
  s[2] ^= t;
  s[3] = std::rotl(s[3], 45);
}

constexpr uint64_t StarStar(const State& s) { return std::rotl(s[1] * 5, 7) * 9; }

// Polynomials over GF(2): bit k of word k/64 is the coefficient of x^k.
template <size_t Words>
using Poly = std::array<uint64_t, Words>;
// Residues modulo P (degree < 256); P itself is x^256 + its low part.
using Residue = Poly<4>;

template <size_t Words>
constexpr bool Bit(const Poly<Words>& p, size_t k) {
  return (p[k / 64] >> (k % 64)) & 1;
}

template <size_t Words>
constexpr Poly<Words> ShiftUp(const Poly<Words>& p, size_t shift) {
  Poly<Words> out{};
  for (size_t k = 0; k + shift < 64 * Words; ++k)
    if (Bit(p, k)) out[(k + shift) / 64] |= 1ull << ((k + shift) % 64);
  return out;
}

// Berlekamp–Massey on the low bit of word 0 over 512 steps: the shortest
// linear recurrence of that bit sequence. The engine's characteristic
// polynomial is primitive (its period is 2^256 - 1), so any nonzero
// sequence it makes has exactly that polynomial as its minimal one.
struct Recurrence {
  Residue low;    // P's coefficients below x^degree
  size_t degree;  // 256 when the recurrence is the engine's
};

constexpr Recurrence CharacteristicPolynomial() {
  constexpr size_t kBits = 512;
  std::array<bool, kBits> sequence{};
  State s{1, 2, 3, 4};
  for (size_t n = 0; n < kBits; ++n) {
    sequence[n] = s[0] & 1;
    Step(s);
  }
  // Connection polynomials: c(x) = 1 + c_1 x + ... + c_L x^L means
  // sequence[n] = sum of c_i sequence[n - i].
  Poly<5> c{1}, previous{1};
  size_t length = 0, shift = 1;
  for (size_t n = 0; n < kBits; ++n) {
    bool discrepancy = sequence[n];
    for (size_t i = 1; i <= length; ++i) discrepancy ^= Bit(c, i) && sequence[n - i];
    if (!discrepancy) {
      ++shift;
      continue;
    }
    const Poly<5> correction = ShiftUp(previous, shift);
    if (2 * length <= n) {
      const Poly<5> saved = c;
      for (size_t w = 0; w < 5; ++w) c[w] ^= correction[w];
      length = n + 1 - length;
      previous = saved;
      shift = 1;
    } else {
      for (size_t w = 0; w < 5; ++w) c[w] ^= correction[w];
      ++shift;
    }
  }
  // The characteristic polynomial is the reciprocal x^L c(1/x).
  Recurrence p{{}, length};
  for (size_t i = 1; i <= length && i <= 256; ++i)
    if (Bit(c, i)) p.low[(length - i) / 64] |= 1ull << ((length - i) % 64);
  return p;
}

constexpr Recurrence kRecurrence = CharacteristicPolynomial();
static_assert(kRecurrence.degree == 256, "the engine's recurrence must have the state's size");
constexpr Residue kCharacteristic = kRecurrence.low;

// r·x mod P.
constexpr Residue TimesX(Residue r) {
  const bool carry = r[3] >> 63;
  for (size_t w = 3; w > 0; --w) r[w] = (r[w] << 1) | (r[w - 1] >> 63);
  r[0] <<= 1;
  if (carry)
    for (size_t w = 0; w < 4; ++w) r[w] ^= kCharacteristic[w];
  return r;
}

// a·b mod P, by Horner's rule over the coefficients of b from the top.
constexpr Residue MultiplyMod(const Residue& a, const Residue& b) {
  Residue r{};
  for (size_t k = 256; k-- > 0;) {
    r = TimesX(r);
    if (Bit(b, k))
      for (size_t w = 0; w < 4; ++w) r[w] ^= a[w];
  }
  return r;
}

// x^n mod P: square at every bit of n, multiply by x at the set ones.
constexpr Residue PowerOfX(uint64_t n) {
  Residue r{1};
  for (int bit = 63 - std::countl_zero(n); bit >= 0; --bit) {
    r = MultiplyMod(r, r);
    if ((n >> bit) & 1) r = TimesX(r);
  }
  return r;
}

// x^(2^k) mod P, by k squarings.
constexpr Residue PowerOfXToPowerOfTwo(int k) {
  Residue r{2};
  for (int i = 0; i < k; ++i) r = MultiplyMod(r, r);
  return r;
}
// The authors' jump() polynomial for 2^128 steps, from their reference
// code: recovering it checks P and the arithmetic above.
static_assert(PowerOfXToPowerOfTwo(128) == Residue{0x180ec6d33cfd0abaull, 0xd5a61266f0c9392cull,
                                                   0xa9582618e03fc9aaull, 0x39abdc4529b1661cull});

// (sum of r_k x^k)(M) applied to s: the sum of r_k M^k s.
constexpr State Apply(const Residue& r, State s) {
  State out{};
  for (size_t k = 0; k < 256; ++k) {
    if (Bit(r, k))
      for (size_t w = 0; w < 4; ++w) out[w] ^= s[w];
    Step(s);
  }
  return out;
}

// Below this, stepping is cheaper than building x^offset mod P.
constexpr uint64_t kJumpThreshold = 1u << 16;

constexpr State Advance(State s, uint64_t steps) {
  if (steps >= kJumpThreshold) return Apply(PowerOfX(steps), s);
  for (uint64_t k = 0; k < steps; ++k) Step(s);
  return s;
}

constexpr State Seeded(uint64_t seed, uint64_t stream) {
  constexpr uint64_t kGolden = 0x9e3779b97f4a7c15ull;
  const uint64_t start = yarf::Hash(seed, stream);
  State s{};
  for (size_t w = 0; w < 4; ++w) s[w] = yarf::MixBits(start + (w + 1) * kGolden);
  return s;
}

class Xoshiro256StarStar final : public yarf::Generator {
 public:
  static yarf::ParameterSchema Parameters() { return {}; }

  explicit Xoshiro256StarStar(const yarf::Properties&) {}

  void Next(uint64_t seed, uint64_t stream, uint64_t offset, std::span<float> out) override {
    State s = Advance(Seeded(seed, stream), offset);
    for (float& value : out) {
      value = yarf::ToUnitFloat(uint32_t(StarStar(s) >> 32));
      Step(s);
    }
  }
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Xoshiro256StarStar>(registrar, "xoshiro256starstar", "1.0.0",
                                     "Blackman & Vigna's xoshiro256** seeded by splitmix64, "
                                     "O(log n) polynomial jump-ahead");
}
