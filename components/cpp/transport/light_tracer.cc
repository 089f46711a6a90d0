// light — the light tracer (Dutré, Lafortune & Willems; Veach §10.2).
//
// Paths start at the lights and are connected, at every vertex, to the
// camera; each connection splats to wherever on the film the vertex
// appears. Surfaces scatter importance (TransportMode::kImportance), so
// glass does not scale it by 1/η². The light tracer sees no path whose
// vertex next to the camera is specular (a mirror or glass seen directly):
// such pixels stay black, as in every light tracer. An environment seen
// directly is added by camera rays (the film coordinates), as Mitsuba's
// particle tracer adds visible emitters. Paths advance as a
// wavefront: each bounce calls each SurfaceModel and Emitter once.
//
// In media, light paths are walked by delta tracking and scatter by the
// phase function; every connection to the camera crosses media by ratio
// tracking and null boundaries (volpath's estimators: see
// medium_transport.h). A light's medium is the one its point lies in, seen
// along the line from the camera (and, on an emitting boundary, the one
// it emits into).
//
// Primary sample space: 0–1 film (only for an environment seen directly:
// elsewhere the film position comes from the connection), 2–3 lens, 4 time; then (6, 7) light position, (8, 9)
// emission direction, (10) light choice; from 12 on, 4 per bounce: the
// BSDF direction pair, then (lobe choice, Russian roulette).
//
// Parameters: LightTracer::Parameters() below; max_depth counts the
// segment to the camera.

#include <algorithm>
#include <vector>

#include <bit>

#include "medium_transport.h"
#include "yarf/plugin.h"

namespace yarf {
namespace {

constexpr uint32_t kLightPosition = kTransportDimension, kEmission = kTransportDimension + 2,
                   kLightChoice = kTransportDimension + 4, kFirstBounce = kTransportDimension + 6,
                   kPerBounce = 4;

struct LightPath : SpectralPath {
  Ray ray;
  uint32_t medium = kNoMedium;
  // Vertices after the light's own: the next one reaches the camera in
  // bounce + 1 segments.
  int bounce = 1;
};

// A connection of a vertex to the camera, before its transmittance.
struct CameraLink {
  uint32_t path;
  ShadowWalk shadow;
  Vec3 value;
  // The path's r_u there.
  Vec3 r_path{1, 1, 1};
  CameraConnection camera;
};

uint32_t FloatBits(float f) { return std::bit_cast<uint32_t>(f); }

class LightTracer final : public Transport {
 public:
  static ParameterSchema Parameters() { return PathLength::Parameters(); }

  explicit LightTracer(const Properties& props)
      : length_(props) {}

  uint32_t Dimensions() const override {
    return kFirstBounce + kPerBounce * length_.Bounces();
  }

  void Prepare(const SceneView& scene) override {
    RefuseUnreachableCamera(scene, "light");
    RefuseEmittingMedia(scene, "light");
    null_boundaries_ = HasNullBoundaries(scene);
  }

  void Evaluate(const SceneView& scene, const PrimarySamples& points, FilmSamples& out) override {
    out.splats = true;
    const size_t n = points.Count();
    if (length_.max_depth == 0 || !scene.HasLights()) return;
    const std::vector<LightStart> starts = StartLightPaths(scene, points, kLightChoice, kLightPosition, kEmission);
    std::vector<float> time(n);
    for (uint32_t i = 0; i < n; ++i) time[i] = scene.ShutterTime(points.Get(i, kTimeDimension));
    const std::vector<uint32_t> media = LightStartMedia(scene, starts, time.empty() ? 0.0f : time[0]);
    std::vector<LightPath> paths(n);
    for (uint32_t i = 0; i < n; ++i) {
      LightPath& p = paths[i];
      p.random.seed = Hash(FloatBits(points.Get(i, kLightPosition)), FloatBits(points.Get(i, kLightPosition + 1)),
                           FloatBits(points.Get(i, kEmission)), FloatBits(points.Get(i, kEmission + 1)),
                           FloatBits(points.Get(i, kLightChoice)));
      p.ChooseHero();
    }
    ConnectLightsToCamera(scene, points, starts, media, paths, time, out);
    if (scene.HasEnvironment()) SeeEnvironment(scene, points, paths, time, out);

    std::vector<uint32_t> active;
    for (uint32_t i = 0; i < n; ++i) {
      if (!starts[i].Valid()) continue;
      LightPath& p = paths[i];
      p.ray = starts[i].FirstRay(time[i]);
      p.beta = starts[i].Throughput();
      p.medium = media[i];
      if (MaxComponent(p.beta) > 0 && length_.max_depth != 1) active.push_back(i);
    }
    while (!active.empty()) active = Bounce(scene, points, paths, active, out);
  }

