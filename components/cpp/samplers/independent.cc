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

#include "yarf/support/hash.h"
#include "yarf/plugin.h"

namespace {

class Independent final : public yarf::Sampler {
 public:
  static yarf::ParameterSchema Parameters() { return {}; }

  explicit Independent(const yarf::Properties&) {}

  float Sample(uint64_t index, uint32_t dimension, uint64_t seed) const override {
    // The high half of the hash: its best-mixed bits.
    return yarf::ToUnitFloat(uint32_t(yarf::Hash(seed, index, dimension) >> 32));
  }
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<Independent>(registrar, "independent", "1.0.0",
                              "Independent uniform random numbers (stateless hash)");
}
