// sppm — stochastic progressive photon mapping, in the probabilistic
// formulation of Knaus & Zwicker (2011).
//
// Pass i (the sample index of a point in its pixel) is an ordinary photon
// mapping estimate with its own, freshly shot photon map and its own
// radius r_i = r_1·(i+1)^((α−1)/2). Each pass's estimate has bias O(r_i²)
// and variance O(1/r_i²); averaging the passes, as the film does, makes
// both vanish as passes grow (for 0 < α < 1), with nothing but the pass
// index shared between passes.
//
// Camera rays follow surfaces without a diffuse lobe by sampling them
// (seeing emitters on the way) to the first surface x with one; there,
// direct light by next-event estimation (one light sample) plus the
// density estimate of every photon after at least one bounce within r_i
// of x, uniform kernel 1/(πr_i²), the BSDF evaluated toward each photon.
//
// In participating media photons are delta-tracked and also stored
// wherever they really scatter; a camera ray that scatters in a medium
// ends there with the volume estimate of the pass's volume photons within
// r_i, Σ p(wi, wo)·Φ / (σ_s·(4/3)πr_i³) (Jensen & Christensen's, with
// Knaus & Zwicker's shrinking radius). Null boundaries are stepped
// through; media that emit light are refused.
//
// Photon maps are built on demand, once per pass (threads that need the
// same pass join its one build), and the maps of passes before the last
// few are dropped.
//
// Parameters: StochasticProgressivePhotonMapper::Parameters() below.
// max_depth bounds photon paths, and also the non-diffuse bounces of
// camera rays (16 when unbounded).
//
// Primary sample space: 0–1 film, 2–3 lens, 4 time; from 6, 4 per camera
// bounce through non-diffuse surfaces (direction pair, lobe, unused); then
// at x (light position pair, light choice, unused).

#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <vector>

#include <tbb/collaborative_call_once.h>

#include "photon_tracing.h"
#include "yarf/plugin.h"

namespace yarf {
namespace {

constexpr int kUnboundedSpecularBounces = 16;
// Passes whose maps are kept behind the newest one asked for.
constexpr uint64_t kKeptPasses = 2;
constexpr float kRadiusOfDiagonal = 0.015f;

// A pass's photons: on surfaces (after at least one bounce) and at real
// scatterings in media (all of them).
struct PassMaps {
  PassMaps(std::vector<Photon> surface_photons, std::vector<Photon> volume_photons)
      : surface(std::move(surface_photons)), volume(std::move(volume_photons)) {}
  PhotonTree surface, volume;
};

// A pass's maps and whether they are built.
struct PassSlot {
  tbb::collaborative_once_flag built;
  std::shared_ptr<const PassMaps> maps;
};

class StochasticProgressivePhotonMapper final : public Transport {
 public:
  // Each sample lands in its own pixel: the film may be rendered in tiles.
  static std::vector<std::string> Capabilities() { return {kPixelLocalCapability}; }
  static ParameterSchema Parameters() {
    using P = Parameter;
    ParameterSchema schema = {
        P::Int("photons_per_pass").Default(50000).Range(1, 50'000'000).Doc("photon paths shot per pass"),
        P::Float("initial_radius").Default(0).Min(0).Doc(
            "r_1 in scene units; 0: 1.5% of the diagonal of the first pass's photons' bounds"),
        P::Float("alpha").Default(2.0 / 3.0).Range(0, 1).Doc("how fast the radius shrinks, in (0, 1)"),
        P::Int("seed").Default(0).Doc("the photons' random stream"),
    };
    const ParameterSchema length = PathLength::Parameters();
    schema.insert(schema.end(), length.begin(), length.end());
    return schema;
  }

  explicit StochasticProgressivePhotonMapper(const Properties& props)
      : length_(props),
        photons_per_pass_(props.Int("photons_per_pass", 50000, 1, 50'000'000)),
        initial_radius_(float(props.Float("initial_radius", 0))),
        alpha_(float(props.Float("alpha", 2.0 / 3.0))),
        seed_(props.Int("seed", 0)) {
    if (!(initial_radius_ >= 0) || !std::isfinite(initial_radius_))
      throw Error("property 'initial_radius' must be > 0 (or 0 for the default)");
    if (!(alpha_ > 0 && alpha_ < 1)) throw Error("property 'alpha' must be in (0, 1)");
  }

  uint32_t Dimensions() const override { return LightSampling() + 4; }

  void Prepare(const SceneView& scene) override {
    RefuseEmissiveMedia(scene, "sppm");
    {
      std::lock_guard lock(mutex_);
      maps_.clear();
    }
    if (initial_radius_ == 0) initial_radius_ = DefaultRadius(*MapOfPass(scene, 0));
  }

