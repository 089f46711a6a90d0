// bdpt — bidirectional path tracing (Veach & Guibas 1995, Lafortune &
// Willems 1993; Veach 1997 ch. 10).
//
// Each point of primary sample space grows a camera subpath and a light
// subpath and combines them in every way: s light vertices joined to t
// camera vertices, for all s ≥ 0, t ≥ 1 with s + t − 1 ≤ max_depth
// segments. s = 0 is the camera path hitting an emitter; t = 1 joins a
// light subpath vertex to the camera and splats wherever it appears on
// the film. Strategies are weighted by the power heuristic, evaluated with
// the ratio recurrence over per-vertex forward and reverse area densities
// (Veach §10.2; the formulation pbrt popularised). Every contribution is a
// splat (FilmSamples::splats): the film sums them and divides by passes.
//
// Both subpaths advance as wavefronts, and every connection of a batch is
// evaluated together: each SurfaceModel and Emitter is called once per
// bounce per subpath direction and once per connection round, never per
// sample (a batch whose subpaths would outgrow kSubpathBytes, at a deep
// max_depth, goes in runs of points). The light subpath's vertex 0 serves
// the s = 1 strategies.
//
// In media (pbrt-v4's BDPTIntegrator), both subpaths are walked by delta
// tracking with one hero channel per sample, and a collision that scatters
// is a vertex whose phase function plays the BSDF: no cosine at it, in
// contributions or in the conversion of densities to area. Null
// boundaries (the `null` material) are stepped through and are no
// vertices. Each connection crosses media by ratio tracking and null
// boundaries (medium_transport.h). Every subpath vertex keeps its
// channels' densities relative to the hero's (r_u), and a contribution is
// divided by the channels' mean of the whole path's: the balance
// heuristic over hero channels, as volpath. As in pbrt-v4, the strategy
// weights leave transmittance out of the densities. Light a medium emits
// is found by camera subpaths alone (no light subpath starts in a medium),
// so it takes full weight.
//
// From rr_depth segments on, Russian roulette may end a subpath at a
// surface vertex, surviving with its throughput since the walk began (at
// most 0.95), with the parameter and default of Mitsuba 0.6's bdpt. The
// strategy weights leave the survival probabilities out, as they leave
// transmittance out: computed alike for every strategy from the same
// vertex densities, they still sum to one over the strategies of a path.
//
// Primary sample space: 0–1 film, 2–3 lens, 4 time; (6, 7) light
// position, (8, 9) emission direction, 10 light choice; from 12, four per
// camera vertex (direction pair, lobe, roulette), then four per light
// vertex; the walks through media draw from a hash of the coordinates.
//
// Parameters: Bdpt::Parameters() below; bidirectional weights need
// max_depth finite.

#include <algorithm>
#include <bit>
#include <memory>
#include <optional>
#include <type_traits>
#include <vector>

#include "medium_transport.h"
#include "yarf/plugin.h"

namespace yarf {
namespace {

constexpr uint32_t kLightPosition = kTransportDimension, kEmission = kTransportDimension + 2,
                   kLightChoice = kTransportDimension + 4, kFirstBounce = kTransportDimension + 6,
                   kPerBounce = 4;

struct Vertex {
  enum class Kind : uint8_t { kCamera, kLight, kSurface, kMedium };
  Kind kind = Kind::kSurface;
  // Scattered through a delta lobe (surfaces).
  bool delta = false;
  // A light no camera path can hit (point, spot and directional lights).
  bool delta_position = false;
  // A light vertex at infinity: a light path's start at an environment or
  // directional light, or where a camera path left the scene. It stands 1
  // unit from its neighbour (as pbrt's do), so that the direction between
  // them is what it is.
  bool infinite = false;
  Vec3 p;
  // The geometric normal; a point light's or the camera's axis; at
  // infinity, the direction its light travels toward the scene.
  Vec3 n;
  // Toward the previous vertex of its subpath, world space.
  Vec3 wi;
  Vec3 beta;
  // The subpath's channel densities relative to its hero's, up to here.
  Vec3 r_u{1, 1, 1};
  // Area densities of generating this vertex from its predecessor, and
  // from its successor by the other subpath's sampler.
  float pdf_fwd = 0, pdf_rev = 0;
  uint32_t material = 0, shape = kNoShape;
  // The medium the vertex lies in; on a surface, the one on the side its
  // subpath arrived from.
  uint32_t medium = kNoMedium;
  const Emitter* emitter = nullptr;

