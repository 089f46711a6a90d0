// Tests of the sampler plugins (samplers/*.cc), loaded through the
// registry as yarfd loads them: determinism, range, the (0, m, 2)-net
// stratification of sobol's 2-D blocks, and sobol's advantage over
// independent numbers in discrepancy and integration error.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
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

namespace yarf {
namespace {

constexpr const char* kSamplers[] = {"independent", "sobol"};

class SamplerTest : public testing::Test {
 protected:
  SamplerTest() { registry_.LoadDirectory(YARF_PLUGIN_DIR); }

  std::unique_ptr<Sampler> Make(const std::string& name) const {
    return registry_.CreateAs<Sampler>(name, Properties());
  }

  Registry registry_;
};

// Points first..first+count-1, coordinates (dimension, dimension + 1).
std::vector<std::array<double, 2>> Points2D(const Sampler& sampler, uint64_t first, uint32_t count,
                                            uint32_t dimension, uint64_t seed) {
  std::vector<std::array<double, 2>> points(count);
  for (uint32_t i = 0; i < count; ++i)
    points[i] = {sampler.Sample(first + i, dimension, seed),
                 sampler.Sample(first + i, dimension + 1, seed)};
  return points;
}

// L2 star discrepancy by Warnock's formula: the root mean square, over
// all anchored boxes [0, y), of (fraction of points inside - box volume).
double L2StarDiscrepancy(const std::vector<std::array<double, 2>>& points) {
  const double n = double(points.size());
  double cross = 0, pairs = 0;
  for (const auto& p : points) {
    cross += (1 - p[0] * p[0]) * (1 - p[1] * p[1]);
    for (const auto& q : points)
      pairs += (1 - std::max(p[0], q[0])) * (1 - std::max(p[1], q[1]));
  }
  return std::sqrt(1.0 / 9.0 - cross / (2 * n) + pairs / (n * n));
}

TEST_F(SamplerTest, RegistersWithItsInterface) {
  for (const char* name : kSamplers) {
    ASSERT_TRUE(registry_.Has(name)) << name;
    const auto sampler = Make(name);
    EXPECT_EQ(sampler->Describe().interfaces, std::vector<std::string>{Sampler::kInterface});
  }
}

TEST_F(SamplerTest, TakesNoProperties) {
  for (const char* name : kSamplers) {
    Properties props;
    props.Set("seed_offset", int64_t(3));
    EXPECT_THROW(registry_.Create(name, props), Error) << name;
  }
}

TEST_F(SamplerTest, IsDeterministic) {
  for (const char* name : kSamplers) {
    const auto first = Make(name), second = Make(name);
    testing_support::ExpectDeterministic(*first, *second, name);
  }
}

TEST_F(SamplerTest, ValuesLieInUnitInterval) {
  const uint64_t far_indices[] = {(1ull << 32) - 1, 1ull << 32, (1ull << 32) + 1, 1ull << 63,
                                  std::numeric_limits<uint64_t>::max()};
  for (const char* name : kSamplers) {
    const auto sampler = Make(name);
    auto check = [&](uint64_t index, uint32_t dimension, uint64_t seed) {
      const float value = sampler->Sample(index, dimension, seed);
      EXPECT_GE(value, 0.0f) << name << " " << index << " " << dimension << " " << seed;
      EXPECT_LT(value, 1.0f) << name << " " << index << " " << dimension << " " << seed;
    };
    for (uint64_t seed : {uint64_t(0), uint64_t(5), std::numeric_limits<uint64_t>::max()}) {
      for (uint64_t index = 0; index < 4096; ++index)
        for (uint32_t dimension = 0; dimension < 8; ++dimension) check(index, dimension, seed);
      for (uint64_t index : far_indices)
        for (uint32_t dimension : {0u, 1u, 1000u, std::numeric_limits<uint32_t>::max()})
          check(index, dimension, seed);
    }
  }
}

TEST_F(SamplerTest, SeedsAndDimensionsGiveDifferentNumbers) {
  for (const char* name : kSamplers) {
    const auto sampler = Make(name);
    int same_seed = 0, same_dimension = 0;
    for (uint64_t index = 0; index < 256; ++index) {
      same_seed += sampler->Sample(index, 0, 1) == sampler->Sample(index, 0, 2);
      same_dimension += sampler->Sample(index, 0, 1) == sampler->Sample(index, 2, 1);
    }
    EXPECT_LT(same_seed, 4) << name;
    EXPECT_LT(same_dimension, 4) << name;
  }
}

TEST_F(SamplerTest, SobolBlocksAreZeroMTwoNets) {
  // Every aligned run of 2^m points, in every pair of dimensions (2k,
  // 2k+1), puts exactly one point in each elementary interval
  // [i/2^a, (i+1)/2^a) × [j/2^(m-a), (j+1)/2^(m-a)).
  const auto sobol = Make("sobol");
  for (int m = 4; m <= 8; ++m)
    for (uint64_t seed : {0ull, 1ull, 77ull, 0xdeadbeefcafeull})
      for (uint32_t pair : {0u, 1u, 5u, 31u})
        for (uint64_t run : {0ull, 3ull}) {
          const uint32_t count = 1u << m;
          const auto points = Points2D(*sobol, run * count, count, 2 * pair, seed);
          for (int a = 0; a <= m; ++a) {
            std::vector<int> occupied(count, 0);
            for (const auto& p : points) {
              const uint32_t i = uint32_t(p[0] * (1u << a));
              const uint32_t j = uint32_t(p[1] * (1u << (m - a)));
              ++occupied[(i << (m - a)) | j];
            }
            for (uint32_t cell = 0; cell < count; ++cell)
              ASSERT_EQ(occupied[cell], 1)
                  << "m " << m << ", seed " << seed << ", dimensions " << 2 * pair << "-"
                  << 2 * pair + 1 << ", run " << run << ", interval shape 2^" << a << " x 2^"
                  << m - a << ", cell " << cell;
          }
        }
}

TEST_F(SamplerTest, SobolHasLowerDiscrepancyThanIndependent) {
  constexpr uint32_t kCount = 256;
  constexpr int kSeeds = 16;
  const auto sobol = Make("sobol"), independent = Make("independent");
  for (uint32_t dimension : {0u, 6u}) {
    double sobol_sum = 0, independent_sum = 0;
    for (uint64_t seed = 0; seed < kSeeds; ++seed) {
      sobol_sum += L2StarDiscrepancy(Points2D(*sobol, 0, kCount, dimension, seed));
      independent_sum += L2StarDiscrepancy(Points2D(*independent, 0, kCount, dimension, seed));
    }
    // Random points have L2 star discrepancy ~ 0.2/√N, a (0,m,2)-net
    // ~ log N / N: about 0.013 against 0.004 here.
    EXPECT_LT(sobol_sum, 0.5 * independent_sum) << "dimensions " << dimension;
  }
}

TEST_F(SamplerTest, SobolIntegratesASmoothFunctionBetter) {
  // f(x, y) = x e^x · y e^y has ∫∫ f = 1 over the unit square.
  constexpr uint32_t kCount = 256;
  constexpr int kSeeds = 64;
  auto rms_error = [&](const Sampler& sampler, uint32_t dimension) {
    double sum_squares = 0;
    for (uint64_t seed = 0; seed < kSeeds; ++seed) {
      double estimate = 0;
      for (const auto& p : Points2D(sampler, 0, kCount, dimension, seed))
        estimate += p[0] * std::exp(p[0]) * p[1] * std::exp(p[1]);
      estimate /= kCount;
      sum_squares += (estimate - 1) * (estimate - 1);
    }
    return std::sqrt(sum_squares / kSeeds);
  };
  const auto sobol = Make("sobol"), independent = Make("independent");
  for (uint32_t dimension : {0u, 10u}) {
    const double sobol_error = rms_error(*sobol, dimension);
    const double independent_error = rms_error(*independent, dimension);
    // Owen-scrambled nets converge as N^-1.5 for smooth integrands, random
    // points as N^-0.5: a factor of ~16 at N = 256.
    EXPECT_LT(sobol_error, 0.2 * independent_error)
        << "dimensions " << dimension << ": sobol " << sobol_error << ", independent "
        << independent_error;
  }
}

TEST_F(SamplerTest, IndependentHasUniformMoments) {
  const auto sampler = Make("independent");
  constexpr int kCount = 200000;
  double sum = 0, sum_squares = 0, lag_product = 0;
  float previous = sampler->Sample(0, 3, 4);
  for (int k = 0; k < kCount; ++k) {
    const float value = sampler->Sample(k, 3, 4);
    sum += value;
    sum_squares += double(value) * value;
    if (k > 0) lag_product += double(value) * previous;
    previous = value;
  }
  // Standard errors: 0.29/√N ≈ 6.5e-4 for the mean, similar for the rest.
  EXPECT_NEAR(sum / kCount, 0.5, 3e-3);
  EXPECT_NEAR(sum_squares / kCount, 1.0 / 3.0, 3e-3);
  // Consecutive indices are uncorrelated: E[x_k x_(k+1)] = 1/4.
  EXPECT_NEAR(lag_product / (kCount - 1), 0.25, 3e-3);
}

TEST(UnitFloatTest, StaysBelowOne) {
  EXPECT_EQ(ToUnitFloat(0), 0.0f);
  EXPECT_LT(ToUnitFloat(0xffffffffu), 1.0f);
  EXPECT_EQ(ToUnitFloat(0x80000000u), 0.5f);
  EXPECT_NE(Hash(1, 2), Hash(2, 1));
  EXPECT_EQ(Hash(1, 2, 3), Hash(1, 2, 3));
}

}  // namespace
}  // namespace yarf
