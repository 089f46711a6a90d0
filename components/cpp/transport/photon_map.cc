// photon_map — Jensen's two-pass photon mapping (Jensen 1996, 2001).
//
// Prepare shoots photons from the lights (light chosen and placed by the
// scene's light sampling, direction by its emitter, scattered in
// importance mode with Russian roulette) and stores them on surfaces with
// a diffuse lobe, in two kd-trees: the global map, from its own photons,
// and the caustic map, holding only photons that reached a diffuse
// surface through surfaces without a diffuse lobe alone (glass, mirrors).
//
// Camera rays follow surfaces without a diffuse lobe by sampling them
// (seeing emitters on the way) to the first surface x with one. There the
// radiance toward the camera is the sum of:
//   direct light, by next-event estimation (one light sample);
//   caustics, from the caustic map at x;
//   the rest (light that met a diffuse surface before x): with
//   final_gather, one BSDF-sampled ray from x, followed through
//   non-diffuse surfaces, and the global map's estimate (all its photons)
//   where it lands; without, the global map's photons that met a diffuse
//   surface before, estimated at x itself.
// In participating media (Jensen & Christensen 1998) photons are
// delta-tracked and also stored, in a volume map, wherever they really
// scatter; camera and gather rays are delta-tracked too, and one that
// scatters in a medium ends there with the volume estimate: the k nearest
// volume photons, Σ p(wi, wo)·Φ / (σ_s·(4/3)πr³), r the k-th distance
// (photons are stored at σ_s's rate, hence the 1/σ_s). Null boundaries are
// stepped through; media that emit light are refused.
// Each surface estimate is Jensen's: the k nearest photons, a cone filter of
// k = 1 (weight 1 − d/r, normalised by πr²/3, r the k-th distance), the
// BSDF evaluated toward each photon. Every light path is counted by
// exactly one of the terms, so the result converges to the path integral
// as photons grow (the estimates' bias falls with photon density).
//
// Parameters: PhotonMapper::Parameters() below. max_depth bounds photon
// paths, and also the non-diffuse bounces of camera and gather rays (16
// when unbounded); photons are a pure function of the scene and the seed.
//
// Primary sample space: 0–1 film, 2–3 lens, 4 time; from 6, 4 per camera
// bounce B through non-diffuse surfaces (direction pair, lobe, unused);
// then at x (light position pair, light choice, unused), the gather
// ray's sample (direction pair, lobe, unused), and 4 per gather bounce.

#include <memory>
#include <vector>

#include <tbb/parallel_invoke.h>

#include "photon_tracing.h"
#include "yarf/plugin.h"

namespace yarf {
namespace {

constexpr int kUnboundedSpecularBounces = 16;
// Photon paths per map: each may store several photons of ~40 bytes.
constexpr int64_t kMaxPhotons = 50'000'000;

class PhotonMapper final : public Transport {
 public:
  // Each sample lands in its own pixel: the film may be rendered in tiles.
  static std::vector<std::string> Capabilities() { return {kPixelLocalCapability}; }
  static ParameterSchema Parameters() {
    using P = Parameter;
    ParameterSchema schema = {
        P::Int("photons").Default(200000).Range(0, double(kMaxPhotons)).Doc("photon paths shot for the global map"),
        P::Int("caustic_photons").Default(200000).Range(0, double(kMaxPhotons)).Doc(
            "photon paths shot for the caustic map"),
        P::Int("nearest").Default(64).Range(1, 65536).Doc("photons per estimate, k, on surfaces and in media"),
        P::Bool("final_gather").Default(true).Doc("gather indirect light with one ray"),
        P::Int("seed").Default(0).Doc("the photons' random stream"),
    };
    const ParameterSchema length = PathLength::Parameters();
    schema.insert(schema.end(), length.begin(), length.end());
    return schema;
  }

  explicit PhotonMapper(const Properties& props)
      : length_(props),
        photons_(props.Int("photons", 200000, 0, kMaxPhotons)),
        caustic_photons_(props.Int("caustic_photons", 200000, 0, kMaxPhotons)),
        nearest_(props.Int("nearest", 64)),
        final_gather_(props.Bool("final_gather", true)),
        seed_(props.Int("seed", 0)) {
    if (nearest_ < 1 || nearest_ > 65536) throw Error("property 'nearest' must be in [1, 65536]");
  }

  uint32_t Dimensions() const override { return GatherWalk() + 4 * uint32_t(Bounces()); }

