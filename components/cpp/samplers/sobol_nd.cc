// sobol_nd — the Sobol sequence in up to 21201 dimensions, Owen-scrambled
//
// Coordinate d of point i is the d-th dimension of the Sobol sequence
// with Joe & Kuo's direction numbers (new-joe-kuo-6.21201, chosen so that
// its 2-D projections are good nets): the XOR of dimension d's direction
// numbers over the set bits of i. Every 2^m consecutive points from a
// multiple of 2^m form a (t, m, s)-net in base 2, and each 1-D projection
// is a (0, m, 1)-net: the 2^m intervals [k/2^m, (k+1)/2^m) get one point
// each. Unlike `sobol`, which pairs 2-D blocks at random, all dimensions
// come from one sequence, so integrands whose variables interact in more
// than pairs are integrated at the Sobol rate too. Use sample counts that
// are powers of two.
//
// Randomization: each dimension is Owen-scrambled with its own seed from
// (seed, dimension), by the hash-based nested uniform scramble (Burley
// 2020, after Laine & Karras 2011). Owen scrambling keeps every
// elementary interval's count, so the nets stay nets, and makes each
// point uniform over seeds: means over seeds are unbiased, with error
// bars (the rqmc integrator's replicates).
//
// Bounds: indices below 2^32 (direction numbers of 32 bits) and
// dimensions below 21201 (all that Joe & Kuo tabulate, see
// sobol_directions.h);
// anything beyond is refused with an Error rather than repeating points.
// Renders keep `sobol` by default: it has no dimension bound (paths with
// Russian roulette have no length bound), and on the Cornell box at 64 spp
// its RMSE was 4% below this one's.
//
// Deterministic and stateless: the same (index, dimension, seed) always
// gives the same number in [0, 1).
//
// Parameters: SobolNd::Parameters() below.
#include <array>
#include <bit>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "sobol_directions.h"
#include "yarf/support/hash.h"
#include "yarf/support/owen.h"
#include "yarf/plugin.h"

namespace {

using yarf::sobol::kDimensions;

// Keeps the scramble seeds apart from other samplers' hashes.
constexpr uint64_t kScrambleSalt = 0x534f424f4cull;  // "SOBOL"
constexpr uint64_t kIndices = uint64_t(1) << 32;

using Directions = std::vector<std::array<uint32_t, 32>>;

// Column k of dimension j's generator matrix, top-aligned: v_k = m_k / 2^k
// for k ≤ s, then Sobol's recurrence from the primitive polynomial
// x^s + a_1 x^(s-1) + … + a_(s-1) x + 1:
//   v_k = a_1 v_(k-1) ⊕ … ⊕ a_(s-1) v_(k-s+1) ⊕ v_(k-s) ⊕ (v_(k-s) / 2^s).
Directions ExpandDirections() {
  Directions v(kDimensions);
  for (int k = 0; k < 32; ++k) v[0][k] = 1u << (31 - k);  // van der Corput
  for (uint32_t j = 1; j < kDimensions; ++j) {
    const yarf::sobol::Primitive& p = yarf::sobol::kPrimitives[j];
    const int s = std::bit_width(p.polynomial) - 1;
    const uint32_t a = (p.polynomial >> 1) & ((1u << (s - 1)) - 1);
    for (int k = 0; k < 32; ++k) {
      if (k < s) {
        v[j][k] = p.m[k] << (31 - k);
        continue;
      }
      uint32_t next = v[j][k - s] ^ (v[j][k - s] >> s);
      for (int i = 1; i < s; ++i)
        if ((a >> (s - 1 - i)) & 1) next ^= v[j][k - i];
      v[j][k] = next;
    }
  }
  return v;
}

// Every dimension's 32 direction numbers (2.7 MB), expanded once, on first
// use, and read-only after.
const Directions& AllDirections() {
  static const Directions directions = ExpandDirections();
  return directions;
}

// The unscrambled coordinate as 32 bits: a fraction of 2^32.
inline uint32_t SobolBits(const Directions& directions, uint32_t index, uint32_t dimension) {
  const std::array<uint32_t, 32>& v = directions[dimension];
  uint32_t bits = 0;
  for (; index != 0; index &= index - 1) bits ^= v[std::countr_zero(index)];
  return bits;
}

class SobolNd final : public yarf::Sampler {
 public:
  static yarf::ParameterSchema Parameters() {
    return {
        yarf::Parameter::Bool("scramble").Default(true).Doc("Owen-scramble; false: the plain sequence, for every seed"),
    };
  }

  explicit SobolNd(const yarf::Properties& props)
      : scramble_(props.Bool("scramble", true)), directions_(AllDirections()) {}

  float Sample(uint64_t index, uint32_t dimension, uint64_t seed) const override {
    CheckRange(index, 1, dimension + 1);
    return Coordinate(uint32_t(index), dimension, seed);
  }

  void Generate(uint64_t first, uint32_t count, uint32_t dimensions, uint64_t seed,
                std::span<float> out) const override {
    if (count == 0 || dimensions == 0) return;
    CheckRange(first, count, dimensions);
    for (uint32_t i = 0; i < count; ++i)
      for (uint32_t d = 0; d < dimensions; ++d)
        out[size_t(i) * dimensions + d] = Coordinate(uint32_t(first + i), d, seed);
  }

 private:
  // Points first .. first+count-1 with `dimensions` coordinates exist.
  static void CheckRange(uint64_t first, uint64_t count, uint64_t dimensions) {
    if (dimensions > kDimensions)
      throw yarf::Error("sobol_nd has " + std::to_string(kDimensions) +
                        " dimensions (Joe-Kuo direction numbers tabulated); " +
                        std::to_string(dimensions) + " were asked for");
    if (first >= kIndices || count > kIndices - first)
      throw yarf::Error("sobol_nd has 2^32 points; index " + std::to_string(first + count - 1) +
                        " was asked for");
  }

  float Coordinate(uint32_t index, uint32_t dimension, uint64_t seed) const {
    const uint32_t bits = SobolBits(directions_, index, dimension);
    if (!scramble_) return yarf::ToUnitFloat(bits);
    const uint32_t scramble_seed = uint32_t(yarf::Hash(kScrambleSalt, seed, dimension) >> 32);
    return yarf::ToUnitFloat(yarf::NestedUniformScramble(bits, scramble_seed));
  }

  bool scramble_;
  const Directions& directions_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<SobolNd>(registrar, "sobol_nd", "1.0.0",
                          "Sobol sequence (Joe-Kuo directions, 21201 dimensions) with hash-based "
                          "Owen scrambling");
}
