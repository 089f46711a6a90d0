// irradiance_cache — irradiance caching for indirect diffuse light (Ward,
// Rubinstein & Clear 1988), records extrapolated by their rotational and
// translational gradients (Ward & Heckbert 1992).
//
// A record holds the irradiance E = ∫ L_i cos dω at a surface point,
// gathered over M×N cosine-stratified cells of the hemisphere (M ≈
// √(rays/π) in θ, N in φ; sin²θ stratified, so each cell is equally
// likely under cos/π), the harmonic mean distance R to the surfaces the
// gather rays hit, clamped to [min, max] spacing (Tabellion & Lamorlette
// 2004), and its gradients from the same cells. A point p with normal n
// interpolates the records whose weight 1/(|p − p_i|/R_i + √(1 − n·n_i))
// exceeds 1/a. Records are made in irradiance_gather.h, stored, looked
// up and kept in files by irradiance_records.h.
//
// The gathered radiance L_i is one bounce: the direct light (one light
// sample) the gathered hit reflects toward the record. Emission seen by
// the gather rays is left out, as the direct light at the shaded point
// counts it already. The image is therefore emission + direct light +
// one indirect diffuse bounce: the paths of at most three segments, what
// the path tracer with max_depth 3 computes.
//
// The cache is built in Prepare, single-threaded and in a fixed order, so
// that rendering is deterministic and Evaluate only reads it: camera rays
// through a grid of prepare_grid² points per pixel (lens centre, mid
// shutter) are followed through specular surfaces to their first hit on a
// surface with a diffuse lobe, and a record is made wherever no record
// weighs more than 1/a there. Evaluate makes no records: a point no record
// covers (between those points, or outside the view prepared) takes the
// relaxed lookup of IrradianceRecords::Estimate.
//
// Evaluate: the camera ray follows specular (delta-only) surfaces up to
// max_depth segments, gathering emission; at the first other surface it
// adds emission, the direct light of one light sample (no MIS) and
// f(wi, n)·E from the cache for materials with a diffuse lobe (exact for
// Lambertian surfaces, where f = ρ/π; only the direct light for
// materials without a diffuse lobe).
//
// With cache_file set, Prepare reads the records stored there when they
// were made for the same scene (geometry, materials, emitters; not the
// camera) and settings, makes any records the current view still lacks,
// and writes the file back only when it made some.
//
// Primary sample space: 0–1 film, 2–3 lens, 4 time, then 8 per segment
// from 6: light position pair, specular direction pair, (light choice,
// lobe choice), two unused.
//
// Parameters: IrradianceCache::Parameters() below. gather_rays: M×N is
// the nearest product not above it (13×39 = 507 for 512); the spacings
// are fractions of the scene's extent, the diagonal of its triangles'
// bounds; cache_file is a file name in the submitting user's folder on
// the server (<state-dir>/files/<user>/), never a path.

#include <algorithm>
#include <bit>
#include <cmath>
#include <string>
#include <vector>

#include "irradiance_gather.h"
#include "irradiance_records.h"
#include "yarf/support/wavefront.h"
#include "yarf/support/hash.h"
#include "yarf/plugin.h"

namespace yarf {
namespace {

constexpr uint32_t kPerSegment = 8;
constexpr uint32_t kLightPosition = 0, kDirection = 2, kLightChoice = 4, kLobe = 5;
// Salt of the lobe choices Prepare makes at specular surfaces.
constexpr uint64_t kVisitSalt = 0x6972632d76697369ull;

uint32_t Bits(float f) { return std::bit_cast<uint32_t>(f); }

// Whether the cache lights a surface of these lobes (a model without kind
// flags counts as diffuse).
bool HasDiffuseLobe(uint32_t lobes) { return (lobes & kScatterDiffuse) || lobes == 0; }
// Surfaces the camera path goes through rather than shades.
bool OnlySpecular(uint32_t lobes) { return !SamplesLights(lobes); }

struct Settings {
  float accuracy;
  uint32_t gather_rays;
  float min_spacing, max_spacing;
  uint32_t prepare_grid;
  int max_depth;
  std::string cache_file;  // a path inside the user's file folder