  bool OnSurface() const {
    return kind == Kind::kSurface || (kind == Kind::kLight && !delta_position && !infinite);
  }
  // Converts a solid-angle density of the direction from here toward
  // `next` into an area density at next. A vertex at infinity is reached
  // by a direction, whose density stays per solid angle; from one, light
  // paths are parallel rays through a disk, whose area density the caller
  // passes, and next sees it through its cosine alone. A point in a
  // medium has no cosine.
  float ToArea(float pdf, const Vertex& next) const {
    if (next.infinite) return pdf;
    if (infinite) return next.OnSurface() ? pdf * std::abs(Dot(next.n, n)) : pdf;
    const Vec3 d = next.p - p;
    const float dist2 = Dot(d, d);
    if (!(dist2 > 0)) return 0;
    if (next.OnSurface()) pdf *= std::abs(Dot(next.n, d)) / std::sqrt(dist2);
    return pdf / dist2;
  }
  // The medium a ray leaving the vertex toward `direction` starts in.
  uint32_t MediumToward(const SceneView& scene, Vec3 direction) const {
    if (shape == kNoShape || !OnSurface()) return medium;
    return scene.MediaOf(shape).Beyond(direction, n, medium);
  }
};

// What the surface models and emitters are told of a vertex on a surface:
// its shading frame (ShadingFrame; a light at infinity: its frame) and
// where it lies. Kept apart from the Vertex, which the strategy weights
// read many times over, so that those reads stay dense.
struct VertexSurface {
  Frame frame{Vec3(0, 0, 1)};
  SurfaceSite site;
};

// Subpaths of a batch: room for `capacity` vertices per point, each made
// when its subpath reaches it (most end long before a deep max_depth), and
// beside each its surface record, written only where there is a surface.
struct Subpaths {
  std::vector<uint32_t> count;
  uint32_t capacity = 0;
  Subpaths(size_t n, uint32_t capacity_)
      : count(n, 0),
        capacity(capacity_),
        room_(n * capacity_),
        vertices_(std::allocator<Vertex>().allocate(room_)),
        surfaces_(std::allocator<VertexSurface>().allocate(room_)) {}
  ~Subpaths() {
    std::allocator<Vertex>().deallocate(vertices_, room_);
    std::allocator<VertexSurface>().deallocate(surfaces_, room_);
  }
  Subpaths(const Subpaths&) = delete;
  Subpaths& operator=(const Subpaths&) = delete;

  // The next vertex of `path`'s subpath, fresh.
  Vertex& Append(size_t path) { return *std::construct_at(vertices_ + path * capacity + count[path]++); }
  Vertex& at(size_t path, uint32_t k) { return vertices_[path * capacity + k]; }
  const Vertex& at(size_t path, uint32_t k) const { return vertices_[path * capacity + k]; }
  // The surface record of vertex k, made by SetSurface.
  void SetSurface(size_t path, uint32_t k, const Frame& frame, const SurfaceSite& site) {
    std::construct_at(surfaces_ + path * capacity + k, VertexSurface{frame, site});
  }
  const VertexSurface& surface(size_t path, uint32_t k) const { return surfaces_[path * capacity + k]; }

 private:
  static_assert(std::is_trivially_destructible_v<Vertex> && std::is_trivially_destructible_v<VertexSurface>,
                "vertices are left without destruction");
  size_t room_;
  Vertex* vertices_;
  VertexSurface* surfaces_;
};

// A walk in progress: its weight, channel ratios, hero and walk numbers;
// the ray leaving the last vertex, the solid-angle density its direction
// was sampled with, and the medium it travels through.
struct Walker : SpectralPath {
  // The throughput's largest channel where the walk began: roulette
  // weighs what it became against it.
  float start = 1;
  Ray ray;
  float pdf_dir = 0;
  uint32_t medium = kNoMedium;
};

// A phase function query at a vertex in a medium, world space: wi toward
// where the subpath came from, wo toward the other subpath.
struct PhaseQuery {
  uint32_t medium;
  Vec3 wi, wo, position;
};

// The phase function's value and density for every query, as a surface
// answer (f = p in every channel; the function is symmetric, so the
// reverse density is the forward one): one call per medium.
std::vector<SurfaceAnswer> EvaluatePhases(const SceneView& scene, const std::vector<PhaseQuery>& queries) {
  std::vector<SurfaceAnswer> answers(queries.size());
  std::vector<uint32_t> keys(queries.size());
  for (size_t k = 0; k < queries.size(); ++k) keys[k] = queries[k].medium;
  for (const auto& [medium, members] : GroupBy(keys)) {
    const size_t m = members.size();
    std::vector<float> wi(3 * m), wo(3 * m), position(3 * m), value(m), pdf(m);
    for (size_t j = 0; j < m; ++j) {
      const PhaseQuery& q = queries[members[j]];
      q.wi.Store(&wi[3 * j]);
      q.wo.Store(&wo[3 * j]);
      q.position.Store(&position[3 * j]);
    }
    scene.MediumAt(medium).EvaluatePhase(wi, wo, position, value, pdf);
    for (size_t j = 0; j < m; ++j) answers[members[j]] = {Vec3(value[j], value[j], value[j]), pdf[j], pdf[j]};
  }
  return answers;
}

// Points first … first + count − 1 of a batch, as a batch of their own.
class PointRun final : public PrimarySamples {
 public:
  PointRun(const PrimarySamples& all, size_t first, size_t count) : all_(all), first_(first), count_(count) {}
  size_t Count() const override { return count_; }
  float Get(size_t i, uint32_t dimension) const override { return all_.Get(first_ + i, dimension); }
  void Gather(std::span<const uint32_t> points, uint32_t dimension, std::span<float> out) const override {
    std::vector<uint32_t> in_all(points.begin(), points.end());
    for (uint32_t& i : in_all) i += uint32_t(first_);
    all_.Gather(in_all, dimension, out);
  }
  uint64_t SampleIndex(size_t i) const override { return all_.SampleIndex(first_ + i); }

 private:
  const PrimarySamples& all_;
  size_t first_, count_;
};

float Remap0(float f) { return f != 0 ? f : 1; }

uint32_t FloatBits(float f) { return std::bit_cast<uint32_t>(f); }

// The area density of the points of the disk light paths from infinity
// cross (SceneView::InfiniteLightOrigin).
float DiskPdf(const SceneView& scene) {
  float pdf = 0;
  scene.InfiniteLightOrigin(Vec3(0, 0, 1), 0.5f, 0.5f, pdf);
  return pdf;
}

class Bdpt final : public Transport {
 public:
  static ParameterSchema Parameters() {
    return {Parameter::Int("max_depth").Default(8).Range(1, kMaxDepth).Doc(
                "longest path in segments (Mitsuba's convention)"),
            Parameter::Int("rr_depth").Default(5).Range(1, double(PathLength::kLongest)).Doc(
                "subpath length in segments from which Russian roulette may end a subpath")};
  }

