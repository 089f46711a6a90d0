// What the photon mapping transports share: shooting photons from the
// lights and storing them where they land, a kd-tree over them
// (nanoflann), density estimates of reflected radiance, and the walk of
// camera (or gather) rays through surfaces that store no photons.
//
// Photons are stored on surfaces with a diffuse lobe; surfaces without one
// (delta or purely glossy: glass, mirrors) scatter them on. That split
// decides every partition below: a photon's history is "direct" (no
// bounce yet), "caustic" (every bounce so far on a surface without a
// diffuse lobe) or "indirect" (at least one bounce on a surface with one).
// Camera-side walks use the same test, so that estimates of different
// histories add up to each path exactly once.
#pragma once

#include <nanoflann.hpp>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "medium_transport.h"
#include "yarf/support/wavefront.h"
#include "yarf/support/hash.h"

namespace yarf {

// Whether photons are stored at (and density estimates made on) a surface
// with these lobes.
inline bool StoresPhotons(uint32_t lobes) { return (lobes & kScatterDiffuse) != 0; }

enum class PhotonHistory : uint8_t { kDirect, kCaustic, kIndirect };

struct Photon {
  Vec3 position;
  // The surface's normal on the side the photon arrived from.
  Vec3 normal;
  // Unit direction toward where the photon came from.
  Vec3 from;
  // Flux carried (the shooting's 1/N included).
  Vec3 power;
  PhotonHistory history;
};

// Primary samples made by hashing: the photon passes of Prepare (or of an
// SPPM pass) have no sampler points, so their numbers are a pure function
// of (seed, stream, photon, dimension), the same on every run.
class HashedPoints final : public PrimarySamples {
 public:
  HashedPoints(uint64_t seed, uint64_t stream, uint64_t first, size_t count)
      : seed_(seed), stream_(stream), first_(first), count_(count) {}
  size_t Count() const override { return count_; }
  float Get(size_t i, uint32_t dimension) const override {
    return ToUnitFloat(uint32_t(Hash(seed_, stream_, first_ + i, dimension) >> 32));
  }