 private:
  // Paths of one segment: a surface light seen directly by the camera.
  void ConnectLightsToCamera(const SceneView& scene, const PrimarySamples& points,
                             const std::vector<LightStart>& starts, const std::vector<uint32_t>& media,
                             const std::vector<LightPath>& paths, const std::vector<float>& time,
                             FilmSamples& out) const {
    std::vector<EmitterQuery> queries;
    std::vector<CameraConnection> connections;
    std::vector<uint32_t> owners;
    for (uint32_t i = 0; i < starts.size(); ++i) {
      const LightSample& l = starts[i].light;
      // A point light is a delta on the film: the camera never sees it,
      // as camera rays never hit it. A light at infinity starts from a
      // disk that is not there to be seen (SeeEnvironment sees it).
      if (!l.emitter || !(l.pdf > 0) || l.delta_position || l.infinite) continue;
      CameraConnection c;
      if (!scene.ConnectToCamera(l.position, points.Get(i, kLensDimension), points.Get(i, kLensDimension + 1), c))
        continue;
      const Vec3 to_camera = Normalize(c.lens_point - l.position);
      queries.push_back({l.emitter, Frame(l.normal).ToLocal(to_camera), SurfaceSite::Uv(l.u, l.v)});
      connections.push_back(c);
      owners.push_back(i);
    }
    const std::vector<EmitterAnswer> emitted = EvaluateEmitters(scene, queries, Densities::kNone);
    std::vector<CameraLink> links;
    for (size_t k = 0; k < owners.size(); ++k) {
      const uint32_t i = owners[k];
      const LightSample& l = starts[i].light;
      const CameraConnection& c = connections[k];
      const Vec3 d = c.lens_point - l.position;
      const Vec3 value = emitted[k].radiance * (std::abs(queries[k].w.z) * c.importance / (Dot(d, d) * l.pdf));
      if (!(MaxComponent(value) > 0)) continue;
      const Ray ray = RayToLens(l.position, l.normal, c.lens_point, time[i]);
      const uint32_t medium =
          l.shape == kNoShape ? media[i] : scene.MediaOf(l.shape).Beyond(ray.direction, l.normal, media[i]);
      links.push_back({i, {ray, medium, paths[i].hero, Hash(paths[i].random.seed, 0u)}, value, Vec3(1, 1, 1), c});
    }
    Splat(scene, links, out);
  }

  // Paths of one segment from an environment: no light path reaches the
  // camera's pinhole from infinity, so a camera ray per point (its film
  // coordinates) splats the environment where it is seen directly,
  // through media and null boundaries. One pass of W×H points puts one
  // such ray in each pixel on average.
  void SeeEnvironment(const SceneView& scene, const PrimarySamples& points, const std::vector<LightPath>& paths,
                      const std::vector<float>& time, FilmSamples& out) const {
    const size_t n = points.Count();
    std::vector<ShadowWalk> views(n);
    std::vector<Vec3> directions(n);
    for (uint32_t i = 0; i < n; ++i) {
      const Ray ray = CameraRayOf(scene, points, i);
      views[i] = {ray, scene.CameraMedium(), paths[i].hero, Hash(paths[i].random.seed, 1u)};
      views[i].ray.time = time[i];
      directions[i] = ray.direction;
    }
    const std::vector<ShadowTransmittance> through = Transmittances(scene, views, null_boundaries_);
    const std::vector<Vec3> environment = EnvironmentAlong(scene, directions);
    for (uint32_t i = 0; i < n; ++i) {
      const float mean = ChannelMean(through[i].r_l);
      if (MaxComponent(through[i].value) > 0 && mean > 0)
        AddCameraSample(scene, points, i, environment[i] * through[i].value / mean, out);
    }
  }

