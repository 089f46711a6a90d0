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
// Primary sample space: 0–1 film (only for an environment seen directly:
// elsewhere the film position comes from the connection), 2–3 lens, 4 time; then (6, 7) light position, (8, 9)
// emission direction, (10) light choice; from 12 on, 4 per bounce: the
// BSDF direction pair, then (lobe choice, Russian roulette).
//
// Properties:
//   int max_depth  longest path in segments, counting the one to the
//                  camera (Mitsuba's convention); -1 (default) unbounded.
//   int rr_depth   bounces after which Russian roulette may end paths (5).

#include <algorithm>
#include <vector>

#include "wavefront.h"
#include "yarf/plugin.h"

namespace yarf {
namespace {

constexpr uint32_t kLightPosition = kTransportDimension, kEmission = kTransportDimension + 2,
                   kLightChoice = kTransportDimension + 4, kFirstBounce = kTransportDimension + 6,
                   kPerBounce = 4;

struct LightPath {
  Ray ray;
  Vec3 throughput;
};

class LightTracer final : public Transport {
 public:
  explicit LightTracer(const Properties& props)
      : length_(props) {}

  uint32_t Dimensions() const override {
    return kFirstBounce + kPerBounce * length_.Bounces();
  }

  void Prepare(const SceneView& scene) override { RefuseOrthographicCamera(scene, "light"); }

  void Evaluate(const SceneView& scene, const PrimarySamples& points, FilmSamples& out) override {
    out.splats = true;
    const size_t n = points.Count();
    if (length_.max_depth == 0 || !scene.HasLights()) return;
    const std::vector<LightStart> starts = StartLightPaths(scene, points, kLightChoice, kLightPosition, kEmission);
    std::vector<float> time(n);
    for (uint32_t i = 0; i < n; ++i) time[i] = scene.ShutterTime(points.Get(i, kTimeDimension));
    ConnectLightsToCamera(scene, points, starts, time, out);
    if (scene.HasEnvironment()) SeeEnvironment(scene, points, time, out);

    std::vector<LightPath> paths(n);
    std::vector<uint32_t> active;
    for (uint32_t i = 0; i < n; ++i) {
      if (!starts[i].Valid()) continue;
      paths[i] = {starts[i].FirstRay(time[i]), starts[i].Throughput()};
      if (MaxComponent(paths[i].throughput) > 0) active.push_back(i);
    }
    // A vertex after `bounce` segments reaches the camera in bounce + 1.
    for (int bounce = 1; !active.empty() && (length_.max_depth < 0 || bounce + 1 <= length_.max_depth); ++bounce)
      active = Bounce(scene, points, paths, active, bounce, out);
  }

 private:
  // Paths of one segment: a surface light seen directly by the camera.
  void ConnectLightsToCamera(const SceneView& scene, const PrimarySamples& points,
                             const std::vector<LightStart>& starts, const std::vector<float>& time,
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
    const std::vector<EmitterAnswer> emitted = EvaluateEmitters(scene, queries);
    std::vector<Ray> rays;
    std::vector<Vec3> values;
    std::vector<uint32_t> kept;
    for (size_t k = 0; k < owners.size(); ++k) {
      const LightSample& l = starts[owners[k]].light;
      const CameraConnection& c = connections[k];
      const Vec3 d = c.lens_point - l.position;
      const float dist2 = Dot(d, d);
      const float cos = l.delta_position ? 1.0f : std::abs(queries[k].w.z);
      const Vec3 value = emitted[k].radiance * (cos * c.importance / (dist2 * l.pdf));
      if (!(MaxComponent(value) > 0)) continue;
      rays.push_back(RayToLens(l.position, l.delta_position ? Vec3() : l.normal, c.lens_point, time[owners[k]]));
      values.push_back(value);
      kept.push_back(uint32_t(k));
    }
    SplatVisible(rays, values, [&](size_t q) { return connections[kept[q]]; },
                 [&](size_t q) { return owners[kept[q]]; }, scene, out);
  }

  // Paths of one segment from an environment: no light path reaches the
  // camera's pinhole from infinity, so a camera ray per point (its film
  // coordinates) splats the environment where it is seen directly. One
  // pass of W×H points puts one such ray in each pixel on average.
  void SeeEnvironment(const SceneView& scene, const PrimarySamples& points, const std::vector<float>& time,
                      FilmSamples& out) const {
    const size_t n = points.Count();
    std::vector<Ray> rays(n);
    std::vector<Hit> hits(n);
    for (uint32_t i = 0; i < n; ++i)
      rays[i] = scene.CameraRay(points.Get(i, kFilmDimension), points.Get(i, kFilmDimension + 1),
                                points.Get(i, kLensDimension), points.Get(i, kLensDimension + 1), time[i]);
    scene.Intersect(rays, hits);
    std::vector<Vec3> directions;
    std::vector<uint32_t> escaped;
    for (uint32_t i = 0; i < n; ++i)
      if (!hits[i].Found()) {
        directions.push_back(rays[i].direction);
        escaped.push_back(i);
      }
    const std::vector<Vec3> environment = EnvironmentAlong(scene, directions);
    for (size_t k = 0; k < escaped.size(); ++k) AddCameraSample(scene, points, escaped[k], environment[k], out);
  }