  explicit Bdpt(const Properties& props)
      : max_depth_(MaxDepthOf(props)), rr_depth_(int(props.Int("rr_depth", 5, 1, PathLength::kLongest))) {}

  static int MaxDepthOf(const Properties& props) {
    const int64_t depth = props.Int("max_depth", 8);
    if (depth < 1 || depth > kMaxDepth)
      throw Error("property 'max_depth' must be 1 to " + std::to_string(kMaxDepth) +
                  ": bidirectional weights need a finite depth");
    return int(depth);
  }

  uint32_t Dimensions() const override { return kFirstBounce + 2 * kPerBounce * uint32_t(max_depth_); }

  void Prepare(const SceneView& scene) override {
    RefuseUnreachableCamera(scene, "bdpt");
    null_boundaries_ = HasNullBoundaries(scene);
  }

  // Every point of a batch keeps both its subpaths to the end (Subpaths):
  // a batch whose subpaths would take more than kSubpathBytes is evaluated
  // in runs of points that fit.
  void Evaluate(const SceneView& scene, const PrimarySamples& points, FilmSamples& out) override {
    out.splats = true;
    const size_t n = points.Count();
    const size_t per_point = (2 * size_t(max_depth_) + 1) * sizeof(Vertex);
    const size_t run = std::max<size_t>(1, kSubpathBytes / per_point);
    if (n <= run) return EvaluateRun(scene, points, out);
    FilmSamples part;
    for (size_t first = 0; first < n; first += run) {
      part.Clear();
      EvaluateRun(scene, PointRun(points, first, std::min(run, n - first)), part);
      for (size_t k = 0; k < part.Count(); ++k)
        out.Add(part.point[k] + uint32_t(first), part.xy[2 * k], part.xy[2 * k + 1], part.rgb[k]);
    }
  }

 private:
  static constexpr int kMaxDepth = 4096;
  static constexpr size_t kSubpathBytes = size_t(32) << 20;

  void EvaluateRun(const SceneView& scene, const PrimarySamples& points, FilmSamples& out) const {
    out.splats = true;
    const size_t n = points.Count();
    const float w = float(scene.FilmWidth()), h = float(scene.FilmHeight());
    Subpaths camera(n, uint32_t(max_depth_) + 1), light(n, uint32_t(max_depth_));
    std::vector<float> time(n), raster(2 * n);
    std::vector<Walker> walkers(n);
    std::vector<uint32_t> hero(n);
    std::vector<uint64_t> seed(n);
    std::vector<uint32_t> active;
    for (uint32_t i = 0; i < n; ++i) {
      time[i] = scene.ShutterTime(points.Get(i, kTimeDimension));
      const float fx = points.Get(i, kFilmDimension), fy = points.Get(i, kFilmDimension + 1);
      raster[2 * i] = fx * w;
      raster[2 * i + 1] = fy * h;
      const Ray ray = scene.CameraRay(fx, fy, points.Get(i, kLensDimension), points.Get(i, kLensDimension + 1), time[i]);
      Vertex& c = camera.Append(i);
      c.kind = Vertex::Kind::kCamera;
      c.p = ray.origin;
      c.n = ray.direction;  // only its role as "not a surface" matters
      c.beta = Vec3(1, 1, 1);
      c.medium = scene.CameraMedium();
      Walker& walker = walkers[i];
      walker.ray = ray;
      walker.pdf_dir = scene.CameraDirectionPdf(ray.direction);
      walker.medium = c.medium;
      seed[i] = Hash(FloatBits(fx), FloatBits(fy), FloatBits(points.Get(i, kLensDimension)),
                     FloatBits(points.Get(i, kLensDimension + 1)), FloatBits(points.Get(i, kLightPosition)),
                     FloatBits(points.Get(i, kEmission)));
      walker.random.seed = seed[i];
      walker.ChooseHero();
      hero[i] = walker.hero;
      if (walker.pdf_dir > 0) active.push_back(i);
    }
    std::vector<Vec3> emitted(n);
    Extend(scene, points, TransportMode::kRadiance, kFirstBounce, camera, walkers, active, &emitted);
    for (uint32_t i = 0; i < n; ++i)
      if (MaxComponent(emitted[i]) > 0) out.Add(i, raster[2 * i], raster[2 * i + 1], emitted[i]);

    active.clear();
    if (scene.HasLights()) {
      const std::vector<LightStart> starts = StartLightPaths(scene, points, kLightChoice, kLightPosition, kEmission);
      const std::vector<uint32_t> media = StartMedia(scene, starts, time);
      for (uint32_t i = 0; i < n; ++i) {
        const LightStart& s = starts[i];
        if (!s.light.emitter || !(s.light.pdf > 0)) continue;
        Vertex& l = light.Append(i);
        l.kind = Vertex::Kind::kLight;
        l.delta_position = s.light.delta_position || s.light.delta_direction;
        l.infinite = s.light.infinite;
        l.p = s.light.position;
        l.n = s.light.normal;
        l.beta = Vec3(1, 1, 1) * (1.0f / s.light.pdf);
        l.pdf_fwd = s.light.pdf;
        l.shape = s.light.shape;
        l.medium = media[i];
        l.emitter = s.light.emitter;
        // The emitter sees directions in the light's own frame at
        // infinity, else in the geometric one.
        light.SetSurface(i, 0, l.infinite ? s.light.frame : Frame(l.n), SurfaceSite::Uv(s.light.u, s.light.v));
        if (!s.Valid()) continue;
        Walker& walker = walkers[i];
        walker = Walker{};
        walker.ray = s.FirstRay(time[i]);
        walker.beta = s.Throughput();
        walker.start = MaxComponent(walker.beta);
        walker.pdf_dir = s.pdf_direction;
        walker.medium = l.MediumToward(scene, s.direction);
        walker.random.seed = Hash(seed[i], 1u);
        walker.hero = hero[i];
        if (l.infinite) {
          // At infinity the vertex is its direction, chosen with density
          // p_choice·p_direction per solid angle (s = 1 joins along it);
          // its light then crosses the disk with the disk's area density.
          const float disk = DiskPdf(scene);
          l.pdf_fwd = s.light.pdf / disk * s.pdf_direction;
          l.beta = Vec3(1, 1, 1) * (1.0f / l.pdf_fwd);
          walker.pdf_dir = disk;
        }
        if (MaxComponent(walker.beta) > 0) active.push_back(i);
      }
      Extend(scene, points, TransportMode::kImportance, kFirstBounce + kPerBounce * uint32_t(max_depth_), light,
             walkers, active, nullptr);
    }
    Connect(scene, points, camera, light, raster, time, hero, seed, out);
  }

