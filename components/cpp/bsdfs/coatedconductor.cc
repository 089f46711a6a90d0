// coatedconductor — a metal under a dielectric coat, as pbrt-v4's
//
// pbrt-v4's `coatedconductor` material (its CoatedConductorBxDF, a
// LayeredBxDF): a dielectric interface of index `interface.eta` on top,
// smooth or GGX-rough, over a conductor, smooth or GGX-rough, with between
// them a slab of `thickness` (in mean free paths) that scatters with
// `albedo` and Henyey–Greenstein's phase function of asymmetry `g`. Light
// inside is followed by the random walk of coateddiffuse.cc (layered.h),
// whose header comment says how f is estimated, how Sample and Pdf relate
// and how MIS stays unbiased; everything there holds here with the
// conductor in place of the diffuse base.
//
// The conductor is given by its complex index η + iκ (`conductor.eta`,
// `conductor.k`, copper's by default), or by `reflectance` r, which pbrt
// turns into η = 1, κ = 2√r / √(1 - r) (r clamped to ≤ 0.9999): a
// conductor whose normal-incidence reflectance is r. Either index is
// divided by the coat's, as pbrt does: the metal lies in the coat.
//
// With a smooth coat, a smooth conductor and no medium (albedo 0), every
// path is a delta one: Evaluate and Pdf are 0 and Sample draws the coat's
// reflection and the paths bouncing between coat and metal.
//
// Differences from pbrt-v4: those of coateddiffuse.cc; the default copper
// is yarf/support/named_metals.h's RGB.
//
// Parameters: CoatedConductor::Parameters() below, pbrt-v4's names and
// defaults. A texture's values are clamped into the ranges given.
//
// Lobes: glossy reflection (the walk, or a rough coat's own), diffuse
// reflection (the walk, when the slab scatters), delta reflection (a
// smooth coat's own; the walk when all is smooth).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <utility>

#include "layered.h"
#include "yarf/support/scatter_rows.h"
#include "surface_properties.h"
#include "yarf/support/named_metals.h"
#include "yarf/plugin.h"
#include "yarf/texture.h"

namespace {

using yarf::Vec3;
namespace layered = yarf::layered;

// pbrt's default metal, copper, in yarf/support/named_metals.h's RGB.
yarf::metals::ComplexIor Copper() {
  for (const yarf::metals::NamedMetal& metal : yarf::metals::kMetals)
    if (std::string(metal.name) == "Cu") return metal.ior;
  return {};
}

yarf::TexturedValue ReadIndex(const yarf::Properties& props, const std::string& key, Vec3 fallback) {
  yarf::TexturedValue value = yarf::TexturedValue::Color(props, key, fallback, /*unit=*/false);
  for (int c = 0; c < 3; ++c)
    if (value.IsConstant() && !(value.Constant()[c] >= 0.0f && std::isfinite(value.Constant()[c])))
      throw yarf::Error("property '" + key + "' must be finite and ≥ 0 in every channel");
  return value.Clamped(0.0f, 1e4f);
}

// The metal's index, or its reflectance.
struct ConductorIndex {
  std::optional<yarf::TexturedValue> reflectance;
  yarf::TexturedValue eta, k;
};

ConductorIndex ReadConductorIndex(const yarf::Properties& props) {
  ConductorIndex out;
  if (props.Has("reflectance")) {
    if (props.Has("conductor.eta") || props.Has("conductor.k"))
      throw yarf::Error("properties 'reflectance' and 'conductor.eta'/'conductor.k' exclude each other: "
                        "give the conductor one way");
    out.reflectance = yarf::TexturedValue::Color(props, "reflectance", Vec3(), /*unit=*/true);
    return out;
  }
  out.eta = ReadIndex(props, "conductor.eta", Copper().eta);
  out.k = ReadIndex(props, "conductor.k", Copper().k);
  if (out.eta.IsConstant() && out.k.IsConstant())
    for (int c = 0; c < 3; ++c)
      if (out.eta.Constant()[c] == 0.0f && out.k.Constant()[c] == 0.0f)
        throw yarf::Error("properties 'conductor.eta' and 'conductor.k' are both 0 in a channel: no such conductor");
  return out;
}

// The layers at row k of a call's points.
struct PointLayers {
  std::optional<yarf::PointValues<Vec3>> reflectance;
  yarf::PointValues<Vec3> eta, k;
  layered::PbrtRoughness::Points interface, conductor;
  layered::Slab::Points slab;
  const layered::Slab& constants;

