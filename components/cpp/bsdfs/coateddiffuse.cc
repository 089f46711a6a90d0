// coateddiffuse — a diffuse base under a dielectric coat, as pbrt-v4's
//
// pbrt-v4's `coateddiffuse` material (its CoatedDiffuseBxDF, a
// LayeredBxDF): a dielectric interface of index `eta` on top, smooth or
// GGX-rough, over a Lambertian base of `reflectance`, with between them a
// slab of `thickness` (in mean free paths) that scatters with `albedo`
// and Henyey–Greenstein's phase function of asymmetry `g` (albedo 0: no
// medium, only the geometric attenuation exp(-thickness / |cos θ|) of each
// crossing). Light inside is followed by a random walk (Guo et al. 2018;
// layered.h) of at most `maxdepth` events, `nsamples` walks per
// evaluation. Unlike roughplastic, which approximates the inside
// analytically, every interreflection under the coat is simulated, so a
// white base under a smooth, clear coat reflects all the light (up to the
// walk's depth limit).
//
// f is stochastic: Evaluate and Pdf return unbiased (Evaluate) or
// approximate (Pdf) estimates computed from random numbers that a hash of
// (wi, wo, uv) seeds, so each call is deterministic and repeatable, and
// the mean over many seeds is f. Two-sided, as pbrt's: below the surface
// it reflects as above. The model only reflects (the base is opaque).
//
// Sampling and MIS. Sample follows a walk from wi until it leaves through
// the top: its weight is the walk's throughput, whose expectation given wo
// is f·|cos θo| / p(wo), p the walk's own (not computable) density of wo.
// The pdf it returns for a non-delta sample is Pdf(wi, wo) at the drawn
// wo (same seed, same number): pbrt's approximate density, the top's
// reflection plus the paths through one bounce on the base, mixed 9:1 with
// the uniform hemisphere so that it is > 0 wherever a walk can leave. A
// path tracer weighing BSDF samples by that pdf and light samples by Pdf
// thus uses one density for both, so the two MIS weights sum to 1 at every
// wo, and the combination stays unbiased although Pdf is not the walk's
// density (Veach 1997, §9.2: any weights that sum to 1 are unbiased). The
// weight is thus not Evaluate·|cos|/pdf: Evaluate and the walk are two
// independent estimates of f. With a smooth coat, the coat's own
// reflection is a delta lobe: pdf its Fresnel factor (its probability),
// weight 1; with a smooth base too and no medium, every path is delta.
// `allowed` is honoured by dropping a drawn lobe it excludes (no sample):
// the weights of the rest still estimate the allowed lobes' part without
// bias, with more variance than drawing only them.
//
// Differences from pbrt-v4 (layered.h): Evaluate's MIS between the walk's
// steps out through the coat and the joins drawn from wo weighs both by
// their own densities at one direction, so that the weights sum to 1
// (pbrt's do not: its f is 7% too bright for a white base under a
// roughness-0.05 coat, by the tests); Evaluate's last event joins nothing,
// so that Evaluate and Sample truncate the walk at the same maxdepth
// (pbrt's f counts one order more than its Sample_f draws); RGB instead
// of sampled wavelengths; Pdf's uniform part covers the hemisphere on
// wi's side (pbrt: the sphere), as nothing is transmitted; Pdf has no
// transport mode (the η² of the coat's two transmissions cancels in it);
// random numbers come from yarf's hash, not pbrt's RNG, so single
// estimates differ while their means agree.
//
// Parameters: CoatedDiffuse::Parameters() below, pbrt-v4's names and
// defaults. A texture's values are clamped into the ranges given.
//
// Lobes: diffuse reflection (the walk), glossy reflection (a rough coat's
// own) or delta reflection (a smooth coat's own).
#include <cstdint>
#include <span>
#include <utility>

#include "layered.h"
#include "yarf/support/scatter_rows.h"
#include "surface_properties.h"
#include "yarf/plugin.h"
#include "yarf/texture.h"

namespace {

using yarf::Vec3;
namespace layered = yarf::layered;

// The layers at row k of a call's points.
struct PointLayers {
  yarf::PointValues<Vec3> reflectance;
  layered::PbrtRoughness::Points roughness;
  layered::Slab::Points slab;
  const layered::Slab& constants;

  layered::Layers<layered::Diffuse> operator()(size_t k) const {
    layered::Layers<layered::Diffuse> layers;
    layers.top = {constants.eta, roughness[k]};
    layers.bottom = {reflectance[k]};
    layers.thickness = slab.thickness[k];
    layers.albedo = slab.albedo[k];
    layers.g = slab.g[k];
    layers.max_depth = constants.max_depth;
    layers.samples = constants.samples;
    return layers;
  }
};

class CoatedDiffuse final : public layered::LayeredSurfaceModel<CoatedDiffuse> {
 public:
  static yarf::ParameterSchema Parameters() {
    return yarf::JoinParameters({
        {yarf::Parameter::RgbTexture("reflectance").Default(0.5).Range(0, 1).Doc("the base's albedo")},
        layered::PbrtRoughnessParameters("", "the coat"),
        {layered::RemapParameter()},
        layered::SlabParameters("eta"),
    });
  }

  explicit CoatedDiffuse(const yarf::Properties& props)
      : reflectance_(yarf::TexturedValue::Color(props, "reflectance", Vec3(0.5f, 0.5f, 0.5f), /*unit=*/true)),
        roughness_(layered::ReadPbrtRoughness(props, "")),
        slab_(layered::ReadSlab(props, "eta")) {}

  uint32_t Lobes() const override {
    return yarf::kScatterReflect | yarf::kScatterDiffuse | (roughness_.MayRough() ? yarf::kScatterGlossy : 0u) |
           (roughness_.MaySmooth() ? yarf::kScatterDelta : 0u);
  }

 private:
  friend class layered::LayeredSurfaceModel<CoatedDiffuse>;

  // The layers at the points of a call.
  PointLayers LayersAt(const yarf::SurfacePoints& at) const {
    return {reflectance_.At(at), roughness_.At(at), slab_.At(at), slab_};
  }

  yarf::TexturedValue reflectance_;
  layered::PbrtRoughness roughness_;
  layered::Slab slab_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<CoatedDiffuse>(registrar, "coateddiffuse", "1.0.0",
                                "Diffuse base under a dielectric coat and a scattering slab, as pbrt-v4's "
                                "coateddiffuse: a stochastic random walk between the layers (Guo et al. 2018)");
}