  // The medium each light path starts in: the one its point lies in, seen
  // from the camera (an emitting boundary's side is the vertex's to choose).
  static std::vector<uint32_t> StartMedia(const SceneView& scene, const std::vector<LightStart>& starts,
                                          const std::vector<float>& time) {
    std::vector<Vec3> at(starts.size());
    for (size_t i = 0; i < starts.size(); ++i) at[i] = starts[i].light.position;
    return MediaAt(scene, at, time.empty() ? 0.0f : time[0]);
  }

  // Extends the subpaths of `active` until they leave the scene, are
  // absorbed, fail to scatter or fill their capacity: through media by
  // delta tracking (a real collision is a vertex), through null boundaries
  // without a vertex. Sets each new vertex's forward density and its
  // predecessor's reverse one. Camera subpaths add the light media emit
  // along them to `emitted`.
  void Extend(const SceneView& scene, const PrimarySamples& points, TransportMode mode, uint32_t first_dimension,
              Subpaths& paths, std::vector<Walker>& walkers, std::vector<uint32_t> active,
              std::vector<Vec3>* emitted) const {
    // The dimensions of the vertex a subpath has just reached.
    const auto base = [&](uint32_t i) { return first_dimension + kPerBounce * (paths.count[i] - 2); };
    // Each bounce's lists, their room kept from one bounce to the next.
    std::vector<Ray> rays;
    std::vector<Hit> hits;  // Intersect writes every field
    std::vector<std::pair<uint32_t, Vec3>> scattered;  // path, point
    std::vector<uint32_t> next, scattering;
    std::vector<ScatterQuery> queries;
    while (!active.empty()) {
      const size_t count = active.size();
      rays.resize(count);
      hits.resize(count);
      for (size_t k = 0; k < count; ++k) rays[k] = walkers[active[k]].ray;
      scene.Intersect(rays, hits);

      // Through the media: each walk scatters, is absorbed or reaches its hit.
      scattered.clear();
      const std::vector<uint8_t> at_surface = WalkToHits(
          scene, active, hits, [&](uint32_t i) { return WalkStateOf(walkers[i]); },
          [&](uint32_t i, const Collision& c) {
            if (emitted && MaxComponent(c.emission) > 0) (*emitted)[i] += Emission(walkers[i], c);
          },
          [&](uint32_t i, const Collision& c) { scattered.emplace_back(i, c.position); });

      next.clear();
      ScatterInMedia(scene, points, paths, walkers, scattered, base, next);

      queries.clear();
      scattering.clear();
      queries.reserve(count);
      scattering.reserve(count);
      for (size_t k = 0; k < count; ++k) {
        const uint32_t i = active[k];
        Walker& walker = walkers[i];
        if (!at_surface[k] || paths.count[i] == paths.capacity) continue;
        if (!hits[k].Found()) {
          // A camera path that leaves the scene ends at the environment.
          if (mode == TransportMode::kRadiance && scene.HasEnvironment()) {
            const Vec3 from = paths.at(i, paths.count[i] - 1).p;
            Vertex& v = paths.Append(i);
            v.kind = Vertex::Kind::kLight;
            v.infinite = true;
            v.n = -rays[k].direction;
            v.p = from + rays[k].direction;
            v.wi = v.n;
            v.beta = walker.beta;
            v.r_u = walker.r_u;
            v.pdf_fwd = walker.pdf_dir;
            v.medium = walker.medium;
          }
          continue;
        }
        if (IsNullBoundary(scene, hits[k].shape)) {
          // A boundary only: on through it, no vertex.
          walker.medium = scene.MediaOf(hits[k].shape).Beyond(rays[k].direction, hits[k].normal, walker.medium);
          Redirect(walker.ray, rays[k].origin + rays[k].direction * hits[k].t, hits[k].normal, rays[k].direction);
          next.push_back(i);
          continue;
        }
        Vertex& prev = paths.at(i, paths.count[i] - 1);
        Vertex& v = paths.Append(i);
        const ShadingPoint at(scene, hits[k], rays[k]);
        v.p = at.position;
        v.n = hits[k].normal;
        paths.SetSurface(i, paths.count[i] - 1, at.frame, at.site);
        v.wi = -rays[k].direction;
        v.beta = walker.beta;
        v.r_u = walker.r_u;
        v.pdf_fwd = prev.ToArea(walker.pdf_dir, v);
        v.material = scene.MaterialOf(hits[k].shape);
        v.shape = hits[k].shape;
        v.medium = walker.medium;
        v.emitter = scene.EmitterOf(hits[k].shape);
        if (paths.count[i] == paths.capacity) continue;
        ScatterQuery& q = queries.emplace_back(v.material, at.wi, at.site);
        q.uniform[0] = points.Get(i, base(i) + 2);
        q.uniform[1] = points.Get(i, base(i));
        q.uniform[2] = points.Get(i, base(i) + 1);
        scattering.push_back(i);
      }
      const std::vector<ScatterAnswer> sampled = SampleSurfaces(scene, mode, 0, queries);
      for (size_t q = 0; q < queries.size(); ++q) {
        const uint32_t i = scattering[q];
        const ScatterAnswer& a = sampled[q];
        Vertex& v = paths.at(i, paths.count[i] - 1);
        const Frame& frame = paths.surface(i, paths.count[i] - 1).frame;
        const Vec3 weight = a.weight * ShadingWeight(frame, v.n, queries[q].wi, a.wo, mode);
        if (!(a.pdf > 0) || !(MaxComponent(weight) > 0)) continue;
        Vertex& prev = paths.at(i, paths.count[i] - 2);
        const Vec3 dir = Normalize(frame.ToWorld(a.wo));
        Walker& walker = walkers[i];
        walker.beta *= weight;
        walker.pdf_dir = a.pdf;
        float pdf_rev = a.pdf_reverse;
        if (a.flags & kScatterDelta) {
          v.delta = true;
          walker.pdf_dir = pdf_rev = 0;
        }
        prev.pdf_rev = v.ToArea(pdf_rev, prev);
        walker.medium = v.MediumToward(scene, dir);
        Redirect(walker.ray, v.p, v.n, dir);
        if (int(paths.count[i]) - 1 >= rr_depth_ &&
            !Survives(walker.beta, points.Get(i, base(i) + 3), walker.start))
          continue;
        next.push_back(i);
      }
      active.swap(next);
    }
  }