  layered::Layers<layered::Conductor> operator()(size_t row) const {
    layered::Layers<layered::Conductor> layers;
    layers.top = {constants.eta, interface[row]};
    Vec3 metal_eta, metal_k;
    if (reflectance) {
      const Vec3 r = (*reflectance)[row];
      float kappa[3];
      for (int c = 0; c < 3; ++c) {
        const float rc = std::clamp(r[c], 0.0f, 0.9999f);
        kappa[c] = 2.0f * std::sqrt(rc) / std::sqrt(1.0f - rc);
      }
      metal_eta = Vec3(1.0f, 1.0f, 1.0f);
      metal_k = Vec3::Load(kappa);
    } else {
      metal_eta = eta[row];
      metal_k = k[row];
    }
    layers.bottom = {conductor[row], metal_eta / constants.eta, metal_k / constants.eta};
    layers.thickness = slab.thickness[row];
    layers.albedo = slab.albedo[row];
    layers.g = slab.g[row];
    layers.max_depth = constants.max_depth;
    layers.samples = constants.samples;
    return layers;
  }
};

class CoatedConductor final : public layered::LayeredSurfaceModel<CoatedConductor> {
 public:
  static yarf::ParameterSchema Parameters() {
    using P = yarf::Parameter;
    return yarf::JoinParameters({
        layered::PbrtRoughnessParameters("interface.", "the coat"),
        layered::PbrtRoughnessParameters("conductor.", "the metal"),
        {layered::RemapParameter()},
        {
            P::RgbTexture("conductor.eta").Min(0).Doc("η of the metal's index; copper's unless reflectance is given"),
            P::RgbTexture("conductor.k").Min(0).Doc("κ of the metal's index; copper's unless reflectance is given"),
            P::RgbTexture("reflectance").Range(0, 1).Doc("the metal's normal-incidence reflectance, instead of eta, k"),
        },
        layered::SlabParameters("interface.eta"),
    });
  }

  explicit CoatedConductor(const yarf::Properties& props)
      : index_(ReadConductorIndex(props)),
        interface_(layered::ReadPbrtRoughness(props, "interface.")),
        conductor_(layered::ReadPbrtRoughness(props, "conductor.")),
        slab_(layered::ReadSlab(props, "interface.eta")) {}

  uint32_t Lobes() const override {
    // The walk is glossy where the slab is clear, diffuse where it
    // scatters; a smooth coat's own reflection is a delta lobe (and so is
    // every path when the metal is smooth too and the slab clear).
    const bool may_be_clear = !slab_.albedo.IsConstant() || slab_.albedo.IsZero();
    uint32_t lobes = yarf::kScatterReflect;
    if (interface_.MayRough() || (may_be_clear && conductor_.MayRough())) lobes |= yarf::kScatterGlossy;
    if (slab_.MayScatter()) lobes |= yarf::kScatterDiffuse;
    if (interface_.MaySmooth()) lobes |= yarf::kScatterDelta;
    return lobes;
  }

 private:
  friend class layered::LayeredSurfaceModel<CoatedConductor>;

  // The layers at the points of a call.
  PointLayers LayersAt(const yarf::SurfacePoints& at) const {
    std::optional<yarf::PointValues<Vec3>> reflectance;
    if (index_.reflectance) reflectance = index_.reflectance->At(at);
    return {std::move(reflectance),
            index_.reflectance ? yarf::PointValues<Vec3>(Vec3()) : index_.eta.At(at),
            index_.reflectance ? yarf::PointValues<Vec3>(Vec3()) : index_.k.At(at),
            interface_.At(at),
            conductor_.At(at),
            slab_.At(at),
            slab_};
  }

  ConductorIndex index_;
  layered::PbrtRoughness interface_, conductor_;
  layered::Slab slab_;
};

}  // namespace

YARF_PLUGIN(registrar) {
  yarf::Register<CoatedConductor>(registrar, "coatedconductor", "1.0.0",
                                  "Conductor under a dielectric coat and a scattering slab, as pbrt-v4's "
                                  "coatedconductor: a stochastic random walk between the layers (Guo et al. 2018)");
}
