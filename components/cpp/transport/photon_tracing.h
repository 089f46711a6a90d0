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

#include <algorithm>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "wavefront.h"
#include "yarf/hash.h"

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

// Shoots `shooting.paths` photon paths (as a wavefront, in chunks: one
// SurfaceModel call per material per bounce) and returns the photons
// whose history `keep` accepts, where they landed.
template <typename Keep>
std::vector<Photon> ShootPhotons(const SceneView& scene, const PhotonShooting& shooting, Keep keep) {
  using namespace photon_dims;
  std::vector<Photon> stored;
  if (!scene.HasLights() || shooting.paths == 0 || shooting.max_depth == 0 || shooting.max_depth == 1)
    return stored;
  const float scale = 1.0f / float(shooting.paths);
  const int last_bounce = shooting.max_depth < 0 ? kMaxBounces : shooting.max_depth - 1;
  constexpr uint64_t kChunk = 1 << 15;
  struct Live {
    Ray ray;
    Vec3 power;
    PhotonHistory history;
    // Product of the BSDF weights so far, for roulette.
    Vec3 carried{1, 1, 1};
  };
  for (uint64_t first = 0; first < shooting.paths; first += kChunk) {
    const size_t n = size_t(std::min(kChunk, shooting.paths - first));
    const HashedPoints points(shooting.seed, shooting.stream, first, n);
    const std::vector<LightStart> starts = StartLightPaths(scene, points, kLightChoice, kLightPosition, kEmission);
    std::vector<Live> paths(n);
    std::vector<uint32_t> active;
    for (uint32_t i = 0; i < n; ++i) {
      if (!starts[i].Valid()) continue;
      paths[i] = {starts[i].FirstRay(scene.ShutterTime(points.Get(i, kTime))), starts[i].Throughput() * scale,
                  PhotonHistory::kDirect, Vec3(1, 1, 1)};
      if (MaxComponent(paths[i].power) > 0) active.push_back(i);
    }
    for (int bounce = 1; !active.empty() && bounce <= last_bounce; ++bounce) {
      std::vector<Ray> rays(active.size());
      std::vector<Hit> hits(active.size());
      for (size_t k = 0; k < active.size(); ++k) rays[k] = paths[active[k]].ray;
      scene.Intersect(rays, hits);
      const uint32_t base = kFirstBounce + kPerBounce * uint32_t(bounce - 1);
      std::vector<ScatterQuery> queries;
      std::vector<uint32_t> owners;
      std::vector<ShadingPoint> shading;
      for (size_t k = 0; k < active.size(); ++k) {
        if (!hits[k].Found()) continue;
        Live& p = paths[active[k]];
        const Vec3 position = rays[k].origin + rays[k].direction * hits[k].t;
        const uint32_t material = scene.MaterialOf(hits[k].shape);
        const bool diffuse = StoresPhotons(scene.Material(material).Lobes());
        if (diffuse && keep(p.history)) {
          const Vec3 n = hits[k].normal;
          stored.push_back({position, Dot(n, rays[k].direction) < 0 ? n : -n, -rays[k].direction, p.power,
                            p.history});
        }
        if (bounce == last_bounce) continue;
        const ShadingPoint at = ShadingPointOf(scene, hits[k], rays[k]);
        ScatterQuery q{material, at.wi, at.site};
        q.uniform[0] = points.Get(active[k], base + 2);
        q.uniform[1] = points.Get(active[k], base);
        q.uniform[2] = points.Get(active[k], base + 1);
        queries.push_back(q);
        owners.push_back(active[k]);
        shading.push_back(at);
        // The history after this bounce.
        if (diffuse) p.history = PhotonHistory::kIndirect;
        else if (p.history == PhotonHistory::kDirect) p.history = PhotonHistory::kCaustic;
      }
      const std::vector<ScatterAnswer> sampled = SampleSurfaces(scene, TransportMode::kImportance, 0, queries);
      std::vector<uint32_t> next;
      for (size_t q = 0; q < queries.size(); ++q) {
        Live& p = paths[owners[q]];
        const ShadingPoint& at = shading[q];
        const Vec3 weight =
            sampled[q].weight * ShadingWeight(at.frame, at.ng, at.wi, sampled[q].wo, TransportMode::kImportance);
        if (!(sampled[q].pdf > 0) || !(MaxComponent(weight) > 0)) continue;
        p.power = p.power * weight;
        p.carried = p.carried * weight;
        Redirect(p.ray, at.position, at.ng, Normalize(at.frame.ToWorld(sampled[q].wo)));
        // Roulette on what the bounces kept of the photon's power, so that
        // photons' powers stay alike (Jensen's "equal power" photons).
        if (bounce >= shooting.rr_depth) {
          const float survive = std::min(MaxComponent(p.carried), 0.95f);
          if (points.Get(owners[q], base + 3) >= survive) continue;
          p.carried = p.carried * (1.0f / survive);
          p.power = p.power * (1.0f / survive);
        }
        next.push_back(owners[q]);
      }
      active = std::move(next);
    }
  }
  return stored;
}

