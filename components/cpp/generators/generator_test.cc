// Tests of the generator plugins (generators/*.cc), loaded through the
// registry as yarfd loads them: determinism, skip-ahead against plain
// stepping, known answers from the published recurrences, uniformity,
// and independence of consecutive outputs, streams and seeds.
#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "components/registry.h"
#include "yarf/support/hash.h"
#include "yarf/math.h"

namespace yarf {
namespace {

constexpr const char* kGenerators[] = {"lcg", "pcg32", "xoshiro256starstar"};

class GeneratorTest : public testing::Test {
 protected:
  GeneratorTest() { registry_.LoadDirectory(YARF_PLUGIN_DIR); }

  std::unique_ptr<Generator> Make(const std::string& name) const {
    return registry_.CreateAs<Generator>(name, Properties{});
  }

  Registry registry_;
};

std::vector<float> Draw(Generator& generator, uint64_t seed, uint64_t stream, uint64_t offset,
                        size_t count) {
  std::vector<float> out(count);
  generator.Next(seed, stream, offset, out);
  return out;
}

// Pearson correlation of two equally long sequences.
double Correlation(const std::vector<float>& a, const std::vector<float>& b) {
  const size_t n = a.size();
  double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
  for (size_t k = 0; k < n; ++k) {
    sa += a[k];
    sb += b[k];
    saa += double(a[k]) * a[k];
    sbb += double(b[k]) * b[k];
    sab += double(a[k]) * b[k];
  }
  const double cov = sab / n - (sa / n) * (sb / n);
  return cov / std::sqrt((saa / n - (sa / n) * (sa / n)) * (sbb / n - (sb / n) * (sb / n)));
}

TEST_F(GeneratorTest, RegistersWithItsInterface) {
  for (const char* name : kGenerators) {
    ASSERT_TRUE(registry_.Has(name)) << name;
    EXPECT_EQ(Make(name)->Describe().interfaces, std::vector<std::string>{Generator::kInterface})
        << name;
  }
}

TEST_F(GeneratorTest, TakesNoProperties) {
  for (const char* name : kGenerators) {
    Properties props;
    props.Set("multiplier", int64_t(5));
    EXPECT_THROW(registry_.Create(name, props), Error) << name;
  }
}

TEST_F(GeneratorTest, IsDeterministicAndInUnitInterval) {
  for (const char* name : kGenerators) {
    const auto first = Make(name), second = Make(name);
    for (uint64_t seed : {0ull, 1ull, 0xfedcba9876543210ull})
      for (uint64_t stream : {0ull, 7ull, ~0ull}) {
        const auto a = Draw(*first, seed, stream, 0, 4096);
        EXPECT_EQ(a, Draw(*first, seed, stream, 0, 4096)) << name;
        EXPECT_EQ(a, Draw(*second, seed, stream, 0, 4096)) << name;
        for (float value : a) {
          ASSERT_GE(value, 0.0f) << name;
          ASSERT_LT(value, 1.0f) << name;
        }
      }
    // An empty request is valid and writes nothing.
    first->Next(1, 2, 3, std::span<float>());
  }
}

TEST_F(GeneratorTest, OffsetSkipsAhead) {
  // Next at offset k is the tail of Next from 0, up to a million steps:
  // the skip-ahead (jump polynomials, LCG strides) agrees with stepping.
  constexpr size_t kFar = 1000000;
  constexpr size_t kTail = 64;
  for (const char* name : kGenerators) {
    const auto generator = Make(name);
    for (uint64_t seed : {3ull, 0x0123456789abcdefull}) {
      const auto all = Draw(*generator, seed, 11, 0, kFar + kTail);
      for (uint64_t offset : {1ull, 2ull, 3ull, 64ull, 1000ull, 65535ull, 65536ull, 65537ull,
                              123457ull, 999999ull, 1000000ull}) {
        const auto tail = Draw(*generator, seed, 11, offset, kTail);
        for (size_t k = 0; k < kTail; ++k)
          ASSERT_EQ(tail[k], all[offset + k]) << name << " seed " << seed << " offset " << offset
                                              << " output " << k;
      }
    }
  }
}

TEST_F(GeneratorTest, HugeOffsetsAreLogarithmicAndCompose) {
  // Offsets near 2^64 would take centuries to step through; they return
  // at once, and skipping k then j equals skipping k + j.
  for (const char* name : kGenerators) {
    const auto generator = Make(name);
    for (uint64_t offset : {1ull << 40, (1ull << 63) + 12345, ~0ull - 100}) {
      const auto run = Draw(*generator, 5, 9, offset, 100);
      for (uint64_t skip : {1ull, 37ull, 99ull}) {
        const auto later = Draw(*generator, 5, 9, offset + skip, 100 - skip);
        for (size_t k = 0; k < later.size(); ++k)
          ASSERT_EQ(later[k], run[skip + k]) << name << " offset " << offset << " + " << skip;
      }
    }
  }
}

TEST_F(GeneratorTest, Pcg32ReproducesTheReferenceDemo) {
  // pcg32-demo's first outputs for seed 42, stream 54 (O'Neill's pcg-c-basic).
  constexpr uint32_t kReference[] = {0xa15c02b7, 0x7b47f409, 0xba1d3330,
                                     0x83d2f293, 0xbfa4784b, 0xcbed606e};
  const auto values = Draw(*Make("pcg32"), 42, 54, 0, 6);
  for (size_t k = 0; k < 6; ++k) EXPECT_EQ(values[k], ToUnitFloat(kReference[k])) << k;
  // And from the middle of the stream.
  const auto later = Draw(*Make("pcg32"), 42, 54, 4, 2);
  EXPECT_EQ(later[0], ToUnitFloat(kReference[4]));
  EXPECT_EQ(later[1], ToUnitFloat(kReference[5]));
}

TEST_F(GeneratorTest, LcgFollowsTheMmixRecurrence) {
  // Stream 0 is x' = a·x + c mod 2^64 with Knuth's MMIX constants from
  // x_0 = Hash(seed); each output is the new state's high bits.
  constexpr uint64_t a = 6364136223846793005ull, c = 1442695040888963407ull;
  for (uint64_t seed : {0ull, 42ull}) {
    const auto values = Draw(*Make("lcg"), seed, 0, 0, 1000);
    uint64_t x = Hash(seed);
    for (size_t k = 0; k < values.size(); ++k) {
      x = a * x + c;
      ASSERT_EQ(values[k], ToUnitFloat(uint32_t(x >> 32))) << "seed " << seed << " output " << k;
    }
  }
}

// xoshiro256** written from the published recurrence.
struct ReferenceXoshiro {
  std::array<uint64_t, 4> s;