  explicit Settings(const Properties& props)
      : accuracy(float(props.Float("accuracy", 0.2))),
        gather_rays(uint32_t(props.Int("gather_rays", 512, 16, 1 << 20))),
        min_spacing(float(props.Float("min_spacing", 0.01))),
        max_spacing(float(props.Float("max_spacing", 0.25))),
        prepare_grid(uint32_t(props.Int("prepare_grid", 2, 1, 64))),
        max_depth(int(props.Int("max_depth", 8, 1, 64))),
        cache_file(props.File("cache_file").string()) {
    if (!(accuracy > 0 && accuracy <= 2)) throw Error("property 'accuracy' must lie in (0, 2]");
    if (!(min_spacing > 0)) throw Error("property 'min_spacing' must be > 0");
    if (!(max_spacing >= min_spacing))
      throw Error("property 'max_spacing' must be >= min_spacing");
  }
};

// The diagonal of the bounds of the scene's triangles; of `fallback`'s
// points when it has none (spheres only).
float SceneExtent(const SceneView& scene, const std::vector<SurfacePoint>& fallback) {
  Vec3 lo(kInfinity, kInfinity, kInfinity), hi = -lo;
  auto grow = [&](Vec3 p) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  };
  for (uint32_t s = 0; s < scene.ShapeCount(); ++s)
    for (uint32_t k = 0; k < scene.PrimitiveCount(s); ++k) {
      Vec3 corners[3];
      if (scene.Triangle(s, k, corners))
        for (Vec3 c : corners) grow(c);
    }
  if (!(lo.x <= hi.x))
    for (const SurfacePoint& p : fallback) grow(p.position);
  const float extent = lo.x <= hi.x ? Length(hi - lo) : 0.0f;
  return extent > 0 ? extent : 1.0f;
}

// The key of what the records depend on: the scene's shapes, their
// materials' and emitters' responses in fixed directions, the point
// lights, the environment, and the settings that shape a record. Not the camera.
uint64_t SceneKey(const SceneView& scene, const Settings& settings) {
  uint64_t key = Hash(uint64_t(irradiance_file::kVersion), uint64_t(Bits(settings.accuracy)),
                      uint64_t(settings.gather_rays), uint64_t(Bits(settings.min_spacing)),
                      uint64_t(Bits(settings.max_spacing)));
  auto mix = [&](uint64_t v) { key = Hash(key, v); };
  auto mix3 = [&](Vec3 v) { mix(Bits(v.x)), mix(Bits(v.y)), mix(Bits(v.z)); };
  const std::vector<float> wi{0.3f, 0.2f, 0.932738f}, wo{0, 0, 1}, uv{0.5f, 0.5f};
  const SurfacePoints at{.uv = uv};
  mix(scene.MaterialCount());
  for (uint32_t m = 0; m < scene.MaterialCount(); ++m) {
    std::vector<float> f(3);
    scene.Material(m).Evaluate(TransportMode::kRadiance, wi, wo, at, f);
    mix(scene.Material(m).Lobes());
    mix3(Vec3::Load(f.data()));
  }
  mix(scene.ShapeCount());
  for (uint32_t s = 0; s < scene.ShapeCount(); ++s) {
    mix(scene.MaterialOf(s));
    mix(scene.PrimitiveCount(s));
    for (uint32_t k = 0; k < scene.PrimitiveCount(s); ++k) {
      Vec3 corners[3];
      if (scene.Triangle(s, k, corners))
        for (Vec3 c : corners) mix3(c);
    }
    if (const Emitter* emitter = scene.EmitterOf(s)) {
      std::vector<float> radiance(3);
      emitter->Radiance(wo, at, radiance);
      mix3(Vec3::Load(radiance.data()));
    }
  }
  mix(scene.LightCount());
  for (uint32_t l = 0; l < scene.LightCount(); ++l) {
    const LightDirection s = scene.LightPoint(l, Vec3());
    mix3(s.position), mix3(s.normal), mix3(s.direction), mix(Bits(s.pdf));
    if (s.emitter) {
      std::vector<float> radiance(3);
      s.emitter->Radiance(wo, at, radiance);
      mix3(Vec3::Load(radiance.data()));
    }
  }
  if (scene.HasEnvironment()) {
    const std::vector<Vec3> directions{{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0.6f, -0.8f, 0}};
    for (Vec3 radiance : EnvironmentAlong(scene, directions)) mix3(radiance);
  }
  return key;
}

class IrradianceCache final : public Transport {
 public:
  // Each sample lands in its own pixel: the film may be rendered in tiles.
  static std::vector<std::string> Capabilities() { return {kPixelLocalCapability}; }
  static ParameterSchema Parameters() {
    using P = Parameter;
    return {
        P::Float("accuracy").Default(0.2).Range(0, 2).Doc("Ward's a, > 0: smaller makes more records"),
        P::Int("gather_rays").Default(512).Range(16, 1 << 20).Doc("rays per record"),
        P::Float("min_spacing").Default(0.01).Min(0).Doc("least R, as a fraction of the scene's extent, > 0"),
        P::Float("max_spacing").Default(0.25).Min(0).Doc("largest R, likewise, >= min_spacing"),
        P::Int("prepare_grid").Default(2).Range(1, 64).Doc("camera rays per pixel and axis visited by Prepare"),
        P::Int("max_depth").Default(8).Range(1, 64).Doc("longest specular chain from the camera, in segments"),
        P::File("cache_file").Doc("a file name in your folder on the server for the records; none when absent"),
    };
  }