  // The light a medium emits at a tentative collision, as volpath weighs
  // it over hero channels; only camera subpaths find it.
  static Vec3 Emission(const Walker& walker, const Collision& c) {
    const int h = int(walker.hero);
    const float pdf = c.sigma_maj[h] * c.transmittance_maj[h];
    const Vec3 r_e = walker.r_u * c.sigma_maj * c.transmittance_maj / pdf;
    if (!(pdf > 0) || !(MaxComponent(r_e) > 0)) return Vec3();
    return walker.beta * c.transmittance_maj * c.sigma_a * c.emission / (pdf * ChannelMean(r_e));
  }

  // Real collisions in media become vertices; those with room for more
  // scatter on by their phase function (one call per medium).
  template <typename Base>
  void ScatterInMedia(const SceneView& scene, const PrimarySamples& points, Subpaths& paths,
                      std::vector<Walker>& walkers, const std::vector<std::pair<uint32_t, Vec3>>& scattered,
                      const Base& base, std::vector<uint32_t>& next) const {
    std::vector<uint32_t> keys, owners;
    for (const auto& [i, position] : scattered) {
      Walker& walker = walkers[i];
      Vertex& prev = paths.at(i, paths.count[i] - 1);
      Vertex& v = paths.Append(i);
      v.kind = Vertex::Kind::kMedium;
      v.p = position;
      v.wi = -walker.ray.direction;
      v.beta = walker.beta;
      v.r_u = walker.r_u;
      v.pdf_fwd = prev.ToArea(walker.pdf_dir, v);
      v.medium = walker.medium;
      if (paths.count[i] == paths.capacity) continue;
      keys.push_back(walker.medium);
      owners.push_back(i);
    }
    for (const auto& [medium_index, members] : GroupBy(keys)) {
      const size_t m = members.size();
      std::vector<float> wi(3 * m), position(3 * m), u(2 * m), wo(3 * m), weight(m), pdf(m);
      for (size_t j = 0; j < m; ++j) {
        const uint32_t i = owners[members[j]];
        const Vertex& v = paths.at(i, paths.count[i] - 1);
        v.wi.Store(&wi[3 * j]);
        v.p.Store(&position[3 * j]);
        u[2 * j] = points.Get(i, base(i));
        u[2 * j + 1] = points.Get(i, base(i) + 1);
      }
      scene.MediumAt(medium_index).SamplePhase(wi, position, u, wo, weight, pdf);
      for (size_t j = 0; j < m; ++j) {
        const uint32_t i = owners[members[j]];
        if (!(pdf[j] > 0) || !(weight[j] > 0)) continue;
        Vertex& v = paths.at(i, paths.count[i] - 1);
        Vertex& prev = paths.at(i, paths.count[i] - 2);
        Walker& walker = walkers[i];
        walker.beta *= weight[j];
        walker.pdf_dir = pdf[j];
        prev.pdf_rev = v.ToArea(pdf[j], prev);
        walker.ray.origin = v.p;
        walker.ray.direction = Normalize(Vec3::Load(&wo[3 * j]));
        walker.ray.tnear = 0;
        walker.ray.tfar = kInfinity;
        next.push_back(i);
      }
    }
  }

