// rqmc — randomized quasi-Monte Carlo: independent randomizations of the
// job's sampler's point set.
//
// Integrate: the budget is split into R replicates of n = ⌊evaluations / R⌋
// points (`evaluations` in the result is R · n). Replicate r takes points
// 0 … n−1 of the sampler's sequence for the seed Hash(seed, r), mapped to
// the box, and gives its own mean-sample estimate Q_r = V · (1/n) Σ f(x_i).
// With a randomized low-discrepancy sampler ("sobol_nd": the Sobol
// sequence in all d dimensions, Owen-scrambled) the Q_r are independent
// and unbiased, each far more accurate than plain Monte Carlo on smooth
// integrands, so
//   estimate = (1/R) Σ_r Q_r,   σ = s_Q / √R,
// with s_Q the sample standard deviation of the Q_r: an honest error bar
// for a quasi-Monte Carlo rule, which has none of its own. With sobol_nd,
// make n a power of two (the point set is then a scrambled net); yarf's
// Python integrate() takes it for rqmc unless told otherwise. Any sampler
// works; with "independent" this is plain Monte Carlo in batches, and the
// padded "sobol" (random pairings of 2-D nets) is a net only pair by pair.
//
// Parameters: RqmcIntegrator::Parameters() below.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "integration_box.h"
#include "yarf/support/hash.h"
#include "yarf/plugin.h"

namespace yarf {
namespace {

// Points per Evaluate call: large, since f may live in another process;
// several small replicates share one call.
constexpr uint64_t kBatch = 8192;

class RqmcIntegrator final : public Integrator {
 public:
  static ParameterSchema Parameters() {
    using P = Parameter;
    return {
        P::Int("replicates").Default(16).Range(2, 1 << 20).Doc("independent randomizations R"),
    };
  }

  explicit RqmcIntegrator(const Properties& props) : replicates_(props.Int("replicates", 16)) {
    if (replicates_ < 2 || replicates_ > (int64_t(1) << 20))
      throw Error("property 'replicates' must be in [2, 2^20]");
  }

  IntegrationResult Integrate(Function& f, std::span<const double> lower,
                              std::span<const double> upper, uint64_t evaluations, uint64_t seed,
                              const Sampler& sampler) override {
    const uint32_t d = f.InputDimensions(), k = f.OutputDimensions();
    CheckProperBox(lower, upper, d);
    const uint64_t replicates = uint64_t(replicates_);
    if (evaluations < replicates)
      throw Error("rqmc needs at least one evaluation per replicate (" + std::to_string(replicates) + ")");
    const uint64_t n = evaluations / replicates;
    const uint64_t total = n * replicates;

    const double volume = BoxVolume(lower, upper);

    // Replicate sums, R·k: small beside the points.
    std::vector<double> sums(replicates * k, 0.0);
    std::vector<float> points, values;
    for (uint64_t first = 0; first < total; first += kBatch) {
      const uint64_t count = std::min(kBatch, total - first);
      points.resize(count * d);
      values.resize(count * k);
      // The call's points, replicate by replicate.
      for (uint64_t done = 0; done < count;) {
        const uint64_t r = (first + done) / n, index = (first + done) % n;
        const uint32_t run = uint32_t(std::min(count - done, n - index));
        sampler.Generate(index, run, d, Hash(seed, r),
                         std::span<float>(points).subspan(done * d, size_t(run) * d));
        done += run;
      }
      MapToBox(points, lower, upper);
      f.Evaluate(points, values);
      for (uint64_t i = 0; i < count; ++i) {
        const uint64_t r = (first + i) / n;
        for (uint32_t c = 0; c < k; ++c) sums[r * k + c] += values[i * k + c];
      }
    }

    IntegrationResult result;
    result.evaluations = total;
    const double R = double(replicates);
    for (uint32_t c = 0; c < k; ++c) {
      double mean = 0;
      for (uint64_t r = 0; r < replicates; ++r) mean += volume * sums[r * k + c] / double(n);
      mean /= R;
      double ss = 0;
      for (uint64_t r = 0; r < replicates; ++r) {
        const double q = volume * sums[r * k + c] / double(n) - mean;
        ss += q * q;
      }
      result.estimate.push_back(mean);
      result.standard_error.push_back(std::sqrt(ss / (R - 1) / R));
    }
    return result;
  }

 private:
  int64_t replicates_;
};

}  // namespace
}  // namespace yarf

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::RqmcIntegrator>(
      registrar, "rqmc", "1.0.0", "randomized quasi-Monte Carlo (error from independent randomizations)");
}