  void Evaluate(const SceneView& scene, const PrimarySamples& points, FilmSamples& out) override {
    const size_t n = points.Count();
    std::vector<CameraWalk> walks;
    walks.reserve(n);
    for (uint32_t i = 0; i < n; ++i)
      walks.emplace_back(i, CameraRayOf(scene, points, i), Vec3(1, 1, 1), scene.CameraMedium(), WalkSeed(points, i, 0));
    std::vector<Vec3> radiance(n);
    std::vector<VolumePoint> in_media;
    const std::vector<SurfacePoint> visible =
        WalkToDiffuse(scene, points, std::move(walks), kTransportDimension, Bounces(), &radiance, in_media);
    const std::vector<Vec3> direct = DirectLightAt(scene, points, visible, LightSampling());
    for (size_t k = 0; k < visible.size(); ++k) radiance[visible[k].owner] += direct[k];

    // Points of different passes use different maps and radii.
    std::vector<uint64_t> pass(visible.size());
    for (size_t k = 0; k < visible.size(); ++k) pass[k] = points.SampleIndex(visible[k].owner);
    for (const auto& [index, members] : GroupBy(pass)) {
      std::vector<SurfacePoint> at;
      at.reserve(members.size());
      for (uint32_t k : members) at.push_back(visible[k]);
      const std::shared_ptr<const PassMaps> maps = MapOfPass(scene, index);
      const std::vector<Vec3> indirect = DiscEstimate(scene, maps->surface, at, Radius(index));
      for (size_t j = 0; j < at.size(); ++j) radiance[at[j].owner] += indirect[j];
    }
    std::vector<uint64_t> volume_pass(in_media.size());
    for (size_t k = 0; k < in_media.size(); ++k) volume_pass[k] = points.SampleIndex(in_media[k].owner);
    for (const auto& [index, members] : GroupBy(volume_pass)) {
      std::vector<VolumePoint> at;
      at.reserve(members.size());
      for (uint32_t k : members) at.push_back(in_media[k]);
      const std::shared_ptr<const PassMaps> maps = MapOfPass(scene, index);
      const std::vector<Vec3> in_scattered = VolumeBallEstimate(scene, maps->volume, at, Radius(index));
      for (size_t j = 0; j < at.size(); ++j) radiance[at[j].owner] += in_scattered[j];
    }
    for (uint32_t i = 0; i < n; ++i) AddCameraSample(scene, points, i, radiance[i], out);
  }

 private:
  int Bounces() const { return length_.max_depth < 0 ? kUnboundedSpecularBounces : length_.max_depth; }
  uint32_t LightSampling() const { return kTransportDimension + 4 * uint32_t(Bounces()); }

  float Radius(uint64_t pass) const {
    return initial_radius_ * std::pow(float(pass + 1), (alpha_ - 1.0f) / 2.0f);
  }

  // The photons of a pass: on surfaces those that met a surface (or a
  // medium) before, light at x that next-event estimation does not count;
  // in media all.
  std::shared_ptr<const PassMaps> Shoot(const SceneView& scene, uint64_t pass) const {
    const PhotonShooting shooting{uint64_t(photons_per_pass_), uint64_t(seed_), pass, length_.max_depth,
                                  length_.rr_depth};
    std::vector<Photon> volume;
    std::vector<Photon> surface =
        ShootPhotons(scene, shooting, [](PhotonHistory h) { return h != PhotonHistory::kDirect; }, &volume);
    return std::make_shared<const PassMaps>(std::move(surface), std::move(volume));
  }

  static float DefaultRadius(const PassMaps& maps) {
    bool any = false;
    Vec3 lower, upper;
    for (const PhotonTree* photons : {&maps.surface, &maps.volume})
      for (size_t i = 0; i < photons->size(); ++i) {
        const Vec3 p = (*photons)[i].position;
        if (!any) lower = upper = p;
        any = true;
        lower = {std::min(lower.x, p.x), std::min(lower.y, p.y), std::min(lower.z, p.z)};
        upper = {std::max(upper.x, p.x), std::max(upper.y, p.y), std::max(upper.z, p.z)};
      }
    const float diagonal = any ? Length(upper - lower) : 0;
    return diagonal > 0 ? kRadiusOfDiagonal * diagonal : 1;
  }

  // The maps of `pass`, built once by the first thread to ask for them;
  // threads that ask meanwhile help shoot its photons. Maps of passes far
  // behind are dropped (and rebuilt, identical, if asked again).
  std::shared_ptr<const PassMaps> MapOfPass(const SceneView& scene, uint64_t pass) {
    std::shared_ptr<PassSlot> slot;
    {
      std::lock_guard lock(mutex_);
      auto [it, added] = maps_.try_emplace(pass);
      if (added) it->second = std::make_shared<PassSlot>();
      slot = it->second;
      if (added && pass > kKeptPasses) maps_.erase(maps_.begin(), maps_.lower_bound(pass - kKeptPasses));
    }
    // A build that throws leaves the flag unset: the next caller retries.
    tbb::collaborative_call_once(slot->built, [&] { slot->maps = Shoot(scene, pass); });
    return slot->maps;
  }

  PathLength length_;
  int64_t photons_per_pass_;
  float initial_radius_;
  float alpha_;
  int64_t seed_;
  std::mutex mutex_;
  std::map<uint64_t, std::shared_ptr<PassSlot>> maps_;
};

}  // namespace
}  // namespace yarf

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::StochasticProgressivePhotonMapper>(
      registrar, "sppm", "1.0.0", "stochastic progressive photon mapping (Knaus & Zwicker 2011)");
}
