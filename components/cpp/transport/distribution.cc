// distribution — distribution ray tracing (Cook, Porter & Carpenter 1984).
//
// Rays distributed over the lens (depth of field), the shutter interval
// (motion blur), the area of the lights (soft shadows) and the glossy
// lobes of the surfaces (blurry reflection and refraction). At every hit
// one light sample (next-event estimation, no MIS) with the whole BSDF;
// the path goes on only through non-diffuse lobes (glossy and specular),
// so diffuse surfaces receive direct light only. Emitters count when seen
// directly or through specular lobes, which light samples cannot reach,
// and so does the environment.
// On models whose lobes are all diffuse or all non-diffuse, this computes
// the path integral over E (glossy|specular)* any-lobe L: the same as the
// path tracer with diffuse_indirect = false, by another estimator.
//
// Paths advance as a wavefront (one call per SurfaceModel and Emitter per
// bounce). Primary sample space as the path tracer's: 0–1 film, 2–3 lens,
// 4 time, then 8 per bounce from 6: light position pair, direction pair,
// (light choice, lobe choice), (Russian roulette, unused).
//
// Parameters: DistributionRayTracer::Parameters() below.

#include <algorithm>
#include <vector>

#include "yarf/support/wavefront.h"
#include "yarf/plugin.h"

namespace yarf {
namespace {

constexpr uint32_t kPerBounce = 8;
constexpr uint32_t kLightPosition = 0, kDirection = 2, kLightChoice = 4, kLobe = 5, kRoulette = 6;
// Every lobe but the diffuse ones.
constexpr uint32_t kOnward = kScatterReflect | kScatterRefract | kScatterGlossy | kScatterDelta;

struct Path {
  Ray ray;
  Vec3 throughput{1, 1, 1};
  Vec3 radiance;
  // Whether an emitter hit next counts: camera rays and specular bounces.
  bool sees_emitters = true;
};

class DistributionRayTracer final : public Transport {
 public:
  // Each sample lands in its own pixel: the film may be rendered in tiles.
  static std::vector<std::string> Capabilities() { return {kPixelLocalCapability}; }
  static ParameterSchema Parameters() { return PathLength::Parameters(); }

  explicit DistributionRayTracer(const Properties& props)
      : length_(props) {}

  void Prepare(const SceneView& scene) override { RefuseMedia(scene, "distribution"); }
  uint32_t Dimensions() const override {
    return kTransportDimension + kPerBounce * length_.Bounces();
  }

  void Evaluate(const SceneView& scene, const PrimarySamples& points, FilmSamples& out) override {
    const size_t n = points.Count();
    std::vector<Path> paths(n);
    std::vector<uint32_t> active;
    for (uint32_t i = 0; i < n; ++i) {
      paths[i].ray = CameraRayOf(scene, points, i);
      active.push_back(i);
    }
    for (int depth = 1; !active.empty() && length_.max_depth != 0; ++depth)
      active = Bounce(scene, points, paths, active, depth);
    for (uint32_t i = 0; i < n; ++i) AddCameraSample(scene, points, i, paths[i].radiance, out);
  }

 private:
  struct Vertex {
    uint32_t path;
    ShadingPoint at;
    uint32_t material;
  };

  std::vector<uint32_t> Bounce(const SceneView& scene, const PrimarySamples& points, std::vector<Path>& paths,
                               const std::vector<uint32_t>& active, int depth) const {
    std::vector<Ray> rays(active.size());
    std::vector<Hit> hits(active.size());
    for (size_t k = 0; k < active.size(); ++k) rays[k] = paths[active[k]].ray;
    scene.Intersect(rays, hits);
    std::vector<Vertex> vertices;
    std::vector<EmitterQuery> seen;
    std::vector<uint32_t> seen_by, escaped;
    std::vector<Vec3> escaped_directions;
    for (size_t k = 0; k < active.size(); ++k) {
      if (!hits[k].Found()) {
        if (paths[active[k]].sees_emitters) {
          escaped.push_back(active[k]);
          escaped_directions.push_back(rays[k].direction);
        }
        continue;
      }
      const Emitter* emitter = scene.EmitterOf(hits[k].shape);
      if (emitter && paths[active[k]].sees_emitters) {
        seen.push_back(EmitterQuery::Seen(emitter, rays[k], hits[k]));
        seen_by.push_back(active[k]);
      }
      vertices.push_back({active[k], ShadingPoint(scene, hits[k], rays[k]), scene.MaterialOf(hits[k].shape)});
    }
    const std::vector<EmitterAnswer> emitted = EvaluateEmitters(scene, seen);
    for (size_t q = 0; q < seen.size(); ++q)
      paths[seen_by[q]].radiance += paths[seen_by[q]].throughput * emitted[q].radiance;
    const std::vector<Vec3> environment = EnvironmentAlong(scene, escaped_directions);
    for (size_t q = 0; q < escaped.size(); ++q) paths[escaped[q]].radiance += paths[escaped[q]].throughput * environment[q];
    if (length_.max_depth >= 0 && depth >= length_.max_depth) return {};
    const uint32_t base = kTransportDimension + kPerBounce * uint32_t(depth - 1);
    SampleLights(scene, points, paths, vertices, base);
    return Continue(scene, points, paths, vertices, base, depth);
  }