  // Intersects, connects every hit to the camera, scatters; returns the
  // paths that go on.
  std::vector<uint32_t> Bounce(const SceneView& scene, const PrimarySamples& points, std::vector<LightPath>& paths,
                               const std::vector<uint32_t>& active, int bounce, FilmSamples& out) const {
    std::vector<Ray> rays(active.size());
    std::vector<Hit> hits(active.size());
    for (size_t k = 0; k < active.size(); ++k) rays[k] = paths[active[k]].ray;
    scene.Intersect(rays, hits);

    struct Vertex {
      uint32_t path;
      ShadingPoint at;
      uint32_t material;
      float time;
    };
    std::vector<Vertex> vertices;
    std::vector<SurfaceQuery> to_camera;
    std::vector<CameraConnection> connections;
    std::vector<uint32_t> connected;  // into vertices
    for (size_t k = 0; k < active.size(); ++k) {
      if (!hits[k].Found()) continue;
      const Ray& ray = rays[k];
      const Vertex v{active[k], ShadingPointOf(scene, hits[k], ray), scene.MaterialOf(hits[k].shape), ray.time};
      CameraConnection c;
      if (scene.ConnectToCamera(v.at.position, points.Get(v.path, kLensDimension),
                                points.Get(v.path, kLensDimension + 1), c)) {
        to_camera.push_back({v.material, v.at.wi, v.at.frame.ToLocal(Normalize(c.lens_point - v.at.position)),
                             v.at.site});
        connections.push_back(c);
        connected.push_back(uint32_t(vertices.size()));
      }
      vertices.push_back(v);
    }
    // Splat the connections that carry light.
    const std::vector<SurfaceAnswer> f = EvaluateSurfaces(scene, TransportMode::kImportance, to_camera);
    std::vector<Ray> shadow;
    std::vector<Vec3> values;
    std::vector<uint32_t> kept;
    for (size_t q = 0; q < connected.size(); ++q) {
      const Vertex& v = vertices[connected[q]];
      const CameraConnection& c = connections[q];
      const Vec3 d = c.lens_point - v.at.position;
      const float shading = ShadingWeight(v.at.frame, v.at.ng, v.at.wi, to_camera[q].wo, TransportMode::kImportance);
      const Vec3 value =
          paths[v.path].throughput * f[q].f * (std::abs(to_camera[q].wo.z) * shading * c.importance / Dot(d, d));
      if (!(MaxComponent(value) > 0)) continue;
      shadow.push_back(RayToLens(v.at.position, v.at.ng, c.lens_point, v.time));
      values.push_back(value);
      kept.push_back(uint32_t(q));
    }
    SplatVisible(shadow, values, [&](size_t k) { return connections[kept[k]]; },
                 [&](size_t k) { return vertices[connected[kept[k]]].path; }, scene, out);

    // Scatter importance onward.
    if (length_.max_depth >= 0 && bounce + 2 > length_.max_depth) return {};
    const uint32_t base = kFirstBounce + kPerBounce * uint32_t(bounce - 1);
    std::vector<ScatterQuery> queries;
    std::vector<uint32_t> scattering;  // into vertices
    for (uint32_t j = 0; j < vertices.size(); ++j) {
      const Vertex& v = vertices[j];
      ScatterQuery q{v.material, v.at.wi, v.at.site};
      q.uniform[0] = points.Get(v.path, base + 2);
      q.uniform[1] = points.Get(v.path, base);
      q.uniform[2] = points.Get(v.path, base + 1);
      queries.push_back(q);
      scattering.push_back(j);
    }
    const std::vector<ScatterAnswer> sampled = SampleSurfaces(scene, TransportMode::kImportance, 0, queries);
    std::vector<uint32_t> next;
    for (size_t q = 0; q < queries.size(); ++q) {
      const Vertex& v = vertices[scattering[q]];
      LightPath& p = paths[v.path];
      const float shading = ShadingWeight(v.at.frame, v.at.ng, v.at.wi, sampled[q].wo, TransportMode::kImportance);
      if (!(sampled[q].pdf > 0) || !(MaxComponent(sampled[q].weight * shading) > 0)) continue;
      p.throughput *= sampled[q].weight * shading;
      const Vec3 dir = Normalize(v.at.frame.ToWorld(sampled[q].wo));
      Redirect(p.ray, v.at.position, v.at.ng, dir);
      if (bounce >= length_.rr_depth && !Survives(p.throughput, points.Get(v.path, base + 3))) continue;
      next.push_back(v.path);
    }
    return next;
  }

  // Traces the shadow rays and splats the values whose rays are clear.
  template <typename ConnectionOf, typename PointOf>
  static void SplatVisible(const std::vector<Ray>& rays, const std::vector<Vec3>& values, ConnectionOf connection,
                           PointOf point, const SceneView& scene, FilmSamples& out) {
    std::vector<uint8_t> occluded(rays.size());
    scene.Occluded(rays, occluded);
    for (size_t k = 0; k < rays.size(); ++k)
      if (!occluded[k]) {
        const CameraConnection c = connection(k);
        out.Add(uint32_t(point(k)), c.raster_x, c.raster_y, values[k]);
      }
  }

  PathLength length_;
};

}  // namespace
}  // namespace yarf

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::LightTracer>(registrar, "light", "1.0.0",
                                    "light tracer: paths from the lights, connected to the camera");
}