  explicit IrradianceCache(const Properties& props) : settings_(props), records_(settings_.accuracy, 1) {}

  uint32_t Dimensions() const override { return kTransportDimension + kPerSegment * uint32_t(settings_.max_depth); }

  void Prepare(const SceneView& scene) override {
    RefuseMedia(scene, "irradiance_cache");
    const std::vector<SurfacePoint> visits = VisitPoints(scene);
    const float extent = SceneExtent(scene, visits);
    gather_ = {settings_.gather_rays, settings_.min_spacing * extent, settings_.max_spacing * extent};
    records_ = IrradianceRecords(settings_.accuracy, gather_.max_radius);
    const uint64_t key = SceneKey(scene, settings_);
    std::vector<IrradianceRecord> stored;
    if (!settings_.cache_file.empty() && irradiance_file::Read(settings_.cache_file, key, stored))
      for (const IrradianceRecord& r : stored) records_.Add(r);
    const size_t loaded = records_.Size();
    for (const SurfacePoint& p : visits)
      if (!records_.Covered(p.position, p.normal)) records_.Add(GatherRecord(scene, p, records_.Size(), gather_));
    if (!settings_.cache_file.empty() && records_.Size() != loaded)
      irradiance_file::Write(settings_.cache_file, key, records_.All());
  }

  void Evaluate(const SceneView& scene, const PrimarySamples& points, FilmSamples& out) override {
    const size_t n = points.Count();
    std::vector<Path> paths(n);
    std::vector<uint32_t> active;
    for (uint32_t i = 0; i < n; ++i) {
      paths[i].ray = CameraRayOf(scene, points, i);
      active.push_back(i);
    }
    for (int depth = 1; !active.empty() && depth <= settings_.max_depth; ++depth)
      active = Segment(scene, points, paths, active, depth);
    for (uint32_t i = 0; i < n; ++i) AddCameraSample(scene, points, i, paths[i].radiance, out);
  }

 private:
  struct Path {
    Ray ray;
    Vec3 throughput{1, 1, 1};
    Vec3 radiance;
  };
  struct Vertex {
    uint32_t path;
    ShadingPoint at;
    uint32_t material;
  };

