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
// Parameters: none (Sobol::Parameters() below).
//
// zsobol — pbrt-v4's ZSobol (Ahmed & Wonka 2020)
//
// One Sobol sequence for the whole film instead of one per pixel: pixel
// (x, y)'s samples are the consecutive points from its Morton index times
// the samples per pixel (rounded up to a power of two), and for every pair
// of dimensions the index's base-4 digits are permuted, each by a random
// permutation of four chosen by the digits above it. An aligned run of
// indices stays an aligned run, so each pixel's samples are still a
// (0, m, 2)-net in every pair of dimensions, and so are those of every
// aligned 2^k × 2^k block of pixels: neighbouring pixels' errors are
// spread apart (blue noise) rather than alike. The seed scrambles every
// coordinate as in sobol. Films up to 2^16 pixels a side; a film and
// sample count of more than 2^32 points in all are refused.
//
// Parameters: none (ZSobol::Parameters() below).
#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <string>
#include <span>
#include <vector>

#include "yarf/error.h"
#include "yarf/support/hash.h"
#include "yarf/support/owen.h"
#include "yarf/plugin.h"

namespace {

// Distinct salts so that the index shuffle and the value scramble of the
// same block never share a seed.
constexpr uint64_t kShuffleSalt = 0x5348554646ull;   // "SHUFF"
constexpr uint64_t kScrambleSalt = 0x534352414dull;  // "SCRAM"

// Sobol's second dimension of the index whose bits reversed are
// `reversed`, bit-reversed back: its generator matrix is the binary Pascal
// triangle (entry (i, j) is C(i, j) mod 2, 1 exactly when the bits of j are
// among those of i, by Lucas), which factors into five steps, one per bit
// of a bit's position, each a shift and an xor. No table, so a loop of
// these vectorises.
constexpr uint32_t SobolSecondOfReversed(uint32_t reversed) {
  uint32_t v = reversed;
  v ^= (v << 1) & 0xaaaaaaaau;
  v ^= (v << 2) & 0xccccccccu;
  v ^= (v << 4) & 0xf0f0f0f0u;
  v ^= (v << 8) & 0xff00ff00u;
  v ^= (v << 16) & 0xffff0000u;
  return v;
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

// The seed of coordinate `dimension`'s scramble, for `seed`.
inline uint32_t ScrambleSeed(uint32_t dimension, uint64_t seed) {
  return uint32_t(yarf::MixBits(seed ^ kScrambleSeeds[dimension % kCachedSeeds]) + (dimension / kCachedSeeds));
}

// Coordinate `dimension` from its block's shuffled index: Sobol's first
// dimension is the van der Corput sequence, the bit reversal of the index,
// so the reversals around the scrambles cancel; then the coordinate's own
// scramble (of seed `scramble_seed`).
inline float ScrambledCoordinate(uint32_t reversed_shuffled, uint32_t dimension, uint32_t scramble_seed) {
  const uint32_t bits = dimension % 2 == 0 ? reversed_shuffled : SobolSecondOfReversed(reversed_shuffled);
  return yarf::ToUnitFloat(yarf::NestedUniformScramble(bits, scramble_seed));
}
inline float Coordinate(uint32_t reversed_shuffled, uint32_t dimension, uint64_t seed) {
  return ScrambledCoordinate(reversed_shuffled, dimension, ScrambleSeed(dimension, seed));
}

// Both coordinates of block `pair` for each point; the two share the
// index's shuffle. One loop of branch-free integer arithmetic, which the
// compiler vectorises, built for AVX-512, AVX2 and the baseline and picked
// at load time from the CPU.
[[gnu::target_clones("arch=x86-64-v4", "avx2", "default")]]
void SobolPairs(const uint64_t* indices, const uint64_t* seeds, size_t count, uint32_t pair, float* out) {
  for (size_t k = 0; k < count; ++k) {
    const uint32_t shuffled = ShuffledReversedIndex(indices[k], pair, seeds[k]);
    out[2 * k] = Coordinate(shuffled, 2 * pair, seeds[k]);
    out[2 * k + 1] = Coordinate(shuffled, 2 * pair + 1, seeds[k]);
  }
}

class Sobol final : public yarf::Sampler {
 public:
  static std::vector<std::string> Capabilities() { return {yarf::kPowerOfTwoSamplesCapability}; }
  static yarf::ParameterSchema Parameters() { return {}; }

  explicit Sobol(const yarf::Properties&) {}

  float Sample(uint64_t index, uint32_t dimension, uint64_t seed) const override {
    return Coordinate(ShuffledReversedIndex(index, dimension / 2, seed), dimension, seed);
  }

  void SamplePairs(std::span<const uint64_t> indices, std::span<const uint64_t> seeds, uint32_t pair,
                   std::span<float> out) const override {
    SobolPairs(indices.data(), seeds.data(), indices.size(), pair, out.data());
  }
};


// A 32-bit integer hash (Wellons' "lowbias32"): the choice of each digit's
// permutation, one per digit, so it must be cheap. Of one integer or of
// each lane of a vector of them (Lanes, below).
template <typename T>
[[gnu::always_inline]] constexpr T Mix32(T v) {
  v ^= v >> 16;
  v *= 0x7feb352du;
  v ^= v >> 15;
  v *= 0x846ca68bu;
  v ^= v >> 16;
  return v;
}

// Interleaves the bits of x and y (x in the even bits).
constexpr uint64_t Morton(uint32_t x, uint32_t y) {
  const auto spread = [](uint64_t v) {
    v &= 0xffffffffull;
    v = (v | (v << 16)) & 0x0000ffff0000ffffull;
    v = (v | (v << 8)) & 0x00ff00ff00ff00ffull;
    v = (v | (v << 4)) & 0x0f0f0f0f0f0f0f0full;
    v = (v | (v << 2)) & 0x3333333333333333ull;
    return (v | (v << 1)) & 0x5555555555555555ull;
  };
  return spread(x) | (spread(y) << 1);
}

// The 24 permutations of four digits.
constexpr std::array<std::array<uint8_t, 4>, 24> kPermutationsOfFour = [] {
  std::array<std::array<uint8_t, 4>, 24> all{};
  std::array<uint8_t, 4> p{0, 1, 2, 3};
  for (auto& entry : all) {
    entry = p;
    // Next permutation in lexicographic order.
    int i = 2;
    while (i >= 0 && p[i] >= p[i + 1]) --i;
    if (i < 0) break;
    int j = 3;
    while (p[j] <= p[i]) --j;
    std::swap(p[i], p[j]);
    for (int a = i + 1, b = 3; a < b; ++a, --b) std::swap(p[a], p[b]);
  }
  return all;
}();

// The same permutations as one byte each: digit d goes to bits 2d, 2d + 1.
constexpr std::array<uint32_t, 24> kPermutationCodes = [] {
  std::array<uint32_t, 24> codes{};
  for (size_t c = 0; c < codes.size(); ++c)
    for (uint32_t d = 0; d < 4; ++d) codes[c] |= uint32_t(kPermutationsOfFour[c][d]) << (2 * d);
  return codes;
}();

// What zsobol's points share in a pair of dimensions for one seed: the
// salt choosing the digits' permutations, the two coordinates' scrambles
// and the sequence's shape. A job's points all have one seed (AtPixel's
// is the job's, with the shape), so a batch hashes these once.
struct ZSobolPair {
  uint32_t salt;
  uint32_t scramble[2];
  int digits;
  bool odd;
};

// Digit `shift` / 2 of a permuted index: that base-4 digit of `index`
// permuted by the permutation the digits above it choose.
inline uint32_t PermutedDigit(uint64_t index, int shift, uint32_t salt) {
  const uint32_t digit = uint32_t(index >> shift) & 3;
  return (kPermutationCodes[Mix32(uint32_t(index >> (shift + 2)) ^ salt) % 24] >> (2 * digit)) & 3;
}

// With an odd power of two samples per pixel: the last digit's free bit
// dropped, and the sample's bit flipped by a hash of the digits above.
inline uint64_t WithoutFreeBit(uint64_t permuted, uint64_t index, uint32_t salt) {
  return ((permuted | (index & 3)) >> 1) ^ (Mix32(uint32_t(index >> 2) ^ salt) & 1);
}

// Sixteen 32-bit lanes (GCC's vector extension): the batch kernel's
// table lookup becomes a shuffle of two registers, which the vectoriser
// would not make of a table by itself.
using Lanes = uint32_t __attribute__((vector_size(64)));

// zsobol's pair `pair` of `count` points below 2^32 sharing one seed's
// keys (at most 16 digits), sixteen points at a time, as PermutedDigit
// and WithoutFreeBit do for one; built for AVX-512, AVX2 and the baseline
// and picked at load time from the CPU.
[[gnu::target_clones("arch=x86-64-v4", "avx2", "default")]]
void ZSobolPairs(const uint64_t* indices, size_t count, uint32_t pair, const ZSobolPair& p, float* out) {
  constexpr size_t kLanes = 16;
  Lanes first_codes, last_codes;  // kPermutationCodes[0, 16) and [16, 24)
  for (size_t c = 0; c < kLanes; ++c) {
    first_codes[c] = kPermutationCodes[c];
    last_codes[c] = c + kLanes < kPermutationCodes.size() ? kPermutationCodes[c + kLanes] : 0;
  }
  for (size_t first = 0; first < count; first += kLanes) {
    const size_t n = std::min(kLanes, count - first);
    Lanes index = {}, permuted = {};
    for (size_t j = 0; j < n; ++j) index[j] = uint32_t(indices[first + j]);
    for (int i = p.digits - 1; i >= (p.odd ? 1 : 0); --i) {
      const int shift = 2 * i;
      const Lanes digit = (index >> shift) & 3;
      const Lanes above = shift + 2 < 32 ? index >> (shift + 2) : Lanes{};
      const Lanes code = __builtin_shuffle(first_codes, last_codes, Mix32(above ^ p.salt) % 24);
      permuted |= ((code >> (2 * digit)) & 3) << shift;
    }
    if (p.odd) permuted = ((permuted | (index & 3)) >> 1) ^ (Mix32((index >> 2) ^ p.salt) & 1);
    for (size_t j = 0; j < n; ++j) {
      const uint32_t reversed = yarf::ReverseBits(permuted[j]);
      out[2 * (first + j)] = ScrambledCoordinate(reversed, 2 * pair, p.scramble[0]);
      out[2 * (first + j) + 1] = ScrambledCoordinate(reversed, 2 * pair + 1, p.scramble[1]);
    }
  }
}

// How AtPixel's seed carries the sequence's shape to Sample: bit 0 is set
// when the samples per pixel are an odd power of two, bits 1-5 hold the
// number of base-4 digits of the indices, the rest are the job's seed.
constexpr uint64_t kOddBit = 1, kDigitsShift = 1, kDigitsMask = 0x1f, kSeedShift = 6;

class ZSobol final : public yarf::Sampler {
 public:
  static std::vector<std::string> Capabilities() { return {yarf::kPowerOfTwoSamplesCapability}; }
  static yarf::ParameterSchema Parameters() { return {}; }

  explicit ZSobol(const yarf::Properties&) {}

  FilmPoint AtPixel(uint32_t x, uint32_t y, uint32_t width, uint32_t height, uint64_t sample,
                    uint32_t samples_per_pixel, uint64_t seed) const override {
    const uint32_t log2_samples = std::bit_width(std::max(samples_per_pixel, 1u) - 1);
    const bool odd = log2_samples % 2 == 1;
    const uint32_t sample_bits = log2_samples + (odd ? 1 : 0);
    const uint32_t side_bits = std::bit_width(std::max(width, height) - 1);
    const uint32_t bits = 2 * side_bits + sample_bits;
    if (bits > 32)
      throw yarf::Error("zsobol: a " + std::to_string(width) + "×" + std::to_string(height) + " film at " +
                        std::to_string(samples_per_pixel) +
                        " samples per pixel needs more than 2^32 points; use sobol");
    // The odd case leaves the lowest bit free for Sample to fill (pbrt-v4's).
    const uint64_t index = (Morton(x, y) << sample_bits) | (sample << (odd ? 1 : 0));
    const uint64_t shape = (odd ? kOddBit : 0) | (uint64_t((bits + 1) / 2) << kDigitsShift);
    return {index, (yarf::MixBits(seed) << kSeedShift) | shape};
  }

  float Sample(uint64_t index, uint32_t dimension, uint64_t seed) const override {
    const ZSobolPair keys = Keys(dimension / 2, seed);
    return ScrambledCoordinate(yarf::ReverseBits(PermutedIndex(index, keys)), dimension, keys.scramble[dimension % 2]);
  }

  // Runs of points with one seed, AtPixel's shape and indices below 2^32
  // (a job's) go to the batch kernel; any others one at a time.
  void SamplePairs(std::span<const uint64_t> indices, std::span<const uint64_t> seeds, uint32_t pair,
                   std::span<float> out) const override {
    constexpr uint64_t kIndexLimit = uint64_t(1) << 32;
    for (size_t first = 0, end = 0; first < indices.size(); first = end) {
      bool batchable = indices[first] < kIndexLimit;
      for (end = first + 1; end < indices.size() && seeds[end] == seeds[first]; ++end)
        batchable = batchable && indices[end] < kIndexLimit;
      const ZSobolPair keys = Keys(pair, seeds[first]);
      if (batchable && keys.digits <= 16) {
        ZSobolPairs(&indices[first], end - first, pair, keys, &out[2 * first]);
        continue;
      }
      for (size_t k = first; k < end; ++k) {
        const uint32_t reversed = yarf::ReverseBits(PermutedIndex(indices[k], keys));
        out[2 * k] = ScrambledCoordinate(reversed, 2 * pair, keys.scramble[0]);
        out[2 * k + 1] = ScrambledCoordinate(reversed, 2 * pair + 1, keys.scramble[1]);
      }
    }
  }

 private:
  static ZSobolPair Keys(uint32_t pair, uint64_t seed) {
    const uint64_t job_seed = seed >> kSeedShift;
    return {uint32_t(yarf::MixBits(job_seed ^ (uint64_t(pair) * kGolden))),
            {ScrambleSeed(2 * pair, job_seed), ScrambleSeed(2 * pair + 1, job_seed)},
            int((seed >> kDigitsShift) & kDigitsMask),
            (seed & kOddBit) != 0};
  }

  // The Sobol index of film index `index` for a pair of dimensions: each
  // base-4 digit permuted as a function of the digits above it.
  static uint32_t PermutedIndex(uint64_t index, const ZSobolPair& p) {
    uint64_t permuted = 0;
    for (int i = p.digits - 1; i >= (p.odd ? 1 : 0); --i)
      permuted |= uint64_t(PermutedDigit(index, 2 * i, p.salt)) << (2 * i);
    if (p.odd) permuted = WithoutFreeBit(permuted, index, p.salt);
    return uint32_t(permuted);
  }
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Sobol>(registrar, "sobol", "1.0.0",
                        "Padded 2-D Sobol points with hash-based Owen scrambling");
  yarf::Register<ZSobol>(registrar, "zsobol", "1.0.0",
                         "One Owen-scrambled Sobol sequence over the film in Morton order (pbrt-v4's ZSobol)");
}
