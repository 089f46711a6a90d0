// sobol — padded, scrambled Sobol points
//
// Low-discrepancy points built from 2-D blocks: coordinates (2k, 2k+1)
// are the first two dimensions of the Sobol sequence, which together form
// a (0, 2)-sequence in base 2: every 2^m consecutive points from an index
// that is a multiple of 2^m put exactly one point in each elementary
// interval of area 2^-m. Blocks are decorrelated from each other by
// shuffling the point order per block and scrambling every coordinate
// (the "padded" construction of pbrt-v4, with Burley's 2020 hash-based
// Owen scrambling). Use sample counts that are powers of two.
//
// Deterministic and stateless: the same (index, dimension, seed) always
// gives the same number in [0, 1).
//
// Parameters: none.
#include <array>
#include <cstdint>
#include <span>

#include "yarf/hash.h"
#include "yarf/owen.h"
#include "yarf/plugin.h"

namespace {

// Distinct salts so that the index shuffle and the value scramble of the
// same block never share a seed.
constexpr uint64_t kShuffleSalt = 0x5348554646ull;   // "SHUFF"
constexpr uint64_t kScrambleSalt = 0x534352414dull;  // "SCRAM"

// Direction numbers of Sobol's second dimension: column i of its
// generator matrix, the binary Pascal triangle read from the top bit.
constexpr std::array<uint32_t, 32> kSecondDimension = [] {
  std::array<uint32_t, 32> v{};
  v[0] = 1u << 31;
  for (int i = 1; i < 32; ++i) v[i] = v[i - 1] ^ (v[i - 1] >> 1);
  return v;
}();

// The second dimension's generator matrix applied a byte at a time: entry
// [k][b] is the XOR of the direction numbers of the set bits of byte k.
constexpr std::array<std::array<uint32_t, 256>, 4> kSecondDimensionBytes = [] {
  std::array<std::array<uint32_t, 256>, 4> table{};
  for (int k = 0; k < 4; ++k)
    for (int b = 0; b < 256; ++b)
      for (int bit = 0; bit < 8; ++bit)
        if (b & (1 << bit)) table[k][b] ^= kSecondDimension[8 * k + bit];
  return table;
}();

constexpr uint32_t SobolSecond(uint32_t index) {
  return kSecondDimensionBytes[0][index & 0xff] ^ kSecondDimensionBytes[1][(index >> 8) & 0xff] ^
         kSecondDimensionBytes[2][(index >> 16) & 0xff] ^ kSecondDimensionBytes[3][index >> 24];
}

// Per-dimension and per-pair salts, computed at compile time so that a
// coordinate costs one mixing round per seed.
constexpr uint32_t kCachedSeeds = 256;
constexpr uint64_t kGolden = 0x9e3779b97f4a7c15ull;
constexpr std::array<uint64_t, kCachedSeeds> Salts(uint64_t salt) {
  std::array<uint64_t, kCachedSeeds> salts{};
  for (uint32_t d = 0; d < kCachedSeeds; ++d) salts[d] = yarf::MixBits(salt + d * kGolden);
  return salts;
}
constexpr std::array<uint64_t, kCachedSeeds> kScrambleSeeds = Salts(kScrambleSalt);
constexpr std::array<uint64_t, kCachedSeeds> kShuffleSeeds = Salts(kShuffleSalt);

// Point `index` of block `block` (dimensions 2·block, 2·block + 1) for
// `seed`, its index bits reversed and shuffled. Owen-scrambling the index
// permutes it within every aligned run of 2^m indices, and an aligned run
// of Sobol points is a (0, m, 2)-net, so any power-of-two prefix stays
// stratified. Indices past 2^32 pick another shuffle rather than wrapping
// onto the same points.
inline uint32_t ShuffledReversedIndex(uint64_t index, uint32_t block, uint64_t seed) {
  const uint32_t shuffle_seed =
      uint32_t(yarf::MixBits(seed ^ kShuffleSeeds[block % kCachedSeeds] ^ ((index >> 32) * kGolden))) +
      block / kCachedSeeds;
  return yarf::LaineKarrasPermutation(yarf::ReverseBits(uint32_t(index)), shuffle_seed);
}

// Coordinate `dimension` from its block's shuffled index: Sobol's first
// dimension is the van der Corput sequence, the bit reversal of the index,
// so the reversals around the scrambles cancel; then the coordinate's own
// scramble.
inline float Coordinate(uint32_t reversed_shuffled, uint32_t dimension, uint64_t seed) {
  const uint32_t bits =
      dimension % 2 == 0 ? reversed_shuffled : SobolSecond(yarf::ReverseBits(reversed_shuffled));
  const uint32_t scramble_seed =
      uint32_t(yarf::MixBits(seed ^ kScrambleSeeds[dimension % kCachedSeeds]) + (dimension / kCachedSeeds));
  return yarf::ToUnitFloat(yarf::NestedUniformScramble(bits, scramble_seed));
}

class Sobol final : public yarf::Sampler {
 public:
  explicit Sobol(const yarf::Properties&) {}

  float Sample(uint64_t index, uint32_t dimension, uint64_t seed) const override {
    return Coordinate(ShuffledReversedIndex(index, dimension / 2, seed), dimension, seed);
  }

  // Both coordinates of a block share the index's shuffle.
  void SamplePairs(std::span<const uint64_t> indices, std::span<const uint64_t> seeds, uint32_t pair,
                   std::span<float> out) const override {
    for (size_t k = 0; k < indices.size(); ++k) {
      const uint32_t shuffled = ShuffledReversedIndex(indices[k], pair, seeds[k]);
      out[2 * k] = Coordinate(shuffled, 2 * pair, seeds[k]);
      out[2 * k + 1] = Coordinate(shuffled, 2 * pair + 1, seeds[k]);
    }
  }
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Sobol>(registrar, "sobol", "1.0.0",
                        "Padded 2-D Sobol points with hash-based Owen scrambling");
}