 private:
  uint64_t seed_, stream_, first_;
  size_t count_;
};

// How photons are shot: how many paths, from which random stream, and
// how long they may be.
struct PhotonShooting {
  uint64_t paths = 0;
  uint64_t seed = 0;
  uint64_t stream = 0;
  // Mitsuba's convention for the whole path: a photon stored after b
  // segments makes paths of at least b + 1; -1 unbounded.
  int max_depth = -1;
  int rr_depth = 5;
};

namespace photon_dims {
// Per photon path: light choice, position pair, direction pair; then 4
// per bounce: direction pair, lobe, roulette.
constexpr uint32_t kLightChoice = 0, kLightPosition = 2, kEmission = 4, kTime = 1, kFirstBounce = 6,
                   kPerBounce = 4;
// A bound on bounces when max_depth is unbounded (roulette ends paths
// long before).
constexpr int kMaxBounces = 64;
}  // namespace photon_dims

// Media whose coefficients report emission would need photons emitted
// from the volume: refused rather than rendered dark.
inline void RefuseEmissiveMedia(const SceneView& scene, const std::string& transport) {
  for (uint32_t m = 0; m < scene.MediumCount(); ++m)
    if (scene.MediumAt(m).Emits())
      throw Error(transport + " does not render media that emit light: render this scene with volpath");
}

// Null boundaries a walk may step through before it is dropped (a walk
// caught between coincident boundaries).
constexpr int kMaxBoundarySteps = 256;

// Shoots `shooting.paths` photon paths (as a wavefront, in chunks: one
// SurfaceModel call per material per bounce) and returns the photons
// whose history `keep` accepts, where they landed on surfaces. In media
// photons are delta-tracked (hero channel and density ratios as
// volpath's, their power β / mean(r_u)); with `volume` given, every real
// scattering in a medium stores a photon there (of any history), and
// scatters the photon on by the phase function, which makes its history
// indirect. Null boundaries are stepped through without a bounce.
// Chunks of paths are shot on the job's threads; each path's numbers
// depend on its index alone and the chunks' photons join in chunk order,
// so the maps are the same however many threads shot them.
template <typename Keep>
std::vector<Photon> ShootPhotons(const SceneView& scene, const PhotonShooting& shooting, Keep keep,
                                 std::vector<Photon>* volume = nullptr) {
  using namespace photon_dims;
  if (!scene.HasLights() || shooting.paths == 0 || shooting.max_depth == 0 || shooting.max_depth == 1) return {};
  const float scale = 1.0f / float(shooting.paths);
  const int last_bounce = shooting.max_depth < 0 ? kMaxBounces : shooting.max_depth - 1;
  // Long enough for batched component calls, short enough to share
  // 10^5 paths among many threads.
  constexpr uint64_t kChunk = 1 << 12;
  struct Live : SpectralPath {
    Ray ray;
    // The light's flux along the path's start (the shooting's 1/N
    // included); the photon's power is start · β / mean(r_u).
    Vec3 start;
    PhotonHistory history = PhotonHistory::kDirect;
    uint32_t medium = kNoMedium;
    // Real scattering vertices before the next one, plus one.
    int bounce = 1;
    int boundary_steps = 0;
    Vec3 Power() const { return start * beta / ChannelMean(r_u); }
  };
  // Roulette on what the bounces kept of the photon's power, so that
  // photons' powers stay alike (Jensen's "equal power" photons).
  const auto survives = [&](Live& p, float u) {
    if (p.bounce < shooting.rr_depth) return true;
    const float survive = std::min(MaxComponent(p.beta / ChannelMean(p.r_u)), 0.95f);
    if (u >= survive) return false;
    p.beta = p.beta * (1.0f / survive);
    return true;
  };
  const auto shoot_chunk = [&](uint64_t first, std::vector<Photon>& stored, std::vector<Photon>* in_media) {
    const size_t n = size_t(std::min(kChunk, shooting.paths - first));
    const HashedPoints points(shooting.seed, shooting.stream, first, n);
    const std::vector<LightStart> starts = StartLightPaths(scene, points, kLightChoice, kLightPosition, kEmission);
    const std::vector<uint32_t> media = LightStartMedia(scene, starts, scene.ShutterTime(points.Get(0, kTime)));
    std::vector<Live> paths(n);
    std::vector<uint32_t> active;
    for (uint32_t i = 0; i < n; ++i) {
      if (!starts[i].Valid()) continue;
      Live& p = paths[i];
      p.ray = starts[i].FirstRay(scene.ShutterTime(points.Get(i, kTime)));
      p.start = starts[i].Throughput() * scale;
      p.medium = media[i];
      p.random.seed = Hash(shooting.seed, shooting.stream, first + i);
      p.ChooseHero();
      if (MaxComponent(p.start) > 0) active.push_back(i);
    }
    while (!active.empty()) {
      std::vector<Ray> rays(active.size());
      std::vector<Hit> hits(active.size());
      for (size_t k = 0; k < active.size(); ++k) rays[k] = paths[active[k]].ray;
      scene.Intersect(rays, hits);

      // Through the media: each photon scatters, is absorbed or reaches its hit.
      std::vector<std::pair<uint32_t, Vec3>> scattered;  // path, point
      const std::vector<uint8_t> at_surface = WalkToHits(
          scene, active, hits, [&](uint32_t i) { return WalkStateOf(paths[i]); }, [](uint32_t, const Collision&) {},
          [&](uint32_t i, const Collision& c) { scattered.emplace_back(i, c.position); });

      std::vector<uint32_t> next;
      // Photons scattered in media: stored, then scattered on by the phase
      // function (symmetric: sampled with wi back toward the light, its
      // wo is where the photon goes on).
      std::vector<uint32_t> scatter_keys(scattered.size());
      for (size_t k = 0; k < scattered.size(); ++k) scatter_keys[k] = paths[scattered[k].first].medium;
      for (const auto& [medium_index, members] : GroupBy(scatter_keys)) {
        std::vector<float> wi, position, u;
        std::vector<uint32_t> owners;
        for (uint32_t j : members) {
          const auto& [i, at] = scattered[j];
          Live& p = paths[i];
          if (in_media) in_media->push_back({at, Vec3(), -p.ray.direction, p.Power(), p.history});
          if (p.bounce >= last_bounce) continue;
          const uint32_t base = kFirstBounce + kPerBounce * uint32_t(p.bounce - 1);
          for (float v : {-p.ray.direction.x, -p.ray.direction.y, -p.ray.direction.z}) wi.push_back(v);
          for (float v : {at.x, at.y, at.z}) position.push_back(v);
          u.push_back(points.Get(i, base));
          u.push_back(points.Get(i, base + 1));
          owners.push_back(j);
        }
        const size_t m = owners.size();
        std::vector<float> wo(3 * m), weight(m), pdf(m);
        scene.MediumAt(medium_index).SamplePhase(wi, position, u, wo, weight, pdf);
        for (size_t q = 0; q < m; ++q) {
          const auto& [i, at] = scattered[owners[q]];
          Live& p = paths[i];
          if (!(pdf[q] > 0) || !(weight[q] > 0)) continue;
          p.beta *= weight[q];
          p.history = PhotonHistory::kIndirect;
          p.ray.origin = at;
          p.ray.direction = Normalize(Vec3::Load(&wo[3 * q]));
          p.ray.tnear = 0;
          p.ray.tfar = kInfinity;
          const uint32_t base = kFirstBounce + kPerBounce * uint32_t(p.bounce - 1);
          if (!survives(p, points.Get(i, base + 3))) continue;
          ++p.bounce;
          next.push_back(i);
        }
      }

      std::vector<ScatterQuery> queries;
      std::vector<uint32_t> owners, shapes;
      std::vector<ShadingPoint> shading;
      for (size_t k = 0; k < active.size(); ++k) {
        if (!at_surface[k] || !hits[k].Found()) continue;
        Live& p = paths[active[k]];
        if (IsNullBoundary(scene, hits[k].shape)) {
          p.medium = scene.MediaOf(hits[k].shape).Beyond(rays[k].direction, hits[k].normal, p.medium);
          Redirect(p.ray, rays[k].origin + rays[k].direction * hits[k].t, hits[k].normal, rays[k].direction);
          if (++p.boundary_steps < kMaxBoundarySteps) next.push_back(active[k]);
          continue;
        }
        const Vec3 position = rays[k].origin + rays[k].direction * hits[k].t;
        const uint32_t material = scene.MaterialOf(hits[k].shape);
        const bool diffuse = StoresPhotons(scene.Material(material).Lobes());
        if (diffuse && keep(p.history)) {
          const Vec3 n = hits[k].normal;
          stored.push_back({position, Dot(n, rays[k].direction) < 0 ? n : -n, -rays[k].direction, p.Power(),
                            p.history});
        }
        if (p.bounce >= last_bounce) continue;
        const uint32_t base = kFirstBounce + kPerBounce * uint32_t(p.bounce - 1);
        const ShadingPoint at(scene, hits[k], rays[k]);
        ScatterQuery q{material, at.wi, at.site};
        q.uniform[0] = points.Get(active[k], base + 2);
        q.uniform[1] = points.Get(active[k], base);
        q.uniform[2] = points.Get(active[k], base + 1);
        queries.push_back(q);
        owners.push_back(active[k]);
        shapes.push_back(hits[k].shape);
        shading.push_back(at);
        // The history after this bounce.
        if (diffuse) p.history = PhotonHistory::kIndirect;
        else if (p.history == PhotonHistory::kDirect) p.history = PhotonHistory::kCaustic;
      }
      const std::vector<ScatterAnswer> sampled =
          SampleSurfaces(scene, TransportMode::kImportance, 0, queries, Densities::kForward);
      for (size_t q = 0; q < queries.size(); ++q) {
        Live& p = paths[owners[q]];
        const ShadingPoint& at = shading[q];
        const Vec3 weight =
            sampled[q].weight * ShadingWeight(at.frame, at.ng, at.wi, sampled[q].wo, TransportMode::kImportance);
        if (!(sampled[q].pdf > 0) || !(MaxComponent(weight) > 0)) continue;
        p.beta = p.beta * weight;
        const Vec3 direction = Normalize(at.frame.ToWorld(sampled[q].wo));
        p.medium = scene.MediaOf(shapes[q]).Beyond(direction, at.ng, p.medium);
        Redirect(p.ray, at.position, at.ng, direction);
        const uint32_t base = kFirstBounce + kPerBounce * uint32_t(p.bounce - 1);
        if (!survives(p, points.Get(owners[q], base + 3))) continue;
        ++p.bounce;
        next.push_back(owners[q]);
      }
      active = std::move(next);
    }
  };
  struct ChunkPhotons {
    std::vector<Photon> stored, in_media;
  };
  std::vector<ChunkPhotons> chunks(size_t((shooting.paths + kChunk - 1) / kChunk));
  tbb::parallel_for(size_t(0), chunks.size(), [&](size_t c) {
    shoot_chunk(c * kChunk, chunks[c].stored, volume ? &chunks[c].in_media : nullptr);
  });
  size_t total = 0, total_in_media = 0;
  for (const ChunkPhotons& chunk : chunks) total += chunk.stored.size(), total_in_media += chunk.in_media.size();
  std::vector<Photon> stored;
  stored.reserve(total);
  if (volume) volume->reserve(volume->size() + total_in_media);
  for (ChunkPhotons& chunk : chunks) {
    stored.insert(stored.end(), chunk.stored.begin(), chunk.stored.end());
    if (volume) volume->insert(volume->end(), chunk.in_media.begin(), chunk.in_media.end());
    chunk = {};  // freed as it is copied: the photons are held about once
  }
  return stored;
}

// Puts photons near each other in space near each other in memory (along
// a Morton curve over their bounds), which the kd-tree's build and its
// searches visit together.
inline void SortAlongMortonCurve(std::vector<Photon>& photons) {
  float lower[3], upper[3];
  for (int a = 0; a < 3; ++a) lower[a] = upper[a] = photons.front().position[a];
  for (const Photon& p : photons)
    for (int a = 0; a < 3; ++a) lower[a] = std::min(lower[a], p.position[a]), upper[a] = std::max(upper[a], p.position[a]);
  // 10 bits a coordinate, interleaved.
  const auto spread = [](uint32_t x) {
    x = (x | (x << 16)) & 0x030000FFu;
    x = (x | (x << 8)) & 0x0300F00Fu;
    x = (x | (x << 4)) & 0x030C30C3u;
    return (x | (x << 2)) & 0x09249249u;
  };
  const auto code = [&](const Photon& p) {
    uint32_t c = 0;
    for (int a = 0; a < 3; ++a) {
      const float extent = upper[a] - lower[a];
      const float t = extent > 0 ? (p.position[a] - lower[a]) / extent : 0.0f;
      c |= spread(uint32_t(std::clamp(t, 0.0f, 1.0f) * 1023.0f)) << a;
    }
    return c;
  };
  std::vector<std::pair<uint32_t, uint32_t>> keys(photons.size());  // code, index
  for (uint32_t i = 0; i < photons.size(); ++i) keys[i] = {code(photons[i]), i};
  tbb::parallel_sort(keys.begin(), keys.end());
  std::vector<Photon> sorted(photons.size());
  for (size_t i = 0; i < keys.size(); ++i) sorted[i] = photons[keys[i].second];
  photons = std::move(sorted);
}

// A kd-tree over photons.
class PhotonTree {
 public:
  explicit PhotonTree(std::vector<Photon> photons) : photons_(std::move(photons)), cloud_{&positions_} {
    if (photons_.empty()) return;
    SortAlongMortonCurve(photons_);
    // The build reads positions alone, in a random order: packed, they
    // stay in cache far longer than whole photons.
    positions_.resize(photons_.size());
    for (size_t i = 0; i < photons_.size(); ++i) positions_[i] = photons_[i].position;
    index_ = std::make_unique<Index>(3, cloud_, nanoflann::KDTreeSingleIndexAdaptorParams(16));
    index_->buildIndex();
  }
  // The index refers to positions_ through cloud_: neither may move.
  PhotonTree(const PhotonTree&) = delete;
  PhotonTree& operator=(const PhotonTree&) = delete;

