// independent — independent uniform random numbers
//
// Every coordinate of every point is an independent uniform number in
// [0, 1): a hash of (seed, index, dimension). The sampler keeps no state,
// so coordinates can be produced in any order, by any thread, and the
// same (index, dimension, seed) always gives the same number. Error of a
// Monte Carlo estimate falls as 1/√N.
//
// Parameters: none (Independent::Parameters() below).
#include <cstdint>
#include <span>

#include "yarf/support/hash.h"
#include "yarf/plugin.h"

namespace {

// The high half of a hash as a uniform number: its best-mixed bits.
float UniformOf(uint64_t hash) { return yarf::ToUnitFloat(uint32_t(hash >> 32)); }

// Sample's values for coordinates 2·pair and 2·pair + 1 of `count`
// points, the two sharing their points' hash of (seed, index); built for
// AVX-512, AVX2 and the baseline and picked at load time from the CPU
// (the loop vectorises its 64-bit multiplies).
[[gnu::target_clones("arch=x86-64-v4", "avx2", "default")]]
void IndependentPairs(const uint64_t* indices, const uint64_t* seeds, size_t count, uint32_t pair, float* out) {
  for (size_t k = 0; k < count; ++k) {
    const uint64_t point = yarf::Hash(seeds[k], indices[k]);
    out[2 * k] = UniformOf(yarf::HashOnto(point, 2 * pair));
    out[2 * k + 1] = UniformOf(yarf::HashOnto(point, 2 * pair + 1));
  }
}

class Independent final : public yarf::Sampler {
 public:
  static yarf::ParameterSchema Parameters() { return {}; }

  explicit Independent(const yarf::Properties&) {}

  float Sample(uint64_t index, uint32_t dimension, uint64_t seed) const override {
    return UniformOf(yarf::Hash(seed, index, dimension));
  }

  void SamplePairs(std::span<const uint64_t> indices, std::span<const uint64_t> seeds, uint32_t pair,
                   std::span<float> out) const override {
    IndependentPairs(indices.data(), seeds.data(), indices.size(), pair, out.data());
  }
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Independent>(registrar, "independent", "1.0.0",
                              "Independent uniform random numbers (stateless hash)");
}
