// halton — Owen-scrambled Halton sequence
//
// Coordinate d of point i is the radical inverse of i in the d-th prime
// base (2, 3, 5, 7, ...): the digits of i mirrored about the radix point.
// An infinite sequence, so any prefix is usable: in base b, any b^k
// consecutive points from a multiple of b^k fill the b^k intervals
// [j/b^k, (j+1)/b^k) once each.
//
// Randomization: each dimension is Owen-scrambled with its own seed,
// hash(seed, dimension) — every digit goes through a random permutation
// of {0..b-1} chosen by the digits before it (base 2 with the same
// hash-based nested uniform scramble as sobol). Nested permutations keep
// the stratification above, break the correlations between high
// dimensions of the plain Halton sequence (whose large bases make
// consecutive points march in lines), and make each point uniform over
// seeds, so averages over seeds give unbiased error estimates.
//
// Any number of dimensions: the first 1024 primes (up to 8161) are
// tabulated; beyond, the bases repeat cyclically with independent
// scrambles. Large bases stratify only at large counts: use the first
// dimensions for what matters most.
//
// Deterministic and stateless: the same (index, dimension, seed) always
// gives the same number in [0, 1).
//
// Parameters: none (Halton::Parameters() below).
#include <cstdint>

#include "yarf/support/hash.h"
#include "yarf/support/owen.h"
#include "yarf/plugin.h"

namespace {

// Keeps the scramble seeds apart from other samplers' hashes.
constexpr uint64_t kScrambleSalt = 0x48414c54ull;  // "HALT"

class Halton final : public yarf::Sampler {
 public:
  static yarf::ParameterSchema Parameters() { return {}; }

  explicit Halton(const yarf::Properties&) {}

  float Sample(uint64_t index, uint32_t dimension, uint64_t seed) const override {
    const uint32_t base = yarf::kPrimes[dimension % yarf::kPrimes.size()];
    return yarf::OwenScrambledRadicalInverse(index, base, yarf::Hash(seed, dimension, kScrambleSalt));
  }
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Halton>(registrar, "halton", "1.0.0",
                         "Halton sequence with per-dimension Owen scrambling");
}