  uint64_t Next() {
    const uint64_t result = std::rotl(s[1] * 5, 7) * 9;
    const uint64_t t = s[1] << 17;
    s[2] ^= s[0];
    s[3] ^= s[1];
    s[1] ^= s[2];
    s[0] ^= s[3];
    s[2] ^= t;
    s[3] = std::rotl(s[3], 45);
    return result;
  }
};

// splitmix64 (Steele, Lea & Flood 2014), written out in full.
uint64_t SplitMix64(uint64_t& x) {
  uint64_t z = (x += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

TEST_F(GeneratorTest, Xoshiro256StarStarFollowsThePublishedRecurrence) {
  // The reference recurrence itself, from the state {1, 2, 3, 4}.
  ReferenceXoshiro small{{1, 2, 3, 4}};
  EXPECT_EQ(small.Next(), 11520u);
  EXPECT_EQ(small.Next(), 0u);
  EXPECT_EQ(small.Next(), 1509978240u);
  EXPECT_EQ(small.Next(), 1215971899390074240u);

  // The plugin: four splitmix64 outputs from Hash(seed, stream) as state.
  const auto generator = Make("xoshiro256starstar");
  for (auto [seed, stream] : {std::pair{0ull, 0ull}, std::pair{42ull, 54ull}}) {
    uint64_t x = Hash(seed, stream);
    ReferenceXoshiro reference{};
    for (auto& word : reference.s) word = SplitMix64(x);
    const auto values = Draw(*generator, seed, stream, 0, 1000);
    for (size_t k = 0; k < values.size(); ++k)
      ASSERT_EQ(values[k], ToUnitFloat(uint32_t(reference.Next() >> 32)))
          << "seed " << seed << " stream " << stream << " output " << k;
  }
}

TEST_F(GeneratorTest, IsUniform) {
  // Pearson's χ² over 64 equal bins; 103.44 is the 0.999 quantile of χ²
  // with 63 degrees of freedom, so each case fails by chance with p = 0.001.
  constexpr int kBins = 64;
  constexpr size_t kCount = 1 << 20;
  for (const char* name : kGenerators) {
    const auto generator = Make(name);
    for (auto [seed, stream] : {std::pair{0ull, 0ull}, std::pair{1ull, 1ull}, std::pair{99ull, 3ull}}) {
      std::array<double, kBins> counts{};
      for (float value : Draw(*generator, seed, stream, 0, kCount)) ++counts[int(value * kBins)];
      const double expected = double(kCount) / kBins;
      double chi2 = 0;
      for (double observed : counts) chi2 += (observed - expected) * (observed - expected) / expected;
      EXPECT_LT(chi2, 103.44) << name << " seed " << seed << " stream " << stream;
    }
  }
}

TEST_F(GeneratorTest, ConsecutiveOutputsAreUncorrelated) {
  // Lag-1 autocorrelation: its standard error is 1/√N = 0.001 here.
  constexpr size_t kCount = 1000000;
  for (const char* name : kGenerators) {
    const auto values = Draw(*Make(name), 17, 4, 0, kCount + 1);
    const std::vector<float> current(values.begin(), values.end() - 1);
    const std::vector<float> next(values.begin() + 1, values.end());
    EXPECT_LT(std::abs(Correlation(current, next)), 0.005) << name;
  }
}

TEST_F(GeneratorTest, StreamsAndSeedsAreUncorrelated) {
  // Paired outputs of different streams of one seed (and of neighbouring
  // seeds): correlation's standard error is 1/√N ≈ 0.003 here.
  // pcg32 keeps the reference seeding (so that pcg32-demo's outputs
  // reproduce), under which seed 0 makes the LCG states of streams s and
  // t exact multiples of each other: streams 0 and 1 of seed 0 correlate
  // at r ≈ 0.025. pcg32.cc documents this; seed 0 is tested for the
  // others only.
  constexpr size_t kCount = 100000;
  for (const char* name : kGenerators) {
    const auto generator = Make(name);
    const bool pcg32 = std::string(name) == "pcg32";
    for (uint64_t seed : {0ull, 42ull, 0x9e3779b97f4a7c15ull}) {
      if (pcg32 && seed == 0) continue;
      for (auto [s, t] : {std::pair{0ull, 1ull}, std::pair{0ull, 2ull}, std::pair{1ull, 2ull},
                          std::pair{0ull, 1ull << 32}, std::pair{5ull, 1000ull}}) {
        const double r = Correlation(Draw(*generator, seed, s, 0, kCount),
                                     Draw(*generator, seed, t, 0, kCount));
        EXPECT_LT(std::abs(r), 0.02) << name << " seed " << seed << " streams " << s << ", " << t;
      }
    }
    for (uint64_t seed : {0ull, 1000ull}) {
      const double r = Correlation(Draw(*generator, seed, 3, 0, kCount),
                                   Draw(*generator, seed + 1, 3, 0, kCount));
      EXPECT_LT(std::abs(r), 0.02) << name << " seeds " << seed << ", " << seed + 1;
    }
    // A stream is not a shifted copy of another: no stream-1 output run
    // starts inside the first stretch of stream 0.
    const auto zero = Draw(*generator, 8, 0, 0, 4096), one = Draw(*generator, 8, 1, 0, 4);
    for (size_t k = 0; k + 4 <= zero.size(); ++k)
      EXPECT_FALSE(zero[k] == one[0] && zero[k + 1] == one[1] && zero[k + 2] == one[2] &&
                   zero[k + 3] == one[3])
          << name << " at " << k;
  }
}

}  // namespace
}  // namespace yarf
