// latin_hypercube — Latin hypercube sampling
//
// In every dimension, the `sample_count` points of a block occupy each of
// the N strata [j/N, (j+1)/N) exactly once, jittered uniformly inside it
// (McKay, Beckman & Conover 1979). Which point takes which stratum is an
// independent random permutation per (seed, dimension, block), so the
// dimensions are not correlated with each other. Point i belongs to block
// i / N; every block of N consecutive indices is a fresh Latin hypercube.
//
// Every one-dimensional projection is stratified, so integrands that are
// close to a sum of functions of one variable converge much faster than
// with independent points; the variance is never more than that of N - 1
// independent points (Owen 1997).
//
// Deterministic and stateless: the same (index, dimension, seed) always
// gives the same number in [0, 1).
//
// Parameters: LatinHypercube::Parameters() below.
#include <cstdint>

#include "sample_count.h"
#include "yarf/support/hash.h"
#include "yarf/support/owen.h"
#include "yarf/plugin.h"

namespace {

// Distinct salts so that the stratum permutation and the jitter never
// share a hash input with each other or with other samplers.
constexpr uint64_t kPermutationSalt = 0x4c4853ull;  // "LHS"
constexpr uint64_t kJitterSalt = 0x4c4a4954ull;     // "LJIT"

class LatinHypercube final : public yarf::Sampler {
 public:
  static yarf::ParameterSchema Parameters() { return {yarf::SampleCountParameter("points per block N")}; }

  explicit LatinHypercube(const yarf::Properties& props) : count_(yarf::ReadSampleCount(props, "latin_hypercube")) {}

  float Sample(uint64_t index, uint32_t dimension, uint64_t seed) const override {
    const uint64_t block = index / count_;
    const uint32_t stratum = yarf::RandomPermutation(
        uint32_t(index % count_), count_, yarf::Hash(seed, dimension, block, kPermutationSalt));
    const uint32_t jitter = uint32_t(yarf::Hash(seed, index, dimension, kJitterSalt) >> 32);
    return yarf::StratumFloat(stratum, count_, jitter);
  }

 private:
  uint32_t count_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<LatinHypercube>(registrar, "latin_hypercube", "1.0.0",
                                 "Latin hypercube sampling: every dimension stratified in N strata");
}
