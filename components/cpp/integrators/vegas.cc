// vegas — adaptive importance-sampling Monte Carlo, G. P. Lepage's
// classic algorithm as his `vegas` package runs it with beta = 0 (Lepage,
// "A new algorithm for adaptive multidimensional integration", J. Comput.
// Phys. 27 (1978) 192; "Adaptive multidimensional integration: VEGAS
// enhanced", J. Comput. Phys. 439 (2021) 110386).
//
// Integrate: a map x(y) from the unit cube onto the box is built one axis
// at a time. Along each axis [0, 1) is cut into B equal steps in y and
// step i is stretched linearly onto the interval [x_i, x_{i+1}] of that
// axis, so ∫ f dx = ∫ J(y) f(x(y)) dy with J = Π_axes B · (x_{i+1} - x_i).
// The integral over y is estimated by stratified Monte Carlo: the unit
// cube is cut into H equal hypercubes (M or M + 1 per axis, as many as
// leave at least 2 points each) and every hypercube gets the same number
// of points n_h = n / H, uniform inside it. The estimate of an iteration is
// Σ_h V_h mean_h(J f), its variance Σ_h V_h² s_h² / n_h, with V_h = 1 / H and
// s_h² the sample variance of J f among the hypercube's points; every
// output of f is estimated this way.
//
// After every iteration the grid adapts to the first output of f: bin i of
// an axis collects d_i, the mean of (J f)² over the points that fell in it,
// an estimate of the average of J² f² over that slab of the cube (the
// slabs are equally wide in y, so Σ_i d_i / B estimates ∫ J² f² dy, the
// second moment that the map should minimise). A mean, rather than a sum,
// leaves out the noise of how many points each bin happened to get, so
// that a flat integrand leaves the grid where it is. As Lepage does, the
// d_i are smoothed with their neighbours (weights 1:6:1, 7:1 at the ends)
// so that one lucky sample does not pull the whole grid, normalised to
// r_i = d_i / Σ d (plus 10^-257, so that a bin where f vanishes keeps
// some width), and damped to w_i = ((1 - r_i) / ln(1/r_i))^α, which keeps
// the ordering of the r_i but compresses their range so that the grid
// moves gradually.
// New edges are placed so that every bin holds an equal share of Σ w, the
// weight being spread evenly inside an old bin. Bins shrink where |f| is
// large: the sampling density in x follows |f| as closely as a product of
// one-axis densities can.
//
// Iterations are combined weighted by inverse variances, every output of
// f separately: estimate I = Σ_t w_t I_t / Σ_t w_t, standard error
// √(Σ_t w_t² σ_t²) / Σ_t w_t, with Lepage's χ² = Σ_t (I_t - I)²/σ_t² over
// dof = T - 1 and Q, the probability of a χ² at least as large, reported
// per output (IntegrationResult::chi2_per_dof, q). Q < 0.05 says the
// iterations disagree beyond their errors: the grid was still moving, or
// the points per iteration are too few for the integrand.
//
// Where yarf differs from Lepage's package:
// - The map's density along each axis never falls below 5% of uniform
//   (kMinDensity in vegas_map.h). Lepage lets regions where f vanishes
//   collapse; the bin straddling a jump of f then grows wide and mostly
//   empty, and its rare points of huge J f leave the variance
//   underestimated (his vegas is within 2σ in a quarter of the runs on
//   Genz's discontinuous family at 10⁴ points; yarf's, in over 90%).
// - The first `discard` iterations only train the grid: their points are
//   spent (and counted in `evaluations`) but their estimates are left out
//   of the average. Lepage includes every iteration of a call and leaves
//   the warm-up to a separate call. A grid that has not found the
//   integrand's peaks yet tends to under-estimate both the integral and
//   its variance, and an iteration with a small σ_t has a large weight.
// - `evaluations` is the total budget, never exceeded and spent exactly:
//   evaluations / iterations per iteration (the remainder to the first
//   ones), and the points that ⌊n / H⌋ per hypercube leaves over go one
//   each to hypercubes spread evenly (Lepage leaves them unspent).
// - When the budget would leave fewer than 1000 points per iteration,
//   fewer iterations are run (at least one) so that every iteration's
//   variance is well estimated; `discard` is then lowered to keep one.
// - One number of bins for every axis; by default Lepage's, a tenth of the
//   points per iteration up to 1000, a multiple of the strata of the most
//   stratified axis.
// - χ² and Q are per output; Lepage's, for an array-valued integrand,
//   is one χ² over all outputs with their correlations.
// - An iteration that measured no spread at all (σ_t = 0: every
//   hypercube's points agreed, as across a step they mostly do) takes the
//   mean weight of those that did, as GSL's VEGAS does; by its 1/σ_t² it
//   would be the answer, with an error of 10⁻¹³ and 10⁹ of it off. When no
//   iteration measured a spread they weigh the same, and the error is
//   their spread about the mean.
// - A bin no point fell in takes its neighbours' mean (J f)², not 0.
// - Iteration t is weighed by w_t = 1/σ_{t-1}², its predecessor's inverse
//   variance (kept or discarded), not its own (Lepage's w_t = 1/σ_t²). Where
//   J f has a heavy tail (an integrable pole such as x^-½) an iteration's
//   σ_t grows with its estimate, and its own weights biased I low: by 10
//   of its σ on average for ∫₀¹ x^-½ at 10⁴ and 10⁵ points (18 and 20 of
//   20 seeds beyond 3σ); by 1.6 and 1.8 now (5 of 20 beyond 3σ: there σ_t
//   itself falls short). See Combination in vegas_map.h.
// An iteration is one or more calls to f.Evaluate of up to 16384 points.
// Iteration t uses the sampler's points after those of the earlier
// iterations, so a result is a pure function of the seed.
//
// Parameters: VegasIntegrator::Parameters() below, Lepage's names where
// he has one (yarf.integrate also takes his nitn and neval). Without
// "bins", a tenth of the points per iteration, at most 1000 (see above;
// 50 when rendering); without "discard", 2, or iterations - 1 when that
// is smaller. alpha's default 0.5 is Lepage's.

#include <cstdint>
#include <span>

#include "vegas_image.h"
#include "vegas_map.h"
#include "vegas_run.h"
#include "yarf/plugin.h"

namespace yarf {
namespace {

class VegasIntegrator final : public Integrator {
 public:
  static ParameterSchema Parameters() { return VegasSettings::Parameters(); }

  explicit VegasIntegrator(const Properties& props) : settings_(props) { settings_.CheckDiscard(); }

  IntegrationResult Integrate(Function& f, std::span<const double> lower,
                              std::span<const double> upper, uint64_t evaluations, uint64_t seed,
                              const Sampler& sampler) override {
    // β = 0: Lepage's classic stratification, the same points in every hypercube.
    return IntegrateVegas("vegas", settings_, 0.0, f, lower, upper, evaluations, seed, sampler);
  }

  void Render(Transport& transport, const SceneView& scene, const Sampler& sampler,
              RenderTarget& target) override {
    RenderWithVegasMap(transport, scene, sampler, target, settings_.ImageBins(), settings_.alpha);
  }

 private:
  VegasSettings settings_;
};

}  // namespace
}  // namespace yarf

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::VegasIntegrator>(registrar, "vegas", "1.0.0",
                                        "VEGAS adaptive importance-sampling Monte Carlo (Lepage 1978)");
}
