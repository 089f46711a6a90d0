// Tests of the stratified and low-discrepancy samplers (stratified,
// latin_hypercube, hammersley, halton) and of the randomization helpers
// they share (yarf/support/owen.h): determinism, range, the stratification each
// one promises, uniformity over seeds, and integration error in the order
// theory gives.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "components/registry.h"
#include "sampler_test_support.h"
#include "yarf/support/hash.h"
#include "yarf/math.h"
#include "yarf/support/owen.h"

namespace yarf {
namespace {

constexpr const char* kFamily[] = {"stratified", "latin_hypercube", "hammersley", "halton"};
constexpr const char* kCounted[] = {"stratified", "latin_hypercube", "hammersley"};

class SamplerFamilyTest : public testing::Test {
 protected:
  SamplerFamilyTest() { registry_.LoadDirectory(YARF_PLUGIN_DIR); }

  // sample_count is set when given and the class reads it.
  std::unique_ptr<Sampler> Make(const std::string& name, int64_t sample_count = 0) const {
    Properties props;
    if (sample_count > 0) props.Set("sample_count", sample_count);
    return registry_.CreateAs<Sampler>(name, props);
  }

  Registry registry_;
};

// The grid of the stratified sampler: n×m, n the largest divisor ≤ √N.
std::array<uint32_t, 2> Grid(uint32_t count) {
  uint32_t columns = 1;
  for (uint32_t n = 1; n * n <= count; ++n)
    if (count % n == 0) columns = n;
  return {columns, count / columns};
}

// The 0.999 quantile of χ² with k degrees of freedom (Wilson–Hilferty:
// (χ²/k)^(1/3) is nearly normal; 3.0902 is the normal 0.999 quantile).
double ChiSquareQuantile999(int k) {
  const double v = 2.0 / (9.0 * k);
  return k * std::pow(1 - v + 3.0902 * std::sqrt(v), 3);
}

// Stratum of x among `count` equal ones; exact for count ≤ 2^24.
uint32_t Stratum(float x, uint32_t count) { return uint32_t(double(x) * count); }

TEST_F(SamplerFamilyTest, RegistersWithItsInterface) {
  for (const char* name : kFamily) {
    ASSERT_TRUE(registry_.Has(name)) << name;
    EXPECT_EQ(Make(name)->Describe().interfaces, std::vector<std::string>{Sampler::kInterface})
        << name;
  }
}

TEST_F(SamplerFamilyTest, ChecksItsProperties) {
  for (const char* name : kCounted) {
    for (int64_t bad : {int64_t(0), int64_t(-4), (int64_t(1) << 24) + 1}) {
      Properties props;
      props.Set("sample_count", bad);
      EXPECT_THROW(registry_.Create(name, props), Error) << name << " " << bad;
    }
    Properties wrong_type;
    wrong_type.Set("sample_count", std::string("many"));
    EXPECT_THROW(registry_.Create(name, wrong_type), Error) << name;
    Properties unknown;
    unknown.Set("samples", int64_t(16));
    EXPECT_THROW(registry_.Create(name, unknown), Error) << name;
    EXPECT_NO_THROW(Make(name, 1)) << name;
  }
  // Halton is an infinite sequence: it has no sample count.
  Properties props;
  props.Set("sample_count", int64_t(16));
  EXPECT_THROW(registry_.Create("halton", props), Error);
}

TEST_F(SamplerFamilyTest, IsDeterministic) {
  for (const char* name : kFamily) {
    const auto first = Make(name), second = Make(name);
    testing_support::ExpectDeterministic(*first, *second, name);
  }
}

TEST_F(SamplerFamilyTest, ValuesLieInUnitInterval) {
  const uint64_t far_indices[] = {(1ull << 32) - 1, 1ull << 32, 1ull << 63,
                                  std::numeric_limits<uint64_t>::max()};
  for (const char* name : kFamily)
    for (int64_t count : {int64_t(0), int64_t(3), int64_t(1) << 24}) {
      if (count != 0 && std::string(name) == "halton") continue;
      const auto sampler = Make(name, count);
      auto check = [&](uint64_t index, uint32_t dimension, uint64_t seed) {
        const float value = sampler->Sample(index, dimension, seed);
        ASSERT_GE(value, 0.0f) << name << " " << index << " " << dimension << " " << seed;
        ASSERT_LT(value, 1.0f) << name << " " << index << " " << dimension << " " << seed;
      };
      for (uint64_t seed : {uint64_t(0), uint64_t(5), std::numeric_limits<uint64_t>::max()}) {
        for (uint64_t index = 0; index < 2048; ++index)
          for (uint32_t dimension = 0; dimension < 8; ++dimension) check(index, dimension, seed);
        for (uint64_t index : far_indices)
          for (uint32_t dimension : {0u, 1u, 255u, 1023u, 1024u, std::numeric_limits<uint32_t>::max()})
            check(index, dimension, seed);
      }
    }
}

TEST_F(SamplerFamilyTest, SeedsDimensionsAndBlocksGiveDifferentNumbers) {
  for (const char* name : kFamily) {
    const auto sampler = Make(name);
    int same_seed = 0, same_dimension = 0, same_block = 0;
    for (uint64_t index = 0; index < 256; ++index) {
      same_seed += sampler->Sample(index, 1, 1) == sampler->Sample(index, 1, 2);
      same_dimension += sampler->Sample(index, 0, 1) == sampler->Sample(index, 2, 1);
      // 16 is the default sample count: the next block of points.
      same_block += sampler->Sample(index, 1, 1) == sampler->Sample(index + 16, 1, 1);
    }
    EXPECT_LT(same_seed, 4) << name;
    EXPECT_LT(same_dimension, 4) << name;
    EXPECT_LT(same_block, 4) << name;
  }
}

TEST_F(SamplerFamilyTest, StratifiedPutsOnePointInEachGridCell) {
  for (uint32_t count : {1u, 2u, 7u, 12u, 16u, 64u, 100u, 1000u}) {
    const auto sampler = Make("stratified", count);
    const auto [columns, rows] = Grid(count);
    for (uint64_t seed : {0ull, 1ull, 77ull, 0xdeadbeefcafeull})
      for (uint32_t pair : {0u, 1u, 5u, 31u})
        for (uint64_t block : {0ull, 1ull, 1000ull}) {
          std::vector<int> occupied(count, 0);
          for (uint32_t i = 0; i < count; ++i) {
            const uint64_t index = block * count + i;
            const uint32_t x = Stratum(sampler->Sample(index, 2 * pair, seed), columns);
            const uint32_t y = Stratum(sampler->Sample(index, 2 * pair + 1, seed), rows);
            ++occupied[y * columns + x];
          }
          for (uint32_t cell = 0; cell < count; ++cell)
            ASSERT_EQ(occupied[cell], 1) << "N " << count << " (" << columns << "x" << rows
                                         << "), seed " << seed << ", pair " << pair << ", block "
                                         << block << ", cell " << cell;
        }
  }
}

TEST_F(SamplerFamilyTest, LatinHypercubeFillsEveryStratumOfEveryDimension) {
  for (uint32_t count : {1u, 5u, 16u, 100u, 1000u}) {
    const auto sampler = Make("latin_hypercube", count);
    for (uint64_t seed : {0ull, 3ull, 0xdeadbeefcafeull})
      for (uint32_t dimension : {0u, 1u, 7u, 100u})
        for (uint64_t block : {0ull, 2ull, 12345ull}) {
          std::vector<int> occupied(count, 0);
          for (uint32_t i = 0; i < count; ++i)
            ++occupied[Stratum(sampler->Sample(block * count + i, dimension, seed), count)];
          for (uint32_t stratum = 0; stratum < count; ++stratum)
            ASSERT_EQ(occupied[stratum], 1) << "N " << count << ", seed " << seed
                                            << ", dimension " << dimension << ", block " << block
                                            << ", stratum " << stratum;
        }
  }
}

// Points first..first+b^k-1 of `dimension` fill each of the b^k intervals
// [j/b^k, (j+1)/b^k) once, for every b^k ≤ limit.
void ExpectRadicalInverseStratification(const Sampler& sampler, uint32_t dimension, uint32_t base,
                                        uint64_t first, uint32_t limit, uint64_t seed,
                                        const char* name) {
  for (uint32_t count = base; count <= limit; count *= base) {
    std::vector<int> occupied(count, 0);
    for (uint32_t i = 0; i < count; ++i)
      ++occupied[Stratum(sampler.Sample(first + i, dimension, seed), count)];
    for (uint32_t interval = 0; interval < count; ++interval)
      ASSERT_EQ(occupied[interval], 1) << name << ", dimension " << dimension << " (base " << base
                                       << "), " << count << " points from " << first << ", seed "
                                       << seed << ", interval " << interval;
    if (uint64_t(count) * base > limit) break;
  }
}

TEST_F(SamplerFamilyTest, HaltonStratifiesEveryBase) {
  const auto halton = Make("halton");
  for (uint64_t seed : {0ull, 9ull, 0xdeadbeefcafeull})
    for (uint32_t dimension : {0u, 1u, 2u, 3u, 4u, 10u, 31u, 100u, 255u, 1023u}) {
      const uint32_t base = kPrimes[dimension];
      // From index 0 and from a later multiple of each b^k.
      ExpectRadicalInverseStratification(*halton, dimension, base, 0, 20000, seed, "halton");
      uint64_t multiple = 1;
      while (multiple * base <= 20000) multiple *= base;
      ExpectRadicalInverseStratification(*halton, dimension, base, 7 * multiple, uint32_t(multiple),
                                         seed, "halton");
    }
  // The 256th dimension uses the 256th prime, 1619.
  EXPECT_EQ(kPrimes[255], 1619u);
  EXPECT_EQ(kPrimes[1023], 8161u);
}

TEST_F(SamplerFamilyTest, HammersleyStratifiesEveryDimension) {
  for (uint32_t count : {256u, 1000u, 4096u}) {
    const auto hammersley = Make("hammersley", count);
    for (uint64_t seed : {0ull, 9ull, 0xdeadbeefcafeull})
      for (uint64_t block : {0ull, 5ull}) {
        // Dimension 0: one point in each of the N strata.
        std::vector<int> occupied(count, 0);
        for (uint32_t i = 0; i < count; ++i)
          ++occupied[Stratum(hammersley->Sample(block * count + i, 0, seed), count)];
        for (uint32_t stratum = 0; stratum < count; ++stratum)
          ASSERT_EQ(occupied[stratum], 1) << "N " << count << ", seed " << seed << ", block "
                                          << block << ", stratum " << stratum;
        for (uint32_t dimension : {1u, 2u, 3u, 4u, 20u, 256u})
          ExpectRadicalInverseStratification(*hammersley, dimension, kPrimes[dimension - 1],
                                             block * count, count, seed, "hammersley");
      }
  }
}

TEST_F(SamplerFamilyTest, HammersleyFirstTwoDimensionsAreANet) {
  // With N = 2^m, dimensions 0 and 1 put one point in every elementary
  // interval of area 2^-m: the scrambling keeps the (0, m, 2)-net.
  for (int m : {4, 8, 10}) {
    const uint32_t count = 1u << m;
    const auto hammersley = Make("hammersley", count);
    for (uint64_t seed : {0ull, 1ull, 0xdeadbeefcafeull})
      for (int a = 0; a <= m; ++a) {
        std::vector<int> occupied(count, 0);
        for (uint32_t i = 0; i < count; ++i) {
          const uint32_t x = Stratum(hammersley->Sample(i, 0, seed), 1u << a);
          const uint32_t y = Stratum(hammersley->Sample(i, 1, seed), 1u << (m - a));
          ++occupied[(x << (m - a)) | y];
        }
        for (uint32_t cell = 0; cell < count; ++cell)
          ASSERT_EQ(occupied[cell], 1) << "m " << m << ", seed " << seed << ", shape 2^" << a
                                       << " x 2^" << m - a << ", cell " << cell;
      }
  }
}

TEST_F(SamplerFamilyTest, EachPointIsUniformOverSeeds) {
  // Randomized QMC is unbiased only if every single point is uniform over
  // the randomization: χ² over 16 bins.
  constexpr int kBins = 16, kSeeds = 16000;
  for (const char* name : kFamily) {
    const auto sampler = Make(name);
    for (uint64_t index : {0ull, 5ull, 37ull})
      for (uint32_t dimension : {0u, 1u, 2u, 5u}) {
        std::array<double, kBins> counts{};
        double sum = 0;
        for (uint64_t seed = 0; seed < kSeeds; ++seed) {
          const float value = sampler->Sample(index, dimension, seed);
          ++counts[int(value * kBins)];
          sum += value;
        }
        const double expected = double(kSeeds) / kBins;
        double chi2 = 0;
        for (double observed : counts) chi2 += (observed - expected) * (observed - expected) / expected;
        EXPECT_LT(chi2, ChiSquareQuantile999(kBins - 1)) << name << " index " << index << " dimension " << dimension;
        EXPECT_NEAR(sum / kSeeds, 0.5, 0.01) << name << " index " << index << " dimension "
                                             << dimension;
      }
  }
}

// RMS error over seeds 0..19 of the N-point estimate of ∫∫ f = 1 over the
// unit square, f(x, y) = x e^x · y e^y, from dimensions (0, 1).
double RmsError(const Sampler& sampler, uint32_t count) {
  constexpr int kSeeds = 20;
  double sum_squares = 0;
  for (uint64_t seed = 0; seed < kSeeds; ++seed) {
    double estimate = 0;
    for (uint32_t i = 0; i < count; ++i) {
      const double x = sampler.Sample(i, 0, seed), y = sampler.Sample(i, 1, seed);
      estimate += x * std::exp(x) * y * std::exp(y);
    }
    estimate /= count;
    sum_squares += (estimate - 1) * (estimate - 1);
  }
  return std::sqrt(sum_squares / kSeeds);
}

TEST_F(SamplerFamilyTest, IntegrationErrorFollowsTheTheory) {
  // Theory for smooth integrands in two dimensions: independent points
  // ~ N^-1/2 (≈ 0.08 here), jittered ~ N^-1, Owen-scrambled (0, m, 2)-nets
  // (sobol, hammersley with N = 2^m) ~ N^-3/2 up to a log.
  constexpr uint32_t kCount = 256;
  const double independent = RmsError(*Make("independent"), kCount);
  const double stratified = RmsError(*Make("stratified", kCount), kCount);
  const double latin = RmsError(*Make("latin_hypercube", kCount), kCount);
  const double sobol = RmsError(*Make("sobol"), kCount);
  const double hammersley = RmsError(*Make("hammersley", kCount), kCount);
  const double halton = RmsError(*Make("halton"), kCount);
  const std::string errors = "N 256: independent " + std::to_string(independent) +
                             ", stratified " + std::to_string(stratified) + ", latin_hypercube " +
                             std::to_string(latin) + ", sobol " + std::to_string(sobol) +
                             ", hammersley " + std::to_string(hammersley) + ", halton " +
                             std::to_string(halton);
  EXPECT_LT(stratified, 0.25 * independent) << errors;
  // Latin hypercubes remove only the additive part of the variance.
  EXPECT_LT(latin, 0.75 * independent) << errors;
  EXPECT_LT(sobol, 0.5 * stratified) << errors;
  EXPECT_LT(hammersley, 0.5 * stratified) << errors;
  // Halton's first 2^a·3^b points put one point in each box of 2^-a by
  // 3^-b, so it is a net only at multiples of such products. 256 is no
  // multiple of 3: there scrambled Halton is only as good as jittered
  // sampling (both ~ N^-1; measured equal over 400 seeds), still far
  // ahead of independent points.
  EXPECT_LT(halton, 0.2 * independent) << errors;
  // At N = 288 = 2^5·3^2 it is a net in both bases and pulls ahead.
  constexpr uint32_t kHaltonCount = 288;
  const double halton_288 = RmsError(*Make("halton"), kHaltonCount);
  const double stratified_288 = RmsError(*Make("stratified", kHaltonCount), kHaltonCount);
  const std::string errors_288 = "N 288: halton " + std::to_string(halton_288) + ", stratified " +
                                 std::to_string(stratified_288);
  EXPECT_LT(halton_288, 0.6 * stratified_288) << errors_288;
  RecordProperty("rms_errors", errors + "; " + errors_288);
}

TEST_F(SamplerFamilyTest, RandomPermutationIsAUniformBijection) {
  // A bijection of [0, n) for every n and seed.
  for (uint32_t n = 1; n <= 300; ++n)
    for (uint64_t seed : {0ull, 1ull, 0x0123456789abcdefull, ~0ull}) {
      std::vector<int> hit(n, 0);
      for (uint32_t i = 0; i < n; ++i) ++hit[RandomPermutation(i, n, seed)];
      for (uint32_t j = 0; j < n; ++j) ASSERT_EQ(hit[j], 1) << "n " << n << " seed " << seed;
    }
  // Over seeds, the pair (π(0), π(1)) takes each of its n(n-1) values
  // equally often, for small n (ranked keys) and larger n (Feistel).
  constexpr int kSeeds = 100000;
  for (uint32_t n : {2u, 3u, 13u, 17u, 37u, 100u}) {
    std::vector<double> counts(n * n, 0);
    for (uint64_t seed = 0; seed < kSeeds; ++seed) {
      const uint64_t hashed = Hash(seed);
      ++counts[RandomPermutation(0, n, hashed) * n + RandomPermutation(1, n, hashed)];
    }
    const double expected = double(kSeeds) / (n * (n - 1));
    double chi2 = 0;
    for (uint32_t a = 0; a < n; ++a)
      for (uint32_t b = 0; b < n; ++b) {
        const double observed = counts[a * n + b];
        if (a == b) {
          ASSERT_EQ(observed, 0) << "n " << n;
          continue;
        }
        chi2 += (observed - expected) * (observed - expected) / expected;
      }
    EXPECT_LT(chi2, ChiSquareQuantile999(n * (n - 1) - 1)) << "n " << n;
  }
}

TEST_F(SamplerFamilyTest, StratumFloatStaysInItsStratum) {
  for (uint32_t count : {1u, 3u, 7u, 10u, 1000u, 12345u, (1u << 24) - 1, 1u << 24})
    for (uint32_t stratum : {0u, 1u, count / 3, count / 2, count - 2, count - 1}) {
      if (stratum >= count) continue;
      for (uint32_t bits : {0u, 1u << 8, 0x7fffffffu, 0xfffffeffu, 0xffffffffu}) {
        const float x = StratumFloat(stratum, count, bits);
        ASSERT_LT(x, 1.0f);
        ASSERT_EQ(Stratum(x, count), stratum) << "count " << count << " bits " << bits;
      }
    }
}

// SamplePairs is Sample for many points at once, bit for bit, for every
// sampler (those that override it and those that inherit the loop).
TEST_F(SamplerFamilyTest, SamplePairsGivesSamplesValuesExactly) {
  std::vector<uint64_t> indices, seeds;
  for (uint64_t k = 0; k < 300; ++k) {
    indices.push_back(k % 7 == 0 ? (k << 22) + k : k * 37 % 256);
    seeds.push_back(Hash(uint64_t(42), k / 4));
  }
  for (const char* name : {"sobol", "zsobol", "sobol_nd", "independent", "stratified", "latin_hypercube",
                           "hammersley", "halton"}) {
    const bool counted = std::find(std::begin(kCounted), std::end(kCounted), std::string(name)) != std::end(kCounted);
    const std::unique_ptr<Sampler> sampler = Make(name, counted ? 256 : 0);
    for (uint32_t pair : {0u, 1u, 3u, 130u, 500u}) {
      std::vector<float> out(2 * indices.size());
      sampler->SamplePairs(indices, seeds, pair, out);
      for (size_t k = 0; k < indices.size(); ++k)
        for (uint32_t c = 0; c < 2; ++c)
          ASSERT_EQ(out[2 * k + c], sampler->Sample(indices[k], 2 * pair + c, seeds[k]))
              << name << " pair " << pair << " point " << k;
    }
  }
}


// zsobol's batch kernel takes the runs of points a job makes (one seed,
// AtPixel's indices): it gives Sample's values too, for even and odd
// powers of two, with runs that do not fill its blocks.
TEST_F(SamplerFamilyTest, ZSobolSamplePairsOfAJobsPointsGivesSamplesValues) {
  const std::unique_ptr<Sampler> sampler = Make("zsobol", 0);
  for (uint32_t spp : {8u, 16u}) {
    std::vector<uint64_t> indices, seeds;
    for (uint32_t pixel = 0; pixel < 37; ++pixel)
      for (uint32_t s = 0; s < spp; ++s) {
        const Sampler::FilmPoint at = sampler->AtPixel(pixel % 64, pixel / 3, 64, 48, s, spp, 7);
        indices.push_back(at.index);
        seeds.push_back(at.seed);
      }
    for (uint32_t pair : {0u, 2u, 300u}) {
      std::vector<float> out(2 * indices.size());
      sampler->SamplePairs(indices, seeds, pair, out);
      for (size_t k = 0; k < indices.size(); ++k)
        for (uint32_t c = 0; c < 2; ++c)
          ASSERT_EQ(out[2 * k + c], sampler->Sample(indices[k], 2 * pair + c, seeds[k]))
              << "spp " << spp << " pair " << pair << " point " << k;
    }
  }
}

// Whether the points (pairs of coordinates in [0,1)) put exactly one point
// in each elementary interval of area 1/n, n = points.size() a power of 2:
// a (0, m, 2)-net.
bool IsZeroNet(const std::vector<std::array<float, 2>>& points) {
  const uint32_t n = uint32_t(points.size());
  const int m = std::countr_zero(n);
  for (int k = 0; k <= m; ++k) {
    const uint32_t columns = 1u << k, rows = n >> k;
    std::vector<int> count(n, 0);
    for (const auto& p : points) ++count[Stratum(p[1], rows) * columns + Stratum(p[0], columns)];
    for (int c : count)
      if (c != 1) return false;
  }
  return true;
}

// zsobol's points of pixel (x, y), samples 0..spp-1, in dimensions 2·pair, 2·pair + 1.
std::vector<std::array<float, 2>> PixelPoints(const Sampler& sampler, uint32_t x, uint32_t y, uint32_t width,
                                              uint32_t height, uint32_t spp, uint32_t pair, uint64_t seed) {
  std::vector<std::array<float, 2>> points;
  for (uint32_t s = 0; s < spp; ++s) {
    const Sampler::FilmPoint at = sampler.AtPixel(x, y, width, height, s, spp, seed);
    points.push_back({sampler.Sample(at.index, 2 * pair, at.seed), sampler.Sample(at.index, 2 * pair + 1, at.seed)});
  }
  return points;
}

// Each pixel's samples are a (0, m, 2)-net in every pair of dimensions,
// for even and odd powers of two, and in the padded dimensions too.
TEST_F(SamplerFamilyTest, ZSobolPixelsAreNets) {
  const auto sampler = Make("zsobol");
  for (uint32_t spp : {1u, 2u, 8u, 16u, 64u})
    for (uint32_t pair : {0u, 1u, 5u, 40u})
      for (uint64_t seed : {uint64_t(1), uint64_t(77)})
        for (auto [x, y] : {std::pair{0u, 0u}, std::pair{13u, 7u}, std::pair{63u, 31u}})
          ASSERT_TRUE(IsZeroNet(PixelPoints(*sampler, x, y, 64, 48, spp, pair, seed)))
              << "spp " << spp << " pair " << pair << " pixel " << x << "," << y;
}

// The blue-noise property: the samples of an aligned 2^k × 2^k block of
// pixels together are a (0, m, 2)-net too, so neighbours' errors differ.
// Padded per-pixel sequences do not have it.
TEST_F(SamplerFamilyTest, ZSobolNeighbouringPixelsAreStratifiedTogether) {
  const auto zsobol = Make("zsobol");
  const auto padded = Make("sobol");
  int padded_nets = 0;
  for (uint32_t spp : {1u, 2u, 4u})
    for (uint32_t block : {2u, 4u})
      for (uint32_t pair : {1u, 3u})
        for (uint32_t corner : {0u, 8u}) {
          std::vector<std::array<float, 2>> together, independent;
          for (uint32_t y = corner; y < corner + block; ++y)
            for (uint32_t x = corner; x < corner + block; ++x) {
              const auto points = PixelPoints(*zsobol, x, y, 32, 32, spp, pair, 5);
              together.insert(together.end(), points.begin(), points.end());
              const auto own = PixelPoints(*padded, x, y, 32, 32, spp, pair, 5);
              independent.insert(independent.end(), own.begin(), own.end());
            }
          EXPECT_TRUE(IsZeroNet(together)) << "spp " << spp << " block " << block << " pair " << pair;
          padded_nets += IsZeroNet(independent);
        }
  EXPECT_LT(padded_nets, 4);
}

TEST_F(SamplerFamilyTest, ZSobolRefusesMoreThanTwoToThe32Points) {
  const auto sampler = Make("zsobol");
  EXPECT_NO_THROW(sampler->AtPixel(0, 0, 4096, 4096, 0, 256, 1));
  EXPECT_THROW(sampler->AtPixel(0, 0, 4096, 4096, 0, 512, 1), Error);
  EXPECT_THROW(sampler->AtPixel(0, 0, 70000, 2, 0, 1, 1), Error);
}

}  // namespace
}  // namespace yarf
