// stratified — jittered sampling on a grid
//
// Coordinates come in pairs (2k, 2k+1). In each pair, the `sample_count`
// points of a block fall one per cell of an n×m grid with n·m =
// sample_count: √N×√N when N is a square, otherwise the factorisation
// closest to square (n ≤ m, n along dimension 2k; a prime N gives a 1×N
// grid, stratified along 2k+1 only). Which point takes which cell is a
// random permutation per (seed, pair, block), so pairs are not correlated
// with each other, and each point is jittered uniformly inside its cell.
// Point i belongs to block i / N; every block of N consecutive indices is
// a fresh stratified set (new permutation, new jitter). A lone last
// dimension (odd count) is stratified the same way along n.
//
// For smooth integrands the error falls as N^-1 in two dimensions rather
// than N^-1/2 for independent points, but only at the full N of a block.
//
// Deterministic and stateless: the same (index, dimension, seed) always
// gives the same number in [0, 1).
//
// Parameters: Stratified::Parameters() below.
#include <cstdint>

#include "sample_count.h"
#include "yarf/support/hash.h"
#include "yarf/support/owen.h"
#include "yarf/plugin.h"

namespace {

// Distinct salts so that the cell permutation and the jitter never share
// a hash input with each other or with other samplers.
constexpr uint64_t kPermutationSalt = 0x43454c4cull;  // "CELL"
constexpr uint64_t kJitterSalt = 0x4a4954ull;         // "JIT"

class Stratified final : public yarf::Sampler {
 public:
  static yarf::ParameterSchema Parameters() { return {yarf::SampleCountParameter("points per block N")}; }

  explicit Stratified(const yarf::Properties& props) : count_(yarf::ReadSampleCount(props, "stratified")) {
    // The largest divisor of N not above √N gives the squarest grid.
    columns_ = 1;
    for (uint32_t n = 1; uint64_t(n) * n <= count_; ++n)
      if (count_ % n == 0) columns_ = n;
    rows_ = count_ / columns_;
  }

  float Sample(uint64_t index, uint32_t dimension, uint64_t seed) const override {
    const uint64_t block = index / count_;
    const uint32_t pair = dimension / 2;
    const uint32_t cell = yarf::RandomPermutation(
        uint32_t(index % count_), count_, yarf::Hash(seed, pair, block, kPermutationSalt));
    const uint32_t jitter = uint32_t(yarf::Hash(seed, index, dimension, kJitterSalt) >> 32);
    if (dimension % 2 == 0) return yarf::StratumFloat(cell % columns_, columns_, jitter);
    return yarf::StratumFloat(cell / columns_, rows_, jitter);
  }

 private:
  uint32_t count_;
  uint32_t columns_;  // strata along dimension 2k
  uint32_t rows_;     // strata along dimension 2k+1
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Stratified>(registrar, "stratified", "1.0.0",
                             "Jittered sampling: one point per cell of a grid in each pair of "
                             "dimensions");
}