  size_t size() const { return photons_.size(); }
  const Photon& operator[](size_t i) const { return photons_[i]; }

  // The k nearest photons to p: their indices and squared distances,
  // nearest first; returns how many were found.
  size_t Nearest(Vec3 p, size_t k, uint32_t* indices, float* distance2) const {
    if (!index_ || k == 0) return 0;
    const float query[3] = {p.x, p.y, p.z};
    return index_->knnSearch(query, k, indices, distance2);
  }

  // Calls visit(index, squared distance) for every photon within `radius` of p.
  template <typename Visit>
  void Within(Vec3 p, float radius, Visit visit) const {
    if (!index_) return;
    const float query[3] = {p.x, p.y, p.z};
    Visitor<Visit> visitor{radius * radius, visit};
    index_->radiusSearchCustomCallback(query, visitor);
  }

 private:
  struct Cloud {
    const std::vector<Vec3>* positions;
    size_t kdtree_get_point_count() const { return positions->size(); }
    float kdtree_get_pt(size_t i, size_t dim) const { return (*positions)[i][int(dim)]; }
    template <typename Box>
    bool kdtree_get_bbox(Box&) const {
      return false;
    }
  };
  // nanoflann's result-set interface, calling back instead of collecting.
  template <typename Visit>
  struct Visitor {
    float radius2;
    Visit& visit;
    size_t count = 0;
    void init() {}
    size_t size() const { return count; }
    bool full() const { return true; }
    bool addPoint(float distance2, uint32_t index) {
      if (distance2 < radius2) {
        visit(index, distance2);
        ++count;
      }
      return true;
    }
    float worstDist() const { return radius2; }
  };
  using Index = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, Cloud>, Cloud, 3, uint32_t>;

