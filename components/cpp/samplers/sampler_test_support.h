// Checks shared by the sampler plugin tests (sampler_test.cc,
// sampler_family_test.cc), which hold every Sampler to the same contract.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "yarf/math.h"

namespace yarf::testing_support {

// Sample depends on (index, dimension, seed) alone, so that any thread or
// any instance of the class `name` reproduces a coordinate; `first` and
// `second` are two such instances.
inline void ExpectDeterministic(const Sampler& first, const Sampler& second, const char* name) {
  for (uint64_t seed : {0ull, 1ull, 0x123456789abcdefull})
    for (uint64_t index = 0; index < 300; index += 7)
      for (uint32_t dimension = 0; dimension < 40; dimension += 3) {
        const float value = first.Sample(index, dimension, seed);
        EXPECT_EQ(value, first.Sample(index, dimension, seed)) << name;
        EXPECT_EQ(value, second.Sample(index, dimension, seed)) << name;
      }
  // Generate is the same numbers in a block.
  constexpr uint32_t kCount = 16, kDimensions = 5;
  std::vector<float> block(kCount * kDimensions);
  first.Generate(100, kCount, kDimensions, 9, block);
  for (uint32_t i = 0; i < kCount; ++i)
    for (uint32_t d = 0; d < kDimensions; ++d)
      EXPECT_EQ(block[i * kDimensions + d], second.Sample(100 + i, d, 9)) << name;
}

}  // namespace yarf::testing_support