  // Intersects the active paths, adds what they see, shades the first
  // non-specular hits and carries the others on; returns those that go on.
  std::vector<uint32_t> Segment(const SceneView& scene, const PrimarySamples& points, std::vector<Path>& paths,
                                const std::vector<uint32_t>& active, int depth) const {
    std::vector<Ray> rays(active.size());
    std::vector<Hit> hits(active.size());
    for (size_t k = 0; k < active.size(); ++k) rays[k] = paths[active[k]].ray;
    scene.Intersect(rays, hits);
    std::vector<Vertex> shaded, specular;
    std::vector<EmitterQuery> seen;
    std::vector<uint32_t> seen_by, escaped;
    std::vector<Vec3> escaped_directions;
    for (size_t k = 0; k < active.size(); ++k) {
      if (!hits[k].Found()) {
        escaped.push_back(active[k]);
        escaped_directions.push_back(rays[k].direction);
        continue;
      }
      const Vertex v{active[k], ShadingPoint(scene, hits[k], rays[k]), scene.MaterialOf(hits[k].shape)};
      // Paths reach here from the camera or through delta lobes only, so
      // every emitter they hit counts.
      if (const Emitter* emitter = scene.EmitterOf(hits[k].shape)) {
        seen.push_back({emitter, Frame(hits[k].normal).ToLocal(-rays[k].direction), v.at.site});
        seen_by.push_back(v.path);
      }
      (OnlySpecular(scene.Material(v.material).Lobes()) ? specular : shaded).push_back(v);
    }
    const std::vector<EmitterAnswer> emitted = EvaluateEmitters(scene, seen);
    for (size_t q = 0; q < seen.size(); ++q)
      paths[seen_by[q]].radiance += paths[seen_by[q]].throughput * emitted[q].radiance;
    const std::vector<Vec3> environment = EnvironmentAlong(scene, escaped_directions);
    for (size_t q = 0; q < escaped.size(); ++q) paths[escaped[q]].radiance += paths[escaped[q]].throughput * environment[q];
    const uint32_t base = kTransportDimension + kPerSegment * uint32_t(depth - 1);
    Shade(scene, points, paths, shaded, base);
    if (depth >= settings_.max_depth) return {};
    return Reflect(scene, points, paths, specular, base);
  }

  // Direct light by one light sample, and f(wi, n)·E from the cache.
  void Shade(const SceneView& scene, const PrimarySamples& points, std::vector<Path>& paths,
             const std::vector<Vertex>& vertices, uint32_t base) const {
    std::vector<LightConnection> connections;
    std::vector<uint32_t> lit;
    std::vector<Vec3> from;
    std::vector<SurfaceQuery> diffuse;
    std::vector<Vec3> irradiance;
    std::vector<uint32_t> cached;
    for (const Vertex& v : vertices) {
      const uint32_t lobes = scene.Material(v.material).Lobes();
      if (scene.HasLights() && SamplesLights(lobes)) {
        connections.push_back(
            {v.material, v.at.position, v.at.ng, v.at.frame, v.at.wi, v.at.site, paths[v.path].ray.time, {}});
        lit.push_back(v.path);
        from.push_back(v.at.position);
      }
      if (HasDiffuseLobe(lobes) && v.at.wi.z != 0) {
        const float side = v.at.wi.z > 0 ? 1.0f : -1.0f;
        diffuse.push_back({v.material, v.at.wi, Vec3(0, 0, side), v.at.site});
        irradiance.push_back(records_.Estimate(v.at.position, v.at.frame.n * side));
        cached.push_back(v.path);
      }
    }
    const std::vector<LightDirection> lights =
        SampleLightsFrom(scene, points, from, lit, base + kLightChoice, base + kLightPosition);
    for (size_t k = 0; k < lights.size(); ++k) connections[k].light = lights[k];
    const std::vector<Vec3> direct = DirectLight(scene, connections);
    for (size_t k = 0; k < lit.size(); ++k) paths[lit[k]].radiance += paths[lit[k]].throughput * direct[k];
    const std::vector<SurfaceAnswer> f = EvaluateSurfaces(scene, TransportMode::kRadiance, diffuse);
    for (size_t k = 0; k < cached.size(); ++k)
      paths[cached[k]].radiance += paths[cached[k]].throughput * f[k].f * irradiance[k];
  }