  void Prepare(const SceneView& scene) override {
    RefuseEmissiveMedia(scene, "photon_map");
    PhotonShooting shooting{uint64_t(photons_), uint64_t(seed_), 0, length_.max_depth, length_.rr_depth};
    // Final gathering estimates everything leaving the gather point; at x
    // itself only the light that met a diffuse surface (or a medium)
    // before is wanted. Light scattered in media is all in the volume map.
    const bool all = final_gather_;
    std::vector<Photon> volume_photons;
    std::vector<Photon> global_photons = ShootPhotons(
        scene, shooting, [all](PhotonHistory h) { return all || h == PhotonHistory::kIndirect; }, &volume_photons);
    shooting.paths = uint64_t(caustic_photons_);
    shooting.stream = 1;
    std::vector<Photon> caustic_photons =
        ShootPhotons(scene, shooting, [](PhotonHistory h) { return h == PhotonHistory::kCaustic; });
    // Each kd-tree builds on one thread: the three side by side.
    tbb::parallel_invoke([&] { global_ = std::make_unique<PhotonTree>(std::move(global_photons)); },
                         [&] { caustic_ = std::make_unique<PhotonTree>(std::move(caustic_photons)); },
                         [&] { volume_ = std::make_unique<PhotonTree>(std::move(volume_photons)); });
  }

  void Evaluate(const SceneView& scene, const PrimarySamples& points, FilmSamples& out) override {
    if (!global_ || !caustic_ || !volume_) throw Error("photon_map: Evaluate before Prepare");
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
    const std::vector<Vec3> caustic = ConeEstimate(scene, *caustic_, visible, size_t(nearest_));
    for (size_t k = 0; k < visible.size(); ++k) radiance[visible[k].owner] += direct[k] + caustic[k];
    if (final_gather_) {
      const std::vector<SurfacePoint> gathered = Gather(scene, points, visible, in_media);
      const std::vector<Vec3> indirect = ConeEstimate(scene, *global_, gathered, size_t(nearest_));
      for (size_t k = 0; k < gathered.size(); ++k) radiance[gathered[k].owner] += indirect[k];
    } else {
      const std::vector<Vec3> indirect = ConeEstimate(scene, *global_, visible, size_t(nearest_));
      for (size_t k = 0; k < visible.size(); ++k) radiance[visible[k].owner] += indirect[k];
    }
    const std::vector<Vec3> in_scattered = VolumeNearestEstimate(scene, *volume_, in_media, size_t(nearest_));
    for (size_t k = 0; k < in_media.size(); ++k) radiance[in_media[k].owner] += in_scattered[k];
    for (uint32_t i = 0; i < n; ++i) AddCameraSample(scene, points, i, radiance[i], out);
  }

 private:
  int Bounces() const { return length_.max_depth < 0 ? kUnboundedSpecularBounces : length_.max_depth; }
  uint32_t LightSampling() const { return kTransportDimension + 4 * uint32_t(Bounces()); }
  uint32_t GatherSample() const { return LightSampling() + 4; }
  uint32_t GatherWalk() const { return GatherSample() + 4; }

  // One BSDF-sampled ray from each visible point, followed to the
  // diffuse surface it lands on (emitters on the way are direct light or
  // caustics, counted already) or to where it scatters in a medium (its
  // volume estimate joins `in_media`).
  std::vector<SurfacePoint> Gather(const SceneView& scene, const PrimarySamples& points,
                                   const std::vector<SurfacePoint>& visible, std::vector<VolumePoint>& in_media) const {
    std::vector<ScatterQuery> queries(visible.size());
    for (size_t k = 0; k < visible.size(); ++k) {
      const SurfacePoint& s = visible[k];
      queries[k] = {s.material, s.at.wi, s.at.site};
      queries[k].uniform[0] = points.Get(s.owner, GatherSample() + 2);
      queries[k].uniform[1] = points.Get(s.owner, GatherSample());
      queries[k].uniform[2] = points.Get(s.owner, GatherSample() + 1);
    }
    const std::vector<ScatterAnswer> sampled =
        SampleSurfaces(scene, TransportMode::kRadiance, 0, queries, Densities::kForward);
    std::vector<CameraWalk> walks;
    for (size_t k = 0; k < visible.size(); ++k) {
      const SurfacePoint& s = visible[k];
      const Vec3 weight =
          sampled[k].weight * ShadingWeight(s.at.frame, s.at.ng, s.at.wi, sampled[k].wo, TransportMode::kRadiance);
      if (!(sampled[k].pdf > 0) || !(MaxComponent(weight) > 0)) continue;
      const Vec3 direction = Normalize(s.at.frame.ToWorld(sampled[k].wo));
      Ray ray;
      ray.time = s.time;
      Redirect(ray, s.at.position, s.at.ng, direction);
      walks.emplace_back(s.owner, ray, s.throughput * weight, s.MediumToward(scene, direction),
                         WalkSeed(points, s.owner, 1));
    }
    return WalkToDiffuse(scene, points, std::move(walks), GatherWalk(), Bounces(), nullptr, in_media);
  }

  PathLength length_;
  int64_t photons_, caustic_photons_, nearest_;
  bool final_gather_;
  int64_t seed_;
  std::unique_ptr<PhotonTree> global_, caustic_, volume_;
};

}  // namespace
}  // namespace yarf

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::PhotonMapper>(registrar, "photon_map", "1.0.0",
                                     "Jensen's photon mapping: global and caustic maps, final gathering");
}
