// Tests of sobol_nd (samplers/sobol_nd.cc), loaded through the registry as
// yarfd loads it: the net properties of the Sobol sequence, which Owen
// scrambling must keep, in 2-D projections and in every 1-D projection of
// all 21201 tabulated dimensions, and the bounds it refuses past.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "components/registry.h"
#include "sampler_test_support.h"
#include "yarf/math.h"

namespace yarf {
namespace {

constexpr uint32_t kTabulated = 21201;

class SobolNdTest : public testing::Test {
 protected:
  SobolNdTest() { registry_.LoadDirectory(YARF_PLUGIN_DIR); }

  std::unique_ptr<Sampler> Make(bool scramble) const {
    Properties props;
    props.Set("scramble", scramble);
    return registry_.CreateAs<Sampler>("sobol_nd", props);
  }

  Registry registry_;
};

// Points first..first+count-1 with `dimensions` coordinates, row-major.
std::vector<float> Points(const Sampler& sampler, uint64_t first, uint32_t count, uint32_t dimensions,
                          uint64_t seed) {
  std::vector<float> points(size_t(count) * dimensions);
  sampler.Generate(first, count, dimensions, seed, points);
  return points;
}

// The number of points (of `count`) in each elementary interval
// [i/2^a, (i+1)/2^a) × [j/2^b, (j+1)/2^b) of the projection on dimensions
// (x, y). Floats of [0, 1) times a power of two ≤ 2^24 floor exactly.
std::vector<uint32_t> IntervalCounts(const std::vector<float>& points, uint32_t count, uint32_t dimensions,
                                     uint32_t x, uint32_t y, int a, int b) {
  std::vector<uint32_t> counts(size_t(1) << (a + b), 0);
  for (uint32_t i = 0; i < count; ++i) {
    const uint32_t cx = uint32_t(points[size_t(i) * dimensions + x] * float(1u << a));
    const uint32_t cy = uint32_t(points[size_t(i) * dimensions + y] * float(1u << b));
    ++counts[(size_t(cx) << b) | cy];
  }
  return counts;
}

// The least t for which the 2^m points are a (t, m, 2)-net in base 2 on
// dimensions (x, y): every elementary interval of volume 2^(t-m) holds
// exactly 2^t of them.
int TValue(const std::vector<float>& points, int m, uint32_t dimensions, uint32_t x, uint32_t y) {
  for (int t = 0;; ++t) {
    bool net = true;
    for (int a = 0; a <= m - t && net; ++a)
      for (uint32_t c : IntervalCounts(points, 1u << m, dimensions, x, y, a, m - t - a))
        if (c != (1u << t)) net = false;
    if (net) return t;
  }
}

TEST_F(SobolNdTest, IsDeterministicAndInTheUnitInterval) {
  const auto first = Make(true), second = Make(true);
  testing_support::ExpectDeterministic(*first, *second, "sobol_nd");
  for (uint64_t seed : {0ull, 5ull})
    for (float u : Points(*first, 0, 512, kTabulated, seed)) {
      EXPECT_GE(u, 0.0f);
      EXPECT_LT(u, 1.0f);
    }
}

TEST_F(SobolNdTest, FirstTwoDimensionsAreZeroMTwoNetsScrambledOrNot) {
  // Every elementary interval of area 2^-m holds exactly one of 2^m
  // points, in the first run of 2^m points and in a later aligned one.
  constexpr int kMaxM = 12;
  for (bool scramble : {false, true}) {
    const auto sobol = Make(scramble);
    for (uint64_t seed : {0ull, 1ull, 77ull})
      for (int m = 1; m <= kMaxM; ++m)
        for (uint64_t run : {0ull, 5ull}) {
          const uint32_t count = 1u << m;
          const auto points = Points(*sobol, run * count, count, 2, seed);
          for (int a = 0; a <= m; ++a)
            for (uint32_t c : IntervalCounts(points, count, 2, 0, 1, a, m - a))
              ASSERT_EQ(c, 1u) << "scramble " << scramble << " seed " << seed << " m " << m << " run " << run
                               << " interval shape 2^-" << a << " x 2^-" << m - a;
        }
  }
}

TEST_F(SobolNdTest, ScramblingKeepsEveryElementaryIntervalCountOfTheFirstDimensions) {
  // Owen scrambling maps each elementary interval onto one of the same
  // shape, so every pair of dimensions keeps its net quality (t-value)
  // and even the multiset of counts over each interval shape. Joe & Kuo
  // chose their direction numbers for small t in 2-D projections: among
  // the first 8 dimensions t ≤ 4 up to 2^12 points.
  constexpr int kMaxM = 12;
  constexpr uint32_t kDimensions = 8;
  const auto plain = Make(false), scrambled = Make(true);
  const auto reference = Points(*plain, 0, 1u << kMaxM, kDimensions, 0);
  for (uint64_t seed : {3ull, 4ull}) {
    const auto points = Points(*scrambled, 0, 1u << kMaxM, kDimensions, seed);
    for (uint32_t x = 0; x < kDimensions; ++x)
      for (uint32_t y = x + 1; y < kDimensions; ++y)
        for (int m = 1; m <= kMaxM; ++m) {
          const int t = TValue(reference, m, kDimensions, x, y);
          EXPECT_LE(t, 4) << "dimensions " << x << ", " << y << " m " << m;
          EXPECT_EQ(TValue(points, m, kDimensions, x, y), t) << "dimensions " << x << ", " << y << " m " << m;
          for (int a = 0; a <= m; ++a) {
            auto expected = IntervalCounts(reference, 1u << m, kDimensions, x, y, a, m - a);
            auto counts = IntervalCounts(points, 1u << m, kDimensions, x, y, a, m - a);
            std::sort(expected.begin(), expected.end());
            std::sort(counts.begin(), counts.end());
            ASSERT_EQ(counts, expected) << "dimensions " << x << ", " << y << " m " << m << " a " << a;
          }
        }
  }
}

TEST_F(SobolNdTest, EveryDimensionIsStratifiedAtEveryPowerOfTwo) {
  // Each 1-D projection of the sequence is a (0, 1)-sequence: the first
  // 2^m points put one in each interval [k/2^m, (k+1)/2^m), scrambled or
  // not: up to 2^12 points in the first 1024 dimensions, 2^8 in all.
  struct Range {
    uint32_t dimensions;
    int max_m;
  };
  for (const Range range : {Range{1024, 12}, Range{kTabulated, 8}})
    for (bool scramble : {false, true}) {
      const auto sobol = Make(scramble);
      const uint32_t n = 1u << range.max_m;
      const auto points = Points(*sobol, 0, n, range.dimensions, 11);
      for (uint32_t d = 0; d < range.dimensions; ++d)
        for (int m = 0; m <= range.max_m; ++m) {
          std::vector<uint32_t> counts(size_t(1) << m, 0);
          for (uint32_t i = 0; i < (1u << m); ++i)
            ++counts[uint32_t(points[size_t(i) * range.dimensions + d] * float(1u << m))];
          ASSERT_EQ(*std::min_element(counts.begin(), counts.end()), 1u)
              << "scramble " << scramble << " dimension " << d << " m " << m;
        }
    }
}

TEST_F(SobolNdTest, ScrambledPointsDifferBySeedAndAreUniformOverSeeds) {
  // Over seeds, one point's coordinate is uniform: its mean over many
  // seeds is 1/2 within a few standard errors (1/√(12 n)).
  const auto sobol = Make(true);
  constexpr uint32_t kSeeds = 4096;
  for (uint32_t d : {0u, 1u, 7u, 500u, 1023u, 21200u}) {
    double sum = 0;
    for (uint32_t s = 0; s < kSeeds; ++s) sum += sobol->Sample(3, d, s);
    EXPECT_NEAR(sum / kSeeds, 0.5, 4 / std::sqrt(12.0 * kSeeds)) << "dimension " << d;
  }
  EXPECT_NE(sobol->Sample(3, 2, 0), sobol->Sample(3, 2, 1));
  const auto plain = Make(false);
  EXPECT_EQ(plain->Sample(3, 2, 0), plain->Sample(3, 2, 1));
}

TEST_F(SobolNdTest, RefusesDimensionsAndIndicesPastItsTable) {
  const auto sobol = Make(true);
  std::vector<float> out(kTabulated + 1);
  EXPECT_NO_THROW(sobol->Sample(0, kTabulated - 1, 0));
  EXPECT_THROW(sobol->Sample(0, kTabulated, 0), Error);
  EXPECT_THROW(sobol->Generate(0, 1, kTabulated + 1, 0, out), Error);
  EXPECT_NO_THROW(sobol->Sample((uint64_t(1) << 32) - 1, 0, 0));
  EXPECT_THROW(sobol->Sample(uint64_t(1) << 32, 0, 0), Error);
  EXPECT_THROW(sobol->Generate((uint64_t(1) << 32) - 1, 2, 1, 0, out), Error);
  try {
    sobol->Sample(0, kTabulated, 0);
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("21201 dimensions"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace yarf