  // Carries paths on through delta lobes.
  std::vector<uint32_t> Reflect(const SceneView& scene, const PrimarySamples& points, std::vector<Path>& paths,
                                const std::vector<Vertex>& vertices, uint32_t base) const {
    std::vector<ScatterQuery> queries;
    for (const Vertex& v : vertices) {
      ScatterQuery q{v.material, v.at.wi, v.at.site};
      q.uniform[0] = points.Get(v.path, base + kLobe);
      q.uniform[1] = points.Get(v.path, base + kDirection);
      q.uniform[2] = points.Get(v.path, base + kDirection + 1);
      queries.push_back(q);
    }
    const std::vector<ScatterAnswer> sampled = SampleSurfaces(scene, TransportMode::kRadiance, 0, queries);
    std::vector<uint32_t> next;
    for (size_t q = 0; q < queries.size(); ++q) {
      const ScatterAnswer& a = sampled[q];
      const Vertex& v = vertices[q];
      const Vec3 weight = a.weight * ShadingWeight(v.at.frame, v.at.ng, v.at.wi, a.wo, TransportMode::kRadiance);
      if (!(MaxComponent(weight) > 0)) continue;
      paths[v.path].throughput *= weight;
      Redirect(paths[v.path].ray, v.at.position, v.at.ng, Normalize(v.at.frame.ToWorld(a.wo)));
      next.push_back(v.path);
    }
    return next;
  }

  // The first hits on surfaces with a diffuse lobe of the camera rays
  // Prepare visits, in raster order, through specular chains.
  std::vector<SurfacePoint> VisitPoints(const SceneView& scene) const {
    const uint32_t g = settings_.prepare_grid, w = scene.FilmWidth() * g, h = scene.FilmHeight() * g;
    const float time = scene.ShutterTime(0.5f);
    std::vector<Ray> rays;
    std::vector<uint32_t> owner;
    for (uint32_t y = 0; y < h; ++y)
      for (uint32_t x = 0; x < w; ++x) {
        rays.push_back(scene.CameraRay((float(x) + 0.5f) / float(w), (float(y) + 0.5f) / float(h), 0.5f, 0.5f, time));
        owner.push_back(y * w + x);
      }
    std::vector<std::vector<SurfacePoint>> found(size_t(w) * h);
    for (int depth = 1; !rays.empty() && depth <= settings_.max_depth; ++depth) {
      std::vector<Hit> hits(rays.size());
      scene.Intersect(rays, hits);
      std::vector<ScatterQuery> queries;
      std::vector<Vertex> specular;
      for (size_t k = 0; k < rays.size(); ++k) {
        if (!hits[k].Found()) continue;
        const Vertex v{owner[k], ShadingPoint(scene, hits[k], rays[k]), scene.MaterialOf(hits[k].shape)};
        const uint32_t lobes = scene.Material(v.material).Lobes();
        if (HasDiffuseLobe(lobes) && v.at.wi.z != 0)
          found[v.path].push_back({v.at.position, v.at.frame.n * (v.at.wi.z > 0 ? 1.0f : -1.0f), v.at.ng});
        if (!OnlySpecular(lobes) || depth == settings_.max_depth) continue;
        ScatterQuery q{v.material, v.at.wi, v.at.site};
        for (int d = 0; d < 3; ++d) q.uniform[d] = Uniform(kVisitSalt, v.path, uint64_t(depth), uint64_t(d));
        queries.push_back(q);
        specular.push_back(v);
      }
      const std::vector<ScatterAnswer> sampled = SampleSurfaces(scene, TransportMode::kRadiance, 0, queries);
      rays.clear();
      owner.clear();
      for (size_t q = 0; q < queries.size(); ++q) {
        const ShadingPoint& at = specular[q].at;
        if (!(MaxComponent(sampled[q].weight) > 0) ||
            !(ShadingWeight(at.frame, at.ng, at.wi, sampled[q].wo, TransportMode::kRadiance) > 0))
          continue;
        Ray ray;
        ray.time = time;
        Redirect(ray, at.position, at.ng, Normalize(at.frame.ToWorld(sampled[q].wo)));
        rays.push_back(ray);
        owner.push_back(specular[q].path);
      }
    }
    std::vector<SurfacePoint> visits;
    for (const auto& points : found) visits.insert(visits.end(), points.begin(), points.end());
    return visits;
  }

  Settings settings_;
  IrradianceRecords records_;
  GatherSettings gather_;
};

}  // namespace
}  // namespace yarf

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::IrradianceCache>(registrar, "irradiance_cache", "1.0.0",
                                        "irradiance caching with gradients for indirect diffuse light");
}
