// pcg32 — O'Neill's permuted congruential generator, PCG-XSH-RR 64/32
//
// A 64-bit LCG (multiplier 6364136223846793005) whose state is not output
// directly: each 32-bit output is the old state's high bits xor-shifted
// down ("XSH") and then rotated by its top five bits ("RR"), which hides
// the LCG's weak low bits (O'Neill, "PCG: A family of simple fast
// space-efficient statistically good algorithms for random number
// generation", 2014). The number in [0, 1) is made from the output's top
// 24 bits.
//
// Seeds and streams as in the reference pcg32_srandom: `seed` is the
// initial state and `stream` selects the increment 2·stream + 1, so
// seed 42, stream 54 gives the reference demo's numbers. Only the low 63
// bits of the stream id select a stream (the increment must be odd):
// streams s and s + 2^63 coincide.
//
// A weakness kept from the reference seeding: with seed 0 the LCG states
// of streams s and t stay exact multiples of each other, by
// (2t+1)/(2s+1) mod 2^64, so small stream ids of seed 0 are slightly
// correlated (streams 0 and 1: r ≈ 0.025; 0 and 2: r ≈ 0.014). Any other
// seed breaks the relation. Use a nonzero seed, or xoshiro256starstar,
// when streams of one seed must be independent.
//
// Skipping `offset` outputs costs O(log offset): the LCG's n-step map is
// built by squaring (Brown 1994), as the reference pcg32_advance does.
//
// Deterministic and stateless between calls: the same (seed, stream,
// offset) always gives the same numbers.
//
// Parameters: none (Pcg32::Parameters() below).
#include <bit>
#include <cstdint>
#include <span>

#include "yarf/support/hash.h"
#include "yarf/plugin.h"

namespace {

constexpr uint64_t kMultiplier = 6364136223846793005ull;

struct Pcg32State {
  uint64_t state;
  uint64_t increment;

  // The output of the current state, then one LCG step.
  uint32_t Next() {
    const uint64_t old = state;
    state = old * kMultiplier + increment;
    const uint32_t shifted = uint32_t(((old >> 18) ^ old) >> 27);
    return std::rotr(shifted, int(old >> 59));
  }

  void Advance(uint64_t steps) {
    uint64_t total_multiplier = 1, total_increment = 0;
    uint64_t multiplier = kMultiplier, step_increment = increment;
    for (; steps > 0; steps >>= 1) {
      if (steps & 1) {
        total_multiplier *= multiplier;
        total_increment = total_increment * multiplier + step_increment;
      }
      step_increment *= multiplier + 1;
      multiplier *= multiplier;
    }
    state = total_multiplier * state + total_increment;
  }
};

// The reference seeding: one step from zero, add the seed, one more step.
Pcg32State Seeded(uint64_t seed, uint64_t stream) {
  Pcg32State pcg{0, (stream << 1) | 1u};
  pcg.Next();
  pcg.state += seed;
  pcg.Next();
  return pcg;
}

class Pcg32 final : public yarf::Generator {
 public:
  static yarf::ParameterSchema Parameters() { return {}; }

  explicit Pcg32(const yarf::Properties&) {}

  void Next(uint64_t seed, uint64_t stream, uint64_t offset, std::span<float> out) override {
    Pcg32State pcg = Seeded(seed, stream);
    pcg.Advance(offset);
    for (float& value : out) value = yarf::ToUnitFloat(pcg.Next());
  }
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Pcg32>(registrar, "pcg32", "1.0.0",
                        "O'Neill's PCG-XSH-RR 64/32 with stream selection and O(log n) advance");
}
