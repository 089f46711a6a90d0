// hammersley — Owen-scrambled Hammersley point sets
//
// A point set of a fixed size N = `sample_count`. Point j (0 ≤ j < N)
// has coordinate 0 in the j-th of N strata, [j/N, (j+1)/N), and
// coordinate d ≥ 1 the radical inverse of j in the d-th prime base
// (2, 3, 5, ...): with N = 2^m, dimensions 0 and 1 form a (0, m, 2)-net.
//
// Randomization keeps that structure. Coordinates d ≥ 1 are
// Owen-scrambled, seeded by (seed, dimension, block): base 2 with the
// same hash-based nested uniform scramble as sobol, other bases with
// nested random digit permutations. Coordinate 0 is Owen-scrambled in
// base 2 too when N is a power of two (j/N then has m binary digits);
// for other N it is jittered uniformly inside its own stratum, since
// permuting non-dyadic strata would pair them at random with the other
// coordinates and destroy the joint stratification. So in every base-b
// dimension the first b^k ≤ N points of a block fill the b^k intervals
// [i/b^k, (i+1)/b^k) once each, and the average over a whole block is an
// unbiased randomized QMC estimate. With N a power of two each point is
// also uniform on its own; otherwise coordinate 0 of point j stays in
// stratum j, so use whole blocks.
//
// Point i belongs to block i / N; every block of N consecutive indices is
// a freshly scrambled set. Dimensions past the 1024 tabulated primes
// reuse the bases cyclically, with their own scrambles.
//
// Deterministic and stateless: the same (index, dimension, seed) always
// gives the same number in [0, 1).
//
// Parameters: Hammersley::Parameters() below; powers of two for
// sample_count make the first two dimensions a net.
#include <bit>
#include <cstdint>

#include "sample_count.h"
#include "yarf/support/hash.h"
#include "yarf/support/owen.h"
#include "yarf/plugin.h"

namespace {

// Distinct salts so that the jitter and the scrambles never share a hash
// input with each other or with other samplers.
constexpr uint64_t kJitterSalt = 0x484a4954ull;     // "HJIT"
constexpr uint64_t kScrambleSalt = 0x48534352ull;   // "HSCR"

class Hammersley final : public yarf::Sampler {
 public:
  static yarf::ParameterSchema Parameters() { return {yarf::SampleCountParameter("points per set N")}; }

  explicit Hammersley(const yarf::Properties& props) : count_(yarf::ReadSampleCount(props, "hammersley")) {}

  float Sample(uint64_t index, uint32_t dimension, uint64_t seed) const override {
    const uint64_t block = index / count_;
    const uint32_t point = uint32_t(index % count_);
    const uint64_t scramble_seed = yarf::Hash(seed, dimension, block, kScrambleSalt);
    if (dimension == 0) {
      if (std::has_single_bit(count_)) {
        // j/N's binary digits: j in the top m bits.
        const int m = std::countr_zero(count_);
        const uint32_t bits = uint32_t(uint64_t(point) << (32 - m));
        return yarf::ToUnitFloat(yarf::NestedUniformScramble(bits, uint32_t(scramble_seed)));
      }
      const uint32_t jitter = uint32_t(yarf::Hash(seed, index, kJitterSalt) >> 32);
      return yarf::StratumFloat(point, count_, jitter);
    }
    const uint32_t base = yarf::kPrimes[(dimension - 1) % yarf::kPrimes.size()];
    return yarf::OwenScrambledRadicalInverse(point, base, scramble_seed);
  }

 private:
  uint32_t count_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Hammersley>(registrar, "hammersley", "1.0.0",
                             "Hammersley point sets with Owen scrambling");
}