  // One light sample per vertex, the whole BSDF, no MIS.
  void SampleLights(const SceneView& scene, const PrimarySamples& points, std::vector<Path>& paths,
                    const std::vector<Vertex>& vertices, uint32_t base) const {
    if (!scene.HasLights()) return;
    std::vector<const Vertex*> lit;
    std::vector<Vec3> from;
    std::vector<uint32_t> owners;
    for (const Vertex& v : vertices) {
      if (!SamplesLights(scene.Material(v.material).Lobes())) continue;
      lit.push_back(&v);
      from.push_back(v.at.position);
      owners.push_back(v.path);
    }
    const std::vector<LightDirection> lights =
        SampleLightsFrom(scene, points, from, owners, base + kLightChoice, base + kLightPosition);
    std::vector<LightConnection> connections;
    for (size_t k = 0; k < lit.size(); ++k) {
      const Vertex& v = *lit[k];
      connections.push_back(
          {v.material, v.at.position, v.at.ng, v.at.frame, v.at.wi, v.at.site, paths[v.path].ray.time, lights[k]});
    }
    const std::vector<Vec3> light = DirectLight(scene, connections);
    for (size_t k = 0; k < owners.size(); ++k) paths[owners[k]].radiance += paths[owners[k]].throughput * light[k];
  }

  // Goes on through the non-diffuse lobes.
  std::vector<uint32_t> Continue(const SceneView& scene, const PrimarySamples& points, std::vector<Path>& paths,
                                 const std::vector<Vertex>& vertices, uint32_t base, int depth) const {
    std::vector<ScatterQuery> queries;
    std::vector<uint32_t> owners;
    for (uint32_t k = 0; k < vertices.size(); ++k) {
      const Vertex& v = vertices[k];
      ScatterQuery q{v.material, v.at.wi, v.at.site};
      q.uniform[0] = points.Get(v.path, base + kLobe);
      q.uniform[1] = points.Get(v.path, base + kDirection);
      q.uniform[2] = points.Get(v.path, base + kDirection + 1);
      queries.push_back(q);
      owners.push_back(k);
    }
    const std::vector<ScatterAnswer> sampled = SampleSurfaces(scene, TransportMode::kRadiance, kOnward, queries);
    std::vector<uint32_t> next;
    for (size_t q = 0; q < queries.size(); ++q) {
      const ScatterAnswer& a = sampled[q];
      if (!(a.pdf > 0) || !(MaxComponent(a.weight) > 0)) continue;
      const Vertex& v = vertices[owners[q]];
      const float shading = ShadingWeight(v.at.frame, v.at.ng, v.at.wi, a.wo, TransportMode::kRadiance);
      if (!(shading > 0)) continue;
      Path& p = paths[v.path];
      p.throughput *= a.weight;
      p.sees_emitters = (a.flags & kScatterDelta) != 0;
      const Vec3 dir = Normalize(v.at.frame.ToWorld(a.wo));
      Redirect(p.ray, v.at.position, v.at.ng, dir);
      if (depth >= length_.rr_depth && !Survives(p.throughput, points.Get(v.path, base + kRoulette))) continue;
      next.push_back(v.path);
    }
    return next;
  }

  PathLength length_;
};

}  // namespace
}  // namespace yarf

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::DistributionRayTracer>(
      registrar, "distribution", "1.0.0",
      "distribution ray tracer: depth of field, motion blur, soft shadows, glossy reflection");
}