  // One way of joining the subpaths of a point.
  struct Join {
    uint32_t path = 0;
    uint32_t s = 0, t = 0;
    // Indices into the query lists (or none): surface or phase queries at
    // either end.
    uint32_t light_surface = kNone, camera_surface = kNone, light_phase = kNone, camera_phase = kNone;
    uint32_t emitter = kNone;
    // s = 0 at a vertex at infinity: into the environment queries.
    uint32_t environment = kNone;
    // The surface ends' ShadingWeight.
    float light_shading = 1, camera_shading = 1;
    CameraConnection camera;  // t = 1
    static constexpr uint32_t kNone = 0xFFFFFFFFu;
  };

  void Connect(const SceneView& scene, const PrimarySamples& points, const Subpaths& camera, const Subpaths& light,
               const std::vector<float>& raster, const std::vector<float>& time, const std::vector<uint32_t>& hero,
               const std::vector<uint64_t>& seed, FilmSamples& out) const {
    // Every (s, t) of every point at most: the lists are sized once and
    // their entries made in place.
    size_t most = 0;
    for (uint32_t i = 0; i < camera.count.size(); ++i) most += size_t(camera.count[i]) * (light.count[i] + 1);
    std::vector<Join> joins;
    std::vector<SurfaceQuery> light_queries, camera_queries;
    std::vector<PhaseQuery> light_phases, camera_phases;
    std::vector<EmitterQuery> emitter_queries;
    std::vector<Vec3> environment_queries;
    joins.reserve(most);
    light_queries.reserve(most);
    camera_queries.reserve(most);
    emitter_queries.reserve(most);
    // Surface models see a surface vertex's shading frame; an emitter hit
    // by a camera path the geometric one (a light path's start keeps its
    // emitter's frame in its surface record).
    for (uint32_t i = 0; i < camera.count.size(); ++i) {
      const float lens_u = points.Get(i, kLensDimension), lens_v = points.Get(i, kLensDimension + 1);
      for (uint32_t t = 1; t <= camera.count[i]; ++t)
        for (uint32_t s = 0; s <= light.count[i]; ++s) {
          if (s + t < 2 || int(s + t) - 1 > max_depth_) continue;
          Join j;
          j.path = i;
          j.s = s;
          j.t = t;
          const Vertex& pt = camera.at(i, t - 1);
          if (pt.infinite) {
            // Only the environment itself sees a path that left the scene.
            if (s != 0) continue;
            j.environment = uint32_t(environment_queries.size());
            environment_queries.push_back(-pt.n);
            joins.push_back(j);
            continue;
          }
          if (s == 0) {
            if (!pt.emitter) continue;
            j.emitter = uint32_t(emitter_queries.size());
            emitter_queries.emplace_back(pt.emitter, Frame(pt.n).ToLocal(pt.wi), camera.surface(i, t - 1).site);
            joins.push_back(j);
            continue;
          }
          const Vertex& qs = light.at(i, s - 1);
          if (qs.kind == Vertex::Kind::kSurface && qs.delta) continue;
          // A point light is a delta on the film: never seen directly; a
          // light at infinity is seen by the camera paths that leave.
          if (s == 1 && t == 1 && (qs.delta_position || qs.infinite)) continue;
          if (t == 1) {
            if (!scene.ConnectToCamera(qs.p, lens_u, lens_v, j.camera)) continue;
          } else if (pt.delta) {
            continue;
          }
          const Vec3 target = t == 1 ? j.camera.lens_point : pt.p;
          const Vec3 d = target - qs.p;
          if (!(Dot(d, d) > 0)) continue;
          // From infinity, along the light path's own direction.
          const Vec3 to_pt = qs.infinite ? qs.n : Normalize(d);
          // The surface ends' directions in their frames, and their
          // ShadingWeight: where the normals disagree on the side, nothing
          // crosses the join.
          const bool light_on_surface = s > 1 && qs.kind != Vertex::Kind::kMedium;
          const bool camera_on_surface = t > 1 && pt.kind != Vertex::Kind::kMedium;
          Vec3 light_wi, light_wo, camera_wi, camera_wo;
          if (light_on_surface) {
            const Frame& frame = light.surface(i, s - 1).frame;
            light_wi = frame.ToLocal(qs.wi);
            light_wo = frame.ToLocal(to_pt);
            j.light_shading = ShadingWeight(frame, qs.n, light_wi, light_wo, TransportMode::kImportance);
            if (!(j.light_shading > 0)) continue;
          }
          if (camera_on_surface) {
            const Frame& frame = camera.surface(i, t - 1).frame;
            camera_wi = frame.ToLocal(pt.wi);
            camera_wo = frame.ToLocal(-to_pt);
            j.camera_shading = ShadingWeight(frame, pt.n, camera_wi, camera_wo, TransportMode::kRadiance);
            if (!(j.camera_shading > 0)) continue;
          }
          if (s == 1) {
            j.emitter = uint32_t(emitter_queries.size());
            const VertexSurface& start = light.surface(i, 0);
            emitter_queries.emplace_back(qs.emitter, start.frame.ToLocal(to_pt), start.site);
          } else if (light_on_surface) {
            j.light_surface = uint32_t(light_queries.size());
            light_queries.emplace_back(qs.material, light_wi, light_wo, light.surface(i, s - 1).site);
          } else {
            j.light_phase = uint32_t(light_phases.size());
            light_phases.push_back({qs.medium, qs.wi, to_pt, qs.p});
          }
          if (camera_on_surface) {
            j.camera_surface = uint32_t(camera_queries.size());
            camera_queries.emplace_back(pt.material, camera_wi, camera_wo, camera.surface(i, t - 1).site);
          } else if (t > 1) {
            j.camera_phase = uint32_t(camera_phases.size());
            camera_phases.push_back({pt.medium, pt.wi, -to_pt, pt.p});
          }
          joins.push_back(j);
        }
    }
    const std::vector<SurfaceAnswer> at_light = EvaluateSurfaces(scene, TransportMode::kImportance, light_queries);
    const std::vector<SurfaceAnswer> at_camera = EvaluateSurfaces(scene, TransportMode::kRadiance, camera_queries);
    const std::vector<SurfaceAnswer> phase_at_light = EvaluatePhases(scene, light_phases);
    const std::vector<SurfaceAnswer> phase_at_camera = EvaluatePhases(scene, camera_phases);
    const std::vector<EmitterAnswer> emitted = EvaluateEmitters(scene, emitter_queries);
    std::vector<Vec3> environment(environment_queries.size());
    std::vector<float> environment_pdf(environment_queries.size());
    if (!environment_queries.empty()) scene.Escaped(environment_queries, environment, environment_pdf);
    const float disk = DiskPdf(scene);

    std::vector<ShadowWalk> shadows;
    std::vector<Vec3> values, ratios;
    std::vector<uint32_t> owners;
    std::vector<float> xy;
    shadows.reserve(joins.size());
    values.reserve(joins.size());
    ratios.reserve(joins.size());
    owners.reserve(joins.size());
    xy.reserve(2 * joins.size());
    for (const Join& j : joins) {
      const Vertex& pt = camera.at(j.path, j.t - 1);
      float x = raster[2 * j.path], y = raster[2 * j.path + 1];
      if (j.environment != Join::kNone) {
        const Vec3 value = pt.beta * environment[j.environment];
        if (!(MaxComponent(value) > 0)) continue;
        out.Add(j.path, x, y,
                value * (Weight(scene, camera, light, j, nullptr, nullptr, disk, environment_pdf[j.environment]) /
                         ChannelMean(pt.r_u)));
        continue;
      }
      if (j.s == 0) {
        const Vec3 value = pt.beta * emitted[j.emitter].radiance;
        if (!(MaxComponent(value) > 0)) continue;
        const float weight = Weight(scene, camera, light, j, nullptr, nullptr, emitted[j.emitter].pdf_direction, 0);
        out.Add(j.path, x, y, value * (weight / ChannelMean(pt.r_u)));
        continue;
      }
      const Vertex& qs = light.at(j.path, j.s - 1);
      const Vec3 target = j.t == 1 ? j.camera.lens_point : pt.p;
      const Vec3 d = target - qs.p;
      // From infinity: parallel light, no fall-off with distance.
      const float dist2 = qs.infinite ? 1.0f : Dot(d, d);
      const Vec3 to_pt = qs.infinite ? qs.n : d / std::sqrt(dist2);
      // Light end: the emitter's radiance with its cosine, beta·f of a
      // surface with the shading cosine and its importance correction, or
      // beta·p of a point in a medium.
      Vec3 value = qs.beta;
      const SurfaceAnswer* light_answer = nullptr;
      if (j.s == 1) {
        value *= emitted[j.emitter].radiance * (qs.OnSurface() ? std::abs(Dot(qs.n, to_pt)) : 1.0f);
      } else if (j.light_phase != Join::kNone) {
        light_answer = &phase_at_light[j.light_phase];
        value *= light_answer->f;
      } else {
        const SurfaceQuery& q = light_queries[j.light_surface];
        light_answer = &at_light[j.light_surface];
        value *= light_answer->f * (std::abs(q.wo.z) * j.light_shading);
      }
      const SurfaceAnswer* camera_answer = nullptr;
      if (j.t == 1) {
        value *= j.camera.importance / dist2;
        x = j.camera.raster_x;
        y = j.camera.raster_y;
      } else if (j.camera_phase != Join::kNone) {
        camera_answer = &phase_at_camera[j.camera_phase];
        value *= pt.beta * camera_answer->f / dist2;
      } else {
        const SurfaceQuery& q = camera_queries[j.camera_surface];
        camera_answer = &at_camera[j.camera_surface];
        value *= pt.beta * camera_answer->f * (std::abs(q.wo.z) * j.camera_shading / dist2);
      }
      if (!(MaxComponent(value) > 0)) continue;
      const float weight =
          Weight(scene, camera, light, j, light_answer, camera_answer,
                 j.s == 1 ? (qs.infinite ? disk : emitted[j.emitter].pdf_direction) : 0, 0);
      ShadowWalk& shadow = shadows.emplace_back();
      Ray& ray = shadow.ray;
      if (qs.infinite) {
        // Toward the light, from pt.
        ray.origin = pt.OnSurface() ? OffsetRayOrigin(pt.p, pt.n, -to_pt) : pt.p;
        ray.direction = -to_pt;
        shadow.medium = pt.MediumToward(scene, -to_pt);
      } else {
        if (j.t == 1) {
          ray = RayToLens(qs.p, qs.OnSurface() ? qs.n : Vec3(), target, time[j.path]);
        } else {
          ray.origin = qs.OnSurface() ? OffsetRayOrigin(qs.p, qs.n, to_pt) : qs.p;
          const Vec3 along = pt.p - ray.origin;
          const float length = Length(along);
          ray.direction = length > 0 ? along / length : to_pt;
          ray.tfar = std::max(0.0f, length - (pt.OnSurface() ? SurfaceOffset(pt.p) : 0.0f));
        }
        shadow.medium = qs.MediumToward(scene, to_pt);
      }
      ray.time = time[j.path];
      shadow.hero = hero[j.path];
      shadow.seed = Hash(seed[j.path], j.s, j.t, 2u);
      values.push_back(value * weight);
      ratios.push_back(qs.r_u * (j.t == 1 ? Vec3(1, 1, 1) : pt.r_u));
      owners.push_back(j.path);
      xy.push_back(x);
      xy.push_back(y);
    }
    const std::vector<ShadowTransmittance> through = Transmittances(scene, shadows, null_boundaries_);
    for (size_t k = 0; k < shadows.size(); ++k) {
      const float mean = ChannelMean(ratios[k] * through[k].r_l);
      if (!(MaxComponent(through[k].value) > 0) || !(mean > 0)) continue;
      out.Add(owners[k], xy[2 * k], xy[2 * k + 1], values[k] * through[k].value / mean);
    }
  }