// A kd-tree over photons.
class PhotonTree {
 public:
  explicit PhotonTree(std::vector<Photon> photons)
      : photons_(std::move(photons)), cloud_{&photons_} {
    if (photons_.empty()) return;
    index_ = std::make_unique<Index>(3, cloud_, nanoflann::KDTreeSingleIndexAdaptorParams(16));
    index_->buildIndex();
  }
  // The index refers to photons_ through cloud_: neither may move.
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
    const std::vector<Photon>* photons;
    size_t kdtree_get_point_count() const { return photons->size(); }
    float kdtree_get_pt(size_t i, size_t dim) const { return (*photons)[i].position[int(dim)]; }
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
  Cloud cloud_;
  std::unique_ptr<Index> index_;
};

// A point of a surface with a diffuse lobe where a camera (or gather)
// walk ended: where radiance toward `wi` is estimated.
struct SurfacePoint {
  uint32_t owner;
  // What the walk carried there (product of BSDF sample weights).
  Vec3 throughput;
  ShadingPoint at;
  float time = 0;
  uint32_t material = 0;
  // The geometric normal on the side the walk arrived from.
  Vec3 FacingNormal() const { return Dot(at.frame.ToWorld(at.wi), at.ng) >= 0 ? at.ng : -at.ng; }
};

// A ray on its way to a surface with a diffuse lobe.
struct Walk {
  uint32_t owner;
  Ray ray;
  Vec3 throughput{1, 1, 1};
};