  // Whether a vertex after `bounce` segments may scatter on: its next
  // vertex reaches the camera in bounce + 2.
  bool MayScatter(int bounce) const { return length_.max_depth < 0 || bounce + 2 <= length_.max_depth; }

  // Intersects, walks the paths in media, connects every vertex to the
  // camera, scatters; returns the paths that go on.
  std::vector<uint32_t> Bounce(const SceneView& scene, const PrimarySamples& points, std::vector<LightPath>& paths,
                               const std::vector<uint32_t>& active, FilmSamples& out) const {
    std::vector<Ray> rays(active.size());
    std::vector<Hit> hits(active.size());
    for (size_t k = 0; k < active.size(); ++k) rays[k] = paths[active[k]].ray;
    scene.Intersect(rays, hits);

    // Through the media: each path scatters, is absorbed or reaches its hit.
    std::vector<std::pair<uint32_t, Vec3>> scattered;  // path, point
    const std::vector<uint8_t> at_surface = WalkToHits(
        scene, active, hits, [&](uint32_t i) { return WalkStateOf(paths[i]); }, [](uint32_t, const Collision&) {},
        [&](uint32_t i, const Collision& c) { scattered.emplace_back(i, c.position); });

    std::vector<uint32_t> next;
    std::vector<CameraLink> links;
    ScatterInMedia(scene, points, paths, scattered, links, next);

    struct Vertex {
      uint32_t path;
      uint32_t shape;
      ShadingPoint at;
      uint32_t material;
      float time;
    };
    // Sized once, their entries made in place: this runs for every bounce.
    std::vector<Vertex> vertices;
    std::vector<SurfaceQuery> to_camera;
    std::vector<CameraConnection> connections;
    std::vector<uint32_t> connected;  // into vertices
    vertices.reserve(active.size());
    to_camera.reserve(active.size());
    connections.reserve(active.size());
    connected.reserve(active.size());
    for (size_t k = 0; k < active.size(); ++k) {
      if (!at_surface[k] || !hits[k].Found()) continue;
      const Ray& ray = rays[k];
      LightPath& p = paths[active[k]];
      if (IsNullBoundary(scene, hits[k].shape)) {
        // A boundary only: on through it, no bounce counted.
        p.medium = scene.MediaOf(hits[k].shape).Beyond(ray.direction, hits[k].normal, p.medium);
        Redirect(p.ray, ray.origin + ray.direction * hits[k].t, hits[k].normal, ray.direction);
        next.push_back(active[k]);
        continue;
      }
      const Vertex& v = vertices.emplace_back(active[k], hits[k].shape, ShadingPoint(scene, hits[k], ray),
                                              scene.MaterialOf(hits[k].shape), ray.time);
      CameraConnection& c = connections.emplace_back();
      if (!scene.ConnectToCamera(v.at.position, points.Get(v.path, kLensDimension),
                                 points.Get(v.path, kLensDimension + 1), c)) {
        connections.pop_back();
        continue;
      }
      to_camera.emplace_back(v.material, v.at.wi, v.at.frame.ToLocal(Normalize(c.lens_point - v.at.position)),
                             v.at.site);
      connected.push_back(uint32_t(vertices.size() - 1));
    }
    // Connect to the camera.
    const std::vector<SurfaceAnswer> f =
        EvaluateSurfaces(scene, TransportMode::kImportance, to_camera, Densities::kNone);
    for (size_t q = 0; q < connected.size(); ++q) {
      const Vertex& v = vertices[connected[q]];
      const LightPath& p = paths[v.path];
      const CameraConnection& c = connections[q];
      const Vec3 d = c.lens_point - v.at.position;
      const float shading = ShadingWeight(v.at.frame, v.at.ng, v.at.wi, to_camera[q].wo, TransportMode::kImportance);
      const Vec3 value = p.beta * f[q].f * (std::abs(to_camera[q].wo.z) * shading * c.importance / Dot(d, d));
      if (!(MaxComponent(value) > 0)) continue;
      const Ray ray = RayToLens(v.at.position, v.at.ng, c.lens_point, v.time);
      const uint32_t medium = scene.MediaOf(v.shape).Beyond(ray.direction, v.at.ng, p.medium);
      links.push_back({v.path, {ray, medium, p.hero, Hash(p.random.seed, uint32_t(p.bounce), 1u)}, value, p.r_u, c});
    }
    Splat(scene, links, out);

    // Scatter importance onward.
    std::vector<ScatterQuery> queries;
    std::vector<uint32_t> scattering;  // into vertices
    queries.reserve(vertices.size());
    scattering.reserve(vertices.size());
    for (uint32_t j = 0; j < vertices.size(); ++j) {
      const Vertex& v = vertices[j];
      LightPath& p = paths[v.path];
      if (!MayScatter(p.bounce)) continue;
      ScatterQuery& q = queries.emplace_back(v.material, v.at.wi, v.at.site);
      q.uniform[0] = Uniform(points, v.path, p, 2);
      q.uniform[1] = Uniform(points, v.path, p, 0);
      q.uniform[2] = Uniform(points, v.path, p, 1);
      scattering.push_back(j);
    }
    const std::vector<ScatterAnswer> sampled =
        SampleSurfaces(scene, TransportMode::kImportance, 0, queries, Densities::kForward);
    for (size_t q = 0; q < queries.size(); ++q) {
      const Vertex& v = vertices[scattering[q]];
      LightPath& p = paths[v.path];
      const float shading = ShadingWeight(v.at.frame, v.at.ng, v.at.wi, sampled[q].wo, TransportMode::kImportance);
      if (!(sampled[q].pdf > 0) || !(MaxComponent(sampled[q].weight * shading) > 0)) continue;
      p.beta *= sampled[q].weight * shading;
      const Vec3 dir = Normalize(v.at.frame.ToWorld(sampled[q].wo));
      p.medium = scene.MediaOf(v.shape).Beyond(dir, v.at.ng, p.medium);
      Redirect(p.ray, v.at.position, v.at.ng, dir);
      if (Continues(points, v.path, p)) next.push_back(v.path);
    }
    return next;
  }

