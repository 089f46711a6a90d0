// lcg — 64-bit linear congruential generator
//
// The generator of the paper's example: x' = a·x + c mod 2^64 with
// Knuth's MMIX constants a = 6364136223846793005 and
// c = 1442695040888963407. Each output is the state after one step; its
// top 24 bits make the number in [0, 1) (the low bits of an LCG modulo a
// power of two have short periods, the high ones do not).
//
// Seeds and streams: the initial state is yarf::Hash(seed), so nearby
// seeds start far apart; stream s steps with the increment
// c xor (MixBits(s) << 1), an odd number, so every stream has the full
// period 2^64 and stream 0 is the plain MMIX generator. A different
// increment is a different sequence, not a shifted copy of the same one.
//
// Skipping `offset` outputs costs O(log offset): n steps of an LCG are
// one affine map x -> A·x + C, and Brown's method ("Random number
// generation with arbitrary strides", 1994) builds A and C by squaring.
//
// Deterministic and stateless between calls: the same (seed, stream,
// offset) always gives the same numbers.
//
// Parameters: none (Lcg::Parameters() below).
#include <cstdint>
#include <span>

#include "yarf/support/hash.h"
#include "yarf/plugin.h"

namespace {

constexpr uint64_t kMultiplier = 6364136223846793005ull;
constexpr uint64_t kIncrement = 1442695040888963407ull;

// The state after `steps` steps from `state` with increment `increment`.
constexpr uint64_t Advance(uint64_t state, uint64_t steps, uint64_t increment) {
  // (A, C) accumulates the map of the steps taken so far; (a, c) is the
  // map of 2^k steps, squared at each bit of `steps`.
  uint64_t total_multiplier = 1, total_increment = 0;
  uint64_t multiplier = kMultiplier;
  for (; steps > 0; steps >>= 1) {
    if (steps & 1) {
      total_multiplier *= multiplier;
      total_increment = total_increment * multiplier + increment;
    }
    // Two applications of x -> a·x + c: x -> a²·x + (a + 1)·c.
    increment *= multiplier + 1;
    multiplier *= multiplier;
  }
  return total_multiplier * state + total_increment;
}

class Lcg final : public yarf::Generator {
 public:
  static yarf::ParameterSchema Parameters() { return {}; }

  explicit Lcg(const yarf::Properties&) {}

  void Next(uint64_t seed, uint64_t stream, uint64_t offset, std::span<float> out) override {
    const uint64_t increment = kIncrement ^ (yarf::MixBits(stream) << 1);
    uint64_t state = Advance(yarf::Hash(seed), offset, increment);
    for (float& value : out) {
      state = state * kMultiplier + increment;
      value = yarf::ToUnitFloat(uint32_t(state >> 32));
    }
  }
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Lcg>(registrar, "lcg", "1.0.0",
                      "64-bit linear congruential generator (MMIX constants), O(log n) skip-ahead");
}