// Follows each walk through surfaces that store no photons, sampling
// their BSDF (radiance mode), for at most `bounces` such surfaces, and
// returns the surface points with a diffuse lobe it reaches. Bounce b
// uses coordinates first + 4b (direction pair, lobe). When `emitted` is
// given, emitters hit on the way (and at the end) and the environment seen
// by walks that leave the scene add their radiance, times the walk's
// throughput, to emitted[owner].
inline std::vector<SurfacePoint> WalkToDiffuse(const SceneView& scene, const PrimarySamples& points,
                                               std::vector<Walk> walks, uint32_t first, int bounces,
                                               std::vector<Vec3>* emitted) {
  std::vector<SurfacePoint> reached;
  for (int bounce = 0; !walks.empty(); ++bounce) {
    std::vector<Ray> rays(walks.size());
    std::vector<Hit> hits(walks.size());
    for (size_t k = 0; k < walks.size(); ++k) rays[k] = walks[k].ray;
    scene.Intersect(rays, hits);
    if (emitted) {
      std::vector<EmitterQuery> lights;
      std::vector<uint32_t> lit;
      for (size_t k = 0; k < walks.size(); ++k)
        if (hits[k].Found())
          if (const Emitter* e = scene.EmitterOf(hits[k].shape)) {
            lights.push_back({e, Frame(hits[k].normal).ToLocal(-rays[k].direction), SurfaceSite::Of(hits[k])});
            lit.push_back(uint32_t(k));
          }
      const std::vector<EmitterAnswer> le = EvaluateEmitters(scene, lights);
      for (size_t q = 0; q < lit.size(); ++q)
        (*emitted)[walks[lit[q]].owner] += walks[lit[q]].throughput * le[q].radiance;
      std::vector<Vec3> directions;
      std::vector<uint32_t> escaped;
      for (size_t k = 0; k < walks.size(); ++k)
        if (!hits[k].Found()) {
          directions.push_back(rays[k].direction);
          escaped.push_back(uint32_t(k));
        }
      const std::vector<Vec3> environment = EnvironmentAlong(scene, directions);
      for (size_t q = 0; q < escaped.size(); ++q)
        (*emitted)[walks[escaped[q]].owner] += walks[escaped[q]].throughput * environment[q];
    }
    std::vector<ScatterQuery> queries;
    std::vector<uint32_t> scattering;
    std::vector<ShadingPoint> shading;
    for (size_t k = 0; k < walks.size(); ++k) {
      if (!hits[k].Found()) continue;
      const ShadingPoint at = ShadingPointOf(scene, hits[k], rays[k]);
      const uint32_t material = scene.MaterialOf(hits[k].shape);
      if (StoresPhotons(scene.Material(material).Lobes())) {
        reached.push_back({walks[k].owner, walks[k].throughput, at, rays[k].time, material});
        continue;
      }
      if (bounce >= bounces) continue;
      const uint32_t base = first + 4 * uint32_t(bounce);
      ScatterQuery q{material, at.wi, at.site};
      q.uniform[0] = points.Get(walks[k].owner, base + 2);
      q.uniform[1] = points.Get(walks[k].owner, base);
      q.uniform[2] = points.Get(walks[k].owner, base + 1);
      queries.push_back(q);
      scattering.push_back(uint32_t(k));
      shading.push_back(at);
    }
    const std::vector<ScatterAnswer> sampled = SampleSurfaces(scene, TransportMode::kRadiance, 0, queries);
    std::vector<Walk> next;
    for (size_t q = 0; q < queries.size(); ++q) {
      const ShadingPoint& at = shading[q];
      const Vec3 weight =
          sampled[q].weight * ShadingWeight(at.frame, at.ng, at.wi, sampled[q].wo, TransportMode::kRadiance);
      if (!(sampled[q].pdf > 0) || !(MaxComponent(weight) > 0)) continue;
      Walk w = walks[scattering[q]];
      w.throughput *= weight;
      Redirect(w.ray, at.position, at.ng, Normalize(at.frame.ToWorld(sampled[q].wo)));
      next.push_back(w);
    }
    walks = std::move(next);
  }
  return reached;
}

// Next-event estimation at each point: one light sample, chosen from
// coordinates (position pair at `first`, choice at first + 2).
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
  std::vector<Vec3> direct = DirectLight(scene, connections);
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

// Jensen's estimate over the k nearest photons with a cone filter (k = 1):
// weight 1 − d/r, normalised by (1 − 2/3)·πr², r the k-th distance.
inline std::vector<Vec3> ConeEstimate(const SceneView& scene, const PhotonTree& tree,
                                      const std::vector<SurfacePoint>& at, size_t k) {
  std::vector<KernelPhoton> found;
  std::vector<uint32_t> indices(k);
  std::vector<float> distance2(k);
  for (uint32_t q = 0; q < at.size(); ++q) {
    const size_t count = tree.Nearest(at[q].at.position, k, indices.data(), distance2.data());
    if (count == 0) continue;
    const float r = std::sqrt(distance2[count - 1]);
    if (!(r > 0)) continue;
    const float norm = 1.0f / ((1.0f - 2.0f / 3.0f) * kPi * r * r);
    const Vec3 facing = at[q].FacingNormal();
    for (size_t j = 0; j < count; ++j)
      if (SameSurface(tree[indices[j]], facing))
        found.push_back({q, indices[j], (1.0f - std::sqrt(distance2[j]) / r) * norm});
  }
  return ReflectedRadiance(scene, tree, at, found);
}

// The estimate over the photons within a fixed radius, uniform kernel 1/(πr²).
inline std::vector<Vec3> DiscEstimate(const SceneView& scene, const PhotonTree& tree,
                                      const std::vector<SurfacePoint>& at, float radius) {
  std::vector<KernelPhoton> found;
  const float weight = 1.0f / (kPi * radius * radius);
  for (uint32_t q = 0; q < at.size(); ++q) {
    const Vec3 facing = at[q].FacingNormal();
    tree.Within(at[q].at.position, radius, [&](uint32_t photon, float) {
      if (SameSurface(tree[photon], facing)) found.push_back({q, photon, weight});
    });
  }
  return ReflectedRadiance(scene, tree, at, found);
}

}  // namespace yarf