  std::vector<Photon> photons_;
  std::vector<Vec3> positions_;
  Cloud cloud_;
  std::unique_ptr<Index> index_;
};

// A point of a surface with a diffuse lobe where a camera (or gather)
// walk ended: where radiance toward `wi` is estimated.
struct SurfacePoint {
  uint32_t owner;
  // What the walk carried there (product of BSDF sample weights; through
  // media, delta tracking's β / mean(r_u)).
  Vec3 throughput;
  ShadingPoint at;
  float time = 0;
  uint32_t material = 0;
  uint32_t shape = kNoShape;
  // The medium the walk arrived through.
  uint32_t medium = kNoMedium;
  // The geometric normal on the side the walk arrived from.
  Vec3 FacingNormal() const { return Dot(at.frame.ToWorld(at.wi), at.ng) >= 0 ? at.ng : -at.ng; }
  // The medium on the side a ray leaving toward `direction` enters.
  uint32_t MediumToward(const SceneView& scene, Vec3 direction) const {
    return scene.MediaOf(shape).Beyond(direction, at.ng, medium);
  }
};

// A point where a camera (or gather) walk scattered in a medium: where
// in-scattered radiance toward `wi` is estimated.
struct VolumePoint {
  uint32_t owner;
  Vec3 position;
  // Unit, back toward where the walk came from.
  Vec3 wi;
  // The walk's β / mean(r_u) there, divided by σ_s there (per channel;
  // zero where σ_s is): the photons' density already carries σ_s.
  Vec3 weight;
  uint32_t medium;
};

// A ray on its way to a surface with a diffuse lobe (or a scattering in a
// medium): its weight and ratios as a path through media.
struct CameraWalk {
  uint32_t owner;
  Ray ray;
  SpectralPath path;
  uint32_t medium = kNoMedium;