  // The power-heuristic weight of strategy (s, t) against every other way
  // of sampling the same path. `light_answer`/`camera_answer` hold the
  // connection's densities at surface endpoints; `emitter_pdf` the
  // emitter's direction density (s = 1: toward pt; s = 0: toward pt−1),
  // for a light at infinity its disk's area density; `environment_pdf`
  // the density with which a light at infinity is chosen toward a camera
  // path that left the scene (s = 0 there).
  float Weight(const SceneView& scene, const Subpaths& camera, const Subpaths& light, const Join& j,
               const SurfaceAnswer* light_answer, const SurfaceAnswer* camera_answer, float emitter_pdf,
               float environment_pdf) const {
    const uint32_t s = j.s, t = j.t, i = j.path;
    // The connection changes the reverse densities of pt, pt−1, qs and
    // qs−1 alone; every other density is its subpath's own.
    std::optional<Vertex> lens;  // pt when t = 1: the camera vertex the connection sampled
    if (t == 1) {
      lens.emplace();
      lens->kind = Vertex::Kind::kCamera;
      lens->p = j.camera.lens_point;
      lens->n = j.camera.axis;
    }
    const Vertex& pt = t == 1 ? *lens : camera.at(i, t - 1);
    float pt_rev = 0, pt_minus_rev = 0, qs_rev = 0, qs_minus_rev = 0;
    if (s > 0) {
      const Vertex& qs = light.at(i, s - 1);
      // qs as sampled from pt.
      const float pdf = t == 1 ? j.camera.importance : camera_answer->pdf;
      qs_rev = pt.ToArea(pdf, qs);
      // pt as sampled from qs.
      pt_rev = qs.ToArea(s == 1 ? emitter_pdf : light_answer->pdf, pt);
      if (t > 1) pt_minus_rev = pt.ToArea(camera_answer->pdf_reverse, camera.at(i, t - 2));
      if (s > 1) qs_minus_rev = qs.ToArea(light_answer->pdf_reverse, light.at(i, s - 2));
    } else {
      // pt as a light sample, and pt−1 as sampled from it (t ≥ 2 here).
      pt_rev = pt.infinite ? environment_pdf : scene.LightPdfArea(pt.shape);
      pt_minus_rev = pt.ToArea(emitter_pdf, camera.at(i, t - 2));
    }
    const auto camera_vertex = [&](uint32_t k) -> const Vertex& { return k == t - 1 ? pt : camera.at(i, k); };
    const auto camera_rev = [&](uint32_t k) {
      return k == t - 1 ? pt_rev : k == t - 2 ? pt_minus_rev : camera.at(i, k).pdf_rev;
    };
    const auto light_rev = [&](uint32_t k) {
      return k == s - 1 ? qs_rev : k == s - 2 ? qs_minus_rev : light.at(i, k).pdf_rev;
    };
    float sum = 0, ratio = 1;
    for (uint32_t k = t - 1; k >= 1; --k) {
      const Vertex& v = camera_vertex(k);
      ratio *= Remap0(camera_rev(k)) / Remap0(v.pdf_fwd);
      const bool delta = (k == t - 1 ? false : v.delta) || camera_vertex(k - 1).delta;
      // Joining a light at infinity straight to the camera is no strategy.
      const bool impossible = k == 1 && t == 2 && s == 0 && pt.infinite;
      if (!delta && !impossible) sum += ratio * ratio;
    }
    ratio = 1;
    for (int k = int(s) - 1; k >= 0; --k) {
      const Vertex& v = light.at(i, uint32_t(k));
      ratio *= Remap0(light_rev(uint32_t(k))) / Remap0(v.pdf_fwd);
      const bool self_delta = k == int(s) - 1 ? false : v.delta;
      // Strategy (k, ·) needs vertex k − 1 to connect; s = 0 needs a light with area.
      const bool before_delta = k > 0 ? light.at(i, uint32_t(k - 1)).delta : v.delta_position;
      if (!self_delta && !before_delta) sum += ratio * ratio;
    }
    return 1 / (1 + sum);
  }

  int max_depth_;
  int rr_depth_;
  bool null_boundaries_ = false;
};

}  // namespace
}  // namespace yarf

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::Bdpt>(registrar, "bdpt", "1.0.0",
                             "bidirectional path tracer: every connection strategy, power-heuristic MIS");
}