  // Coordinate `offset` of the path's current bounce; walk numbers beyond
  // the bounces that have coordinates of their own.
  float Uniform(const PrimarySamples& points, uint32_t i, LightPath& p, uint32_t offset) const {
    if (uint32_t(p.bounce) > length_.Bounces()) return p.random.Next();
    return points.Get(i, kFirstBounce + kPerBounce * uint32_t(p.bounce - 1) + offset);
  }

  // The bounce ends: Russian roulette from rr_depth on, then the next one.
  bool Continues(const PrimarySamples& points, uint32_t i, LightPath& p) const {
    if (p.bounce >= length_.rr_depth && !Survives(p.beta, Uniform(points, i, p, 3))) return false;
    ++p.bounce;
    return true;
  }

  // Points scattered in media: each connected to the camera through the
  // phase function, then scattered on by it.
  void ScatterInMedia(const SceneView& scene, const PrimarySamples& points, std::vector<LightPath>& paths,
                      const std::vector<std::pair<uint32_t, Vec3>>& scattered, std::vector<CameraLink>& links,
                      std::vector<uint32_t>& next) const {
    std::vector<uint32_t> keys(scattered.size());
    for (size_t k = 0; k < scattered.size(); ++k) keys[k] = paths[scattered[k].first].medium;
    for (const auto& [medium_index, members] : GroupBy(keys)) {
      const Medium& medium = scene.MediumAt(medium_index);
      const size_t m = members.size();
      std::vector<float> wi(3 * m), wo(3 * m), position(3 * m), value(m), pdf(m), u(2 * m), weight(m);
      std::vector<CameraConnection> connections(m);
      std::vector<uint8_t> seen(m);
      for (size_t j = 0; j < m; ++j) {
        const auto& [i, at] = scattered[members[j]];
        LightPath& p = paths[i];
        seen[j] = scene.ConnectToCamera(at, points.Get(i, kLensDimension), points.Get(i, kLensDimension + 1),
                                        connections[j]);
        const Vec3 to_camera = seen[j] ? Normalize(connections[j].lens_point - at) : -p.ray.direction;
        to_camera.Store(&wi[3 * j]);
        (-p.ray.direction).Store(&wo[3 * j]);
        at.Store(&position[3 * j]);
        u[2 * j] = Uniform(points, i, p, 0);
        u[2 * j + 1] = Uniform(points, i, p, 1);
      }
      medium.EvaluatePhase(wi, wo, position, value, pdf);
      for (size_t j = 0; j < m; ++j) {
        const auto& [i, at] = scattered[members[j]];
        const LightPath& p = paths[i];
        if (!seen[j]) continue;
        const CameraConnection& c = connections[j];
        const Vec3 d = c.lens_point - at;
        const Vec3 contribution = p.beta * (value[j] * c.importance / Dot(d, d));
        if (!(MaxComponent(contribution) > 0)) continue;
        const Ray ray = RayToLens(at, Vec3(), c.lens_point, p.ray.time);
        links.push_back({i, {ray, p.medium, p.hero, Hash(p.random.seed, uint32_t(p.bounce), 2u)}, contribution, p.r_u, c});
      }
      // The phase function is symmetric: sampled with wi back toward the
      // light, its wo is where the light goes on (forward: wo = -wi).
      for (size_t j = 0; j < m; ++j) (-paths[scattered[members[j]].first].ray.direction).Store(&wi[3 * j]);
      medium.SamplePhase(wi, position, u, wo, weight, pdf);
      for (size_t j = 0; j < m; ++j) {
        const auto& [i, at] = scattered[members[j]];
        LightPath& p = paths[i];
        if (!MayScatter(p.bounce) || !(pdf[j] > 0) || !(weight[j] > 0)) continue;
        p.beta *= weight[j];
        p.ray.origin = at;
        p.ray.direction = Normalize(Vec3::Load(&wo[3 * j]));
        p.ray.tnear = 0;
        p.ray.tfar = kInfinity;
        if (Continues(points, i, p)) next.push_back(i);
      }
    }
  }

  // Splats each connection by the transmittance of its way to the lens
  // (volpath's estimator for a light that cannot be hit: no MIS).
  void Splat(const SceneView& scene, const std::vector<CameraLink>& links, FilmSamples& out) const {
    std::vector<ShadowWalk> shadows(links.size());
    for (size_t k = 0; k < links.size(); ++k) shadows[k] = links[k].shadow;
    const std::vector<ShadowTransmittance> through = Transmittances(scene, shadows, null_boundaries_);
    for (size_t k = 0; k < links.size(); ++k) {
      const CameraLink& link = links[k];
      const float mean = ChannelMean(link.r_path * through[k].r_l);
      if (!(MaxComponent(through[k].value) > 0) || !(mean > 0)) continue;
      out.Add(link.path, link.camera.raster_x, link.camera.raster_y, link.value * through[k].value / mean);
    }
  }

  PathLength length_;
  bool null_boundaries_ = false;
};

}  // namespace
}  // namespace yarf

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::LightTracer>(registrar, "light", "1.0.0",
                                    "light tracer: paths from the lights, connected to the camera");
}