  CameraWalk(uint32_t owner, const Ray& ray, Vec3 throughput, uint32_t medium, uint64_t seed)
      : owner(owner), ray(ray), medium(medium) {
    path.beta = throughput;
    path.random.seed = seed;
    path.ChooseHero();
  }
  // The unbiased weight of the walk so far.
  Vec3 Throughput() const { return path.beta / ChannelMean(path.r_u); }
};

// A seed for the walks of point i through media, from its film and lens
// coordinates (and `purpose`, to tell the walks of one point apart).
inline uint64_t WalkSeed(const PrimarySamples& points, uint32_t i, uint32_t purpose) {
  const auto bits = [](float f) { return std::bit_cast<uint32_t>(f); };
  return Hash(bits(points.Get(i, kFilmDimension)), bits(points.Get(i, kFilmDimension + 1)),
              bits(points.Get(i, kLensDimension)), bits(points.Get(i, kLensDimension + 1)), purpose);
}

// Follows each walk through surfaces that store no photons, sampling
// their BSDF (radiance mode), for at most `bounces` such surfaces, and
// returns the surface points with a diffuse lobe it reaches. Bounce b
// uses coordinates first + 4b (direction pair, lobe). In media walks are
// delta-tracked: one that scatters really ends there, in `in_media`; null
// boundaries are stepped through without a bounce. When `emitted` is
// given, emitters hit on the way (and at the end) and the environment seen
// by walks that leave the scene add their radiance, times the walk's
// throughput, to emitted[owner].
inline std::vector<SurfacePoint> WalkToDiffuse(const SceneView& scene, const PrimarySamples& points,
                                               std::vector<CameraWalk> walks, uint32_t first, int bounces,
                                               std::vector<Vec3>* emitted, std::vector<VolumePoint>& in_media) {
  std::vector<SurfacePoint> reached;
  // Per walk: surfaces without a diffuse lobe scattered from so far, null
  // boundaries crossed so far.
  std::vector<int> bounce(walks.size()), steps(walks.size());
  std::vector<uint32_t> active(walks.size());
  for (uint32_t k = 0; k < walks.size(); ++k) active[k] = k;
  while (!active.empty()) {
    std::vector<Ray> rays(active.size());
    std::vector<Hit> hits(active.size());
    for (size_t k = 0; k < active.size(); ++k) rays[k] = walks[active[k]].ray;
    scene.Intersect(rays, hits);

    const std::vector<uint8_t> passed = WalkToHits(
        scene, active, hits,
        [&](uint32_t i) { return WalkState{walks[i].ray, walks[i].medium, walks[i].path}; },
        [](uint32_t, const Collision&) {},
        [&](uint32_t i, const Collision& c) {
          CameraWalk& w = walks[i];
          const Vec3 throughput = w.Throughput();
          const auto per_sigma = [](float t, float sigma) { return sigma > 0 ? t / sigma : 0.0f; };
          const Vec3 weight{per_sigma(throughput.x, c.sigma_s.x), per_sigma(throughput.y, c.sigma_s.y),
                            per_sigma(throughput.z, c.sigma_s.z)};
          if (MaxComponent(weight) > 0) in_media.push_back({w.owner, c.position, -w.ray.direction, weight, w.medium});
        });

    if (emitted) {
      std::vector<EmitterQuery> lights;
      std::vector<uint32_t> lit;
      std::vector<Vec3> directions;
      std::vector<uint32_t> escaped;
      for (size_t k = 0; k < active.size(); ++k) {
        if (!passed[k]) continue;
        if (!hits[k].Found()) {
          directions.push_back(rays[k].direction);
          escaped.push_back(uint32_t(k));
        } else if (const Emitter* e = scene.EmitterOf(hits[k].shape)) {
          lights.push_back({e, Frame(hits[k].normal).ToLocal(-rays[k].direction), SurfaceSite::Of(hits[k])});
          lit.push_back(uint32_t(k));
        }
      }
      const std::vector<EmitterAnswer> le = EvaluateEmitters(scene, lights, Densities::kNone);
      for (size_t q = 0; q < lit.size(); ++q) {
        const CameraWalk& w = walks[active[lit[q]]];
        (*emitted)[w.owner] += w.Throughput() * le[q].radiance;
      }
      const std::vector<Vec3> environment = EnvironmentAlong(scene, directions);
      for (size_t q = 0; q < escaped.size(); ++q) {
        const CameraWalk& w = walks[active[escaped[q]]];
        (*emitted)[w.owner] += w.Throughput() * environment[q];
      }
    }
    std::vector<ScatterQuery> queries;
    std::vector<uint32_t> scattering;
    std::vector<ShadingPoint> shading;
    std::vector<uint32_t> next;
    for (size_t k = 0; k < active.size(); ++k) {
      if (!passed[k] || !hits[k].Found()) continue;
      const uint32_t i = active[k];
      CameraWalk& w = walks[i];
      if (IsNullBoundary(scene, hits[k].shape)) {
        w.medium = scene.MediaOf(hits[k].shape).Beyond(rays[k].direction, hits[k].normal, w.medium);
        Redirect(w.ray, rays[k].origin + rays[k].direction * hits[k].t, hits[k].normal, rays[k].direction);
        if (++steps[i] < kMaxBoundarySteps) next.push_back(i);
        continue;
      }
      const ShadingPoint at(scene, hits[k], rays[k]);
      const uint32_t material = scene.MaterialOf(hits[k].shape);
      if (StoresPhotons(scene.Material(material).Lobes())) {
        reached.push_back({w.owner, w.Throughput(), at, rays[k].time, material, hits[k].shape, w.medium});
        continue;
      }
      if (bounce[i] >= bounces) continue;
      const uint32_t base = first + 4 * uint32_t(bounce[i]);
      ScatterQuery q{material, at.wi, at.site};
      q.uniform[0] = points.Get(w.owner, base + 2);
      q.uniform[1] = points.Get(w.owner, base);
      q.uniform[2] = points.Get(w.owner, base + 1);
      queries.push_back(q);
      scattering.push_back(uint32_t(k));
      shading.push_back(at);
    }
    const std::vector<ScatterAnswer> sampled = SampleSurfaces(scene, TransportMode::kRadiance, 0, queries);
    for (size_t q = 0; q < queries.size(); ++q) {
      const ShadingPoint& at = shading[q];
      const Vec3 weight =
          sampled[q].weight * ShadingWeight(at.frame, at.ng, at.wi, sampled[q].wo, TransportMode::kRadiance);
      if (!(sampled[q].pdf > 0) || !(MaxComponent(weight) > 0)) continue;
      const uint32_t i = active[scattering[q]];
      CameraWalk& w = walks[i];
      w.path.beta *= weight;
      const Vec3 direction = Normalize(at.frame.ToWorld(sampled[q].wo));
      w.medium = scene.MediaOf(hits[scattering[q]].shape).Beyond(direction, at.ng, w.medium);
      Redirect(w.ray, at.position, at.ng, direction);
      ++bounce[i];
      next.push_back(i);
    }
    active = std::move(next);
  }
  return reached;
}

// Next-event estimation at each point: one light sample, chosen from
// coordinates (position pair at `first`, choice at first + 2). In scenes
// with media or null boundaries the shadow ray is ratio-tracked through
// them (a hero channel of its own, its estimate divided by the mean of
// its light-sampling ratios: the light tracer's estimator, no MIS).
inline std::vector<Vec3> DirectLightAt(const SceneView& scene, const PrimarySamples& points,
                                       const std::vector<SurfacePoint>& at, uint32_t first) {
  if (!scene.HasLights()) return std::vector<Vec3>(at.size());
  std::vector<Vec3> from;
  std::vector<uint32_t> owners;
  for (const SurfacePoint& s : at) {
    from.push_back(s.at.position);
    owners.push_back(s.owner);
  }
  const std::vector<LightDirection> lights = SampleLightsFrom(scene, points, from, owners, first + 2, first);
  std::vector<LightConnection> connections;
  connections.reserve(at.size());
  for (size_t k = 0; k < at.size(); ++k) {
    const SurfacePoint& s = at[k];
    connections.push_back({s.material, s.at.position, s.at.ng, s.at.frame, s.at.wi, s.at.site, s.time, lights[k]});
  }
  const bool through = scene.MediumCount() > 0 || HasNullBoundaries(scene);
  std::vector<Vec3> direct = through ? UnshadowedDirectLight(scene, connections) : DirectLight(scene, connections);
  if (through) {
    std::vector<ShadowWalk> shadows(at.size());
    for (uint32_t k = 0; k < at.size(); ++k) {
      const SurfacePoint& s = at[k];
      const Ray ray = ShadowRayToLight(s.at.position, s.at.ng, lights[k], s.time);
      const uint64_t seed = Hash(WalkSeed(points, s.owner, 2), k);
      WalkRandom random{seed};
      shadows[k] = {ray, s.MediumToward(scene, ray.direction), std::min(2u, uint32_t(3 * random.Next())), seed};
    }
    const std::vector<ShadowTransmittance> transmittance = Transmittances(scene, shadows, true);
    for (size_t k = 0; k < at.size(); ++k) {
      const float mean = ChannelMean(transmittance[k].r_l);
      direct[k] = mean > 0 ? direct[k] * transmittance[k].value / mean : Vec3();
    }
  }
  for (size_t k = 0; k < at.size(); ++k) direct[k] = direct[k] * at[k].throughput;
  return direct;
}

// Density estimation of reflected radiance: photons found around each
// point with their kernel weights, the BSDF evaluated toward each (one
// Evaluate per material), summed. Photons on a surface facing another way
// (the far side of a thin wall, the other wall of a corner) are left out.
struct KernelPhoton {
  uint32_t point;
  uint32_t photon;
  float weight;
};
inline std::vector<Vec3> ReflectedRadiance(const SceneView& scene, const PhotonTree& tree,
                                           const std::vector<SurfacePoint>& at,
                                           const std::vector<KernelPhoton>& found) {
  std::vector<Vec3> radiance(at.size());
  std::vector<uint32_t> keys(found.size());
  for (size_t j = 0; j < found.size(); ++j) keys[j] = at[found[j].point].material;
  for (const auto& [material, members] : GroupBy(keys)) {
    const size_t m = members.size();
    std::vector<float> wi(3 * m), wo(3 * m), f(3 * m);
    SurfaceRows rows(&scene, m);
    for (size_t j = 0; j < m; ++j) {
      const KernelPhoton& kp = found[members[j]];
      const ShadingPoint& s = at[kp.point].at;
      s.wi.Store(&wi[3 * j]);
      s.frame.ToLocal(tree[kp.photon].from).Store(&wo[3 * j]);
      rows.Add(s.site);
    }
    scene.Material(material).Evaluate(TransportMode::kRadiance, wi, wo, rows.Points(), f);
    for (size_t j = 0; j < m; ++j) {
      const KernelPhoton& kp = found[members[j]];
      const ShadingPoint& s = at[kp.point].at;
      // Photons' power is flux through the geometric surface; the
      // estimate integrates against the shading cosine.
      const Vec3 from = tree[kp.photon].from;
      const float cos_geometric = std::abs(Dot(from, s.ng));
      const Vec3 local = Vec3::Load(&wo[3 * j]);
      const float shading = cos_geometric > 0
          ? ShadingWeight(s.frame, s.ng, s.wi, local, TransportMode::kRadiance) * std::abs(local.z) / cos_geometric
          : 0.0f;
      radiance[kp.point] += Vec3::Load(&f[3 * j]) * tree[kp.photon].power * (kp.weight * shading);
    }
  }
  for (size_t k = 0; k < at.size(); ++k) radiance[k] = radiance[k] * at[k].throughput;
  return radiance;
}

// Whether a photon lies on the surface of a point (facing the same way).
inline bool SameSurface(const Photon& photon, Vec3 facing_normal) {
  return Dot(photon.normal, facing_normal) > 0.5f;
}

// The kernel photons an estimate gathers before it weighs them: a radius
// that covers the scene pairs every point with every photon, so past this
// many the points are weighed in runs.
constexpr size_t kMaxKernelPhotons = size_t(1) << 22;

// An estimate at every point of `at`: gather(q, found) adds point q's
// kernel photons, weigh(found) gives every point's radiance from them
// (zero for points without any); runs of points are weighed apart once
// kMaxKernelPhotons are found, and their radiances summed.
template <typename Points, typename Gather, typename Weigh>
std::vector<Vec3> EstimateInRuns(const Points& at, Gather&& gather, Weigh&& weigh) {
  std::vector<Vec3> radiance(at.size());
  std::vector<KernelPhoton> found;
  const auto weigh_run = [&] {
    if (found.empty()) return;
    const std::vector<Vec3> run = weigh(found);
    for (size_t k = 0; k < at.size(); ++k) radiance[k] += run[k];
    found.clear();
  };
  for (uint32_t q = 0; q < at.size(); ++q) {
    gather(q, found);
    if (found.size() >= kMaxKernelPhotons) weigh_run();
  }
  weigh_run();
  return radiance;
}

// Jensen's estimate over the k nearest photons with a cone filter (k = 1):
// weight 1 − d/r, normalised by (1 − 2/3)·πr², r the k-th distance.
inline std::vector<Vec3> ConeEstimate(const SceneView& scene, const PhotonTree& tree,
                                      const std::vector<SurfacePoint>& at, size_t k) {
  std::vector<uint32_t> indices(k);
  std::vector<float> distance2(k);
  const auto gather = [&](uint32_t q, std::vector<KernelPhoton>& found) {
    const size_t count = tree.Nearest(at[q].at.position, k, indices.data(), distance2.data());
    if (count == 0) return;
    const float r = std::sqrt(distance2[count - 1]);
    if (!(r > 0)) return;
    const float norm = 1.0f / ((1.0f - 2.0f / 3.0f) * kPi * r * r);
    const Vec3 facing = at[q].FacingNormal();
    for (size_t j = 0; j < count; ++j)
      if (SameSurface(tree[indices[j]], facing))
        found.push_back({q, indices[j], (1.0f - std::sqrt(distance2[j]) / r) * norm});
  };
  return EstimateInRuns(at, gather, [&](const auto& found) { return ReflectedRadiance(scene, tree, at, found); });
}

// The estimate over the photons within a fixed radius, uniform kernel 1/(πr²).
inline std::vector<Vec3> DiscEstimate(const SceneView& scene, const PhotonTree& tree,
                                      const std::vector<SurfacePoint>& at, float radius) {
  const float weight = 1.0f / (kPi * radius * radius);
  const auto gather = [&](uint32_t q, std::vector<KernelPhoton>& found) {
    const Vec3 facing = at[q].FacingNormal();
    tree.Within(at[q].at.position, radius, [&](uint32_t photon, float) {
      if (SameSurface(tree[photon], facing)) found.push_back({q, photon, weight});
    });
  };
  return EstimateInRuns(at, gather, [&](const auto& found) { return ReflectedRadiance(scene, tree, at, found); });
}

// Density estimation of in-scattered radiance (Jensen & Christensen
// 1998): photons stored at real scatterings within a ball of radius r
// around x. The expected power of the photons scattered per unit volume
// toward each direction is σ_s·L, so Σ p(wi, photon's from)·Φ / (4/3·πr³)
// estimates σ_s(x)·∫p·L, and the point's weight carries the 1/σ_s(x).
// One EvaluatePhase per medium.
inline std::vector<Vec3> InScatteredRadiance(const SceneView& scene, const PhotonTree& tree,
                                             const std::vector<VolumePoint>& at,
                                             const std::vector<KernelPhoton>& found) {
  std::vector<Vec3> radiance(at.size());
  std::vector<uint32_t> keys(found.size());
  for (size_t j = 0; j < found.size(); ++j) keys[j] = at[found[j].point].medium;
  for (const auto& [medium, members] : GroupBy(keys)) {
    const size_t m = members.size();
    std::vector<float> wi(3 * m), wo(3 * m), position(3 * m), value(m), pdf(m);
    for (size_t j = 0; j < m; ++j) {
      const KernelPhoton& kp = found[members[j]];
      at[kp.point].wi.Store(&wi[3 * j]);
      tree[kp.photon].from.Store(&wo[3 * j]);
      at[kp.point].position.Store(&position[3 * j]);
    }
    scene.MediumAt(medium).EvaluatePhase(wi, wo, position, value, pdf);
    for (size_t j = 0; j < m; ++j) {
      const KernelPhoton& kp = found[members[j]];
      radiance[kp.point] += tree[kp.photon].power * (value[j] * kp.weight);
    }
  }
  for (size_t k = 0; k < at.size(); ++k) radiance[k] = radiance[k] * at[k].weight;
  return radiance;
}

// The volume estimate over the k nearest photons, r the k-th distance.
inline std::vector<Vec3> VolumeNearestEstimate(const SceneView& scene, const PhotonTree& tree,
                                               const std::vector<VolumePoint>& at, size_t k) {
  std::vector<uint32_t> indices(k);
  std::vector<float> distance2(k);
  const auto gather = [&](uint32_t q, std::vector<KernelPhoton>& found) {
    const size_t count = tree.Nearest(at[q].position, k, indices.data(), distance2.data());
    if (count == 0) return;
    const float r = std::sqrt(distance2[count - 1]);
    if (!(r > 0)) return;
    const float weight = 1.0f / (4.0f / 3.0f * kPi * r * r * r);
    for (size_t j = 0; j < count; ++j) found.push_back({q, indices[j], weight});
  };
  return EstimateInRuns(at, gather, [&](const auto& found) { return InScatteredRadiance(scene, tree, at, found); });
}

// The volume estimate over the photons within a fixed radius.
inline std::vector<Vec3> VolumeBallEstimate(const SceneView& scene, const PhotonTree& tree,
                                            const std::vector<VolumePoint>& at, float radius) {
  const float weight = 1.0f / (4.0f / 3.0f * kPi * radius * radius * radius);
  const auto gather = [&](uint32_t q, std::vector<KernelPhoton>& found) {
    tree.Within(at[q].position, radius, [&](uint32_t photon, float) { found.push_back({q, photon, weight}); });
  };
  return EstimateInRuns(at, gather, [&](const auto& found) { return InScatteredRadiance(scene, tree, at, found); });
}

}  // namespace yarf
