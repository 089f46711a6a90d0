// vegas_plus — VEGAS with adaptive stratified sampling, G. P. Lepage's
// VEGAS+ as his `vegas` package runs it by default (Lepage, "Adaptive
// multidimensional integration: VEGAS enhanced", J. Comput. Phys. 439
// (2021) 110386).
//
// Integrate: the map and the stratified sampling of `vegas` (a separable,
// piecewise-linear x(y) from the unit cube onto the box, refined after
// every iteration with the damping exponent α from the smoothed bin
// averages of J² f² of the first output; equal hypercubes of y-space, each
// estimated apart; see vegas.cc), with the points no longer the same in
// every hypercube. The map alone can only follow a product of one-axis
// densities, so an integrand with several peaks off the diagonal of that
// product (two peaks on the diagonal of the cube give 2^d crossings of the
// map's dense regions, of which only two hold a peak) wastes points on
// empty regions. Adaptive stratification corrects this, as Lepage does:
// the hypercubes are chosen so that a quarter of an iteration's points
// gives each at least 2, and hypercube h then gets
//   n_h = max(2, ⌊n / (4 H)⌋) + ⌊(3/4) n · σ_h^β / Σ_h' σ_h'^β⌋
// where σ_h² = V_h² s_h² / n_h is the variance of hypercube h's part of the
// previous iteration's estimate (s_h² the sample variance of J f of the
// first output among its points). β = 1 approaches the allocation that
// minimises the variance when the σ_h are known; β < 1 hedges against σ_h
// estimated from few points; β = 0 is `vegas`. The first iteration
// samples the hypercubes evenly.
//
// Iterations, their weighting by inverse variance with χ²/dof and Q, the
// discarded warm-up iterations, the budget (spent exactly, never
// exceeded) and the batches of up to 16384 points per call to f.Evaluate
// are as in `vegas`, and so are the differences from Lepage written
// there. One more: because points are not uniform in y, each point enters
// the map's bin averages of (J f)² with the weight V_h / n_h, the inverse
// of its sampling density, so that they still estimate the averages of
// J² f² over the slabs of the cube whatever the allocation; Lepage's bins
// average the points unweighted, which leans the map towards the
// hypercubes that had many points.
//
// Parameters: VegasPlusIntegrator::Parameters() below: those of vegas
// (defaults explained in vegas.cc) and beta, whose default 0.75 is
// Lepage's.

#include <cstdint>
#include <span>

#include "vegas_image.h"
#include "vegas_map.h"
#include "vegas_run.h"
#include "yarf/plugin.h"

namespace yarf {
namespace {

class VegasPlusIntegrator final : public Integrator {
 public:
  static ParameterSchema Parameters() {
    ParameterSchema schema = VegasSettings::Parameters();
    schema.push_back(
        Parameter::Float("beta").Default(0.75).Range(0, 1).Doc("exponent of the sample allocation; 0 is vegas"));
    return schema;
  }

  explicit VegasPlusIntegrator(const Properties& props) : settings_(props), beta_(props.Float("beta", 0.75)) {
    if (!(beta_ >= 0 && beta_ <= 1)) throw Error("property 'beta' must be in [0, 1]");
    settings_.CheckDiscard();
  }

  IntegrationResult Integrate(Function& f, std::span<const double> lower,
                              std::span<const double> upper, uint64_t evaluations, uint64_t seed,
                              const Sampler& sampler) override {
    return IntegrateVegas("vegas_plus", settings_, beta_, f, lower, upper, evaluations, seed, sampler);
  }

  void Render(Transport& transport, const SceneView& scene, const Sampler& sampler,
              RenderTarget& target) override {
    RenderWithVegasMap(transport, scene, sampler, target, settings_.ImageBins(), settings_.alpha);
  }

 private:
  VegasSettings settings_;
  double beta_;
};

}  // namespace
}  // namespace yarf

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::VegasPlusIntegrator>(
      registrar, "vegas_plus", "1.0.0",
      "VEGAS+ adaptive importance and stratified sampling Monte Carlo (Lepage 2021)");
}
