// whitted — Whitted's recursive ray tracer (1980).
//
// Camera rays; at each hit the light of every light source gathered into
// one point (LightPoint: a mesh light's centroid, a sphere's facing
// point, a point light itself, a directional light's direction) with one
// shadow ray each, so shadows are hard; and, on surfaces with delta lobes,
// both the mirror reflection and the refraction traced further, each
// weighted by its Fresnel factor. No diffuse or glossy interreflection;
// an environment is seen only by the rays that leave the scene (directly
// and in mirrors), as it has no point to gather it into. Everything is deterministic but the
// position within the pixel, so passes only antialias.
//
// Rays advance level by level as a wavefront: each level intersects all
// its rays and calls each SurfaceModel and Emitter once per group. A point
// keeps its 64 strongest branches per level (KeepStrongest).
//
// Primary sample space: 0–1 film, 2–3 lens, 4 time; nothing more.
//
// Parameters: Whitted::Parameters() below.

#include <algorithm>
#include <numeric>
#include <vector>

#include "yarf/support/wavefront.h"
#include "yarf/plugin.h"

namespace yarf {
namespace {

// A ray of the tree: the point it serves and what it carries to it.
struct Branch {
  uint32_t point;
  Ray ray;
  Vec3 weight;
};

class Whitted final : public Transport {
 public:
  // Each sample lands in its own pixel: the film may be rendered in tiles.
  static std::vector<std::string> Capabilities() { return {kPixelLocalCapability}; }
  static ParameterSchema Parameters() {
    return {Parameter::Int("max_depth").Default(6).Range(0, double(PathLength::kLongest)).Doc(
        "longest path in segments, counting the shadow ray (Mitsuba's: 1 emitters only)")};
  }

  explicit Whitted(const Properties& props)
      : max_depth_(int(props.Int("max_depth", 6, 0, PathLength::kLongest))) {}

  uint32_t Dimensions() const override { return kTransportDimension; }
  void Prepare(const SceneView& scene) override { RefuseMedia(scene, "whitted"); }

  void Evaluate(const SceneView& scene, const PrimarySamples& points, FilmSamples& out) override {
    const size_t n = points.Count();
    std::vector<Vec3> radiance(n);
    std::vector<Branch> level(n);
    for (uint32_t i = 0; i < n; ++i) level[i] = {i, CameraRayOf(scene, points, i), Vec3(1, 1, 1)};
    for (int depth = 1; !level.empty() && depth <= max_depth_; ++depth) {
      level = Trace(scene, level, depth, radiance);
      KeepStrongest(level, n);
    }
    for (uint32_t i = 0; i < n; ++i) AddCameraSample(scene, points, i, radiance[i], out);
  }

 private:
  struct Vertex {
    uint32_t branch;
    ShadingPoint at;
    uint32_t material;
  };

  // Shades the hits of one level; returns the next level's rays.
  std::vector<Branch> Trace(const SceneView& scene, const std::vector<Branch>& level, int depth,
                            std::vector<Vec3>& radiance) const {
    std::vector<Ray> rays(level.size());
    std::vector<Hit> hits(level.size());
    for (size_t k = 0; k < level.size(); ++k) rays[k] = level[k].ray;
    scene.Intersect(rays, hits);

    std::vector<Vertex> vertices;
    std::vector<EmitterQuery> seen;
    std::vector<uint32_t> seen_by, escaped;
    std::vector<Vec3> escaped_directions;
    for (size_t k = 0; k < level.size(); ++k) {
      if (!hits[k].Found()) {
        escaped.push_back(uint32_t(k));
        escaped_directions.push_back(rays[k].direction);
        continue;
      }
      if (const Emitter* emitter = scene.EmitterOf(hits[k].shape)) {
        seen.push_back(EmitterQuery::Seen(emitter, rays[k], hits[k]));
        seen_by.push_back(uint32_t(k));
      }
      vertices.push_back({uint32_t(k), ShadingPoint(scene, hits[k], rays[k]), scene.MaterialOf(hits[k].shape)});
    }
    const std::vector<EmitterAnswer> emitted = EvaluateEmitters(scene, seen, Densities::kNone);
    for (size_t q = 0; q < seen.size(); ++q) {
      const Branch& b = level[seen_by[q]];
      radiance[b.point] += b.weight * emitted[q].radiance;
    }
    const std::vector<Vec3> environment = EnvironmentAlong(scene, escaped_directions);
    for (size_t q = 0; q < escaped.size(); ++q) {
      const Branch& b = level[escaped[q]];
      radiance[b.point] += b.weight * environment[q];
    }
    if (depth >= max_depth_) return {};
    AddDirectLight(scene, level, vertices, radiance);
    return Spawn(scene, level, vertices);
  }

  // Every light, as one point, through one shadow ray each.
  void AddDirectLight(const SceneView& scene, const std::vector<Branch>& level, const std::vector<Vertex>& vertices,
                      std::vector<Vec3>& radiance) const {
    std::vector<LightConnection> connections;
    for (const Vertex& v : vertices) {
      if (!SamplesLights(scene.Material(v.material).Lobes())) continue;
      for (uint32_t l = 0; l < scene.LightCount(); ++l)
        connections.push_back({v.material, v.at.position, v.at.ng, v.at.frame, v.at.wi, v.at.site,
                               level[v.branch].ray.time, scene.LightPoint(l, v.at.position)});
    }
    const std::vector<Vec3> light = DirectLight(scene, connections);
    size_t k = 0;
    for (const Vertex& v : vertices) {
      if (!SamplesLights(scene.Material(v.material).Lobes())) continue;
      const Branch& b = level[v.branch];
      for (uint32_t l = 0; l < scene.LightCount(); ++l) radiance[b.point] += b.weight * light[k++];
    }
  }

  // Both delta lobes of every vertex that has them, each with its weight.
  std::vector<Branch> Spawn(const SceneView& scene, const std::vector<Branch>& level,
                            const std::vector<Vertex>& vertices) const {
    std::vector<ScatterQuery> queries;
    std::vector<uint32_t> owners;
    for (uint32_t k = 0; k < vertices.size(); ++k) {
      const Vertex& v = vertices[k];
      if (!(scene.Material(v.material).Lobes() & kScatterDelta)) continue;
      ScatterQuery q{v.material, v.at.wi, v.at.site};
      q.uniform[0] = q.uniform[1] = q.uniform[2] = 0.5f;
      queries.push_back(q);
      owners.push_back(k);
    }
    std::vector<Branch> next;
    for (const uint32_t side : {kScatterReflect, kScatterRefract}) {
      const std::vector<ScatterAnswer> sampled =
          SampleSurfaces(scene, TransportMode::kRadiance, side | kScatterDelta, queries, Densities::kForward);
      for (size_t q = 0; q < queries.size(); ++q) {
        if (!(sampled[q].pdf > 0) || !(MaxComponent(sampled[q].weight) > 0)) continue;
        const Vertex& v = vertices[owners[q]];
        const float shading = ShadingWeight(v.at.frame, v.at.ng, v.at.wi, sampled[q].wo, TransportMode::kRadiance);
        if (!(shading > 0)) continue;
        const Branch& parent = level[v.branch];
        Branch b{parent.point, parent.ray, parent.weight * sampled[q].weight};
        const Vec3 dir = Normalize(v.at.frame.ToWorld(sampled[q].wo));
        Redirect(b.ray, v.at.position, v.at.ng, dir);
        next.push_back(b);
      }
    }
    return next;
  }

  // Glass splits every branch in two: between glass and mirrors a point's
  // branches would double at every level, 2^max_depth of them. Each point
  // keeps its kMaxBranches strongest (by their largest channel), which a
  // path of the default max_depth never exceeds.
  static constexpr uint32_t kMaxBranches = 64;
  static void KeepStrongest(std::vector<Branch>& level, size_t points) {
    std::vector<uint32_t> count(points, 0);
    bool over = false;
    for (const Branch& b : level) over = ++count[b.point] > kMaxBranches || over;
    if (!over) return;
    std::vector<uint32_t> order(level.size());
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
      if (level[a].point != level[b].point) return level[a].point < level[b].point;
      return MaxComponent(level[a].weight) > MaxComponent(level[b].weight);
    });
    std::vector<Branch> kept;
    kept.reserve(std::min<size_t>(level.size(), points * kMaxBranches));
    uint32_t run = 0;
    for (size_t k = 0; k < order.size(); ++k) {
      run = k > 0 && level[order[k]].point == level[order[k - 1]].point ? run + 1 : 0;
      if (run < kMaxBranches) kept.push_back(level[order[k]]);
    }
    level = std::move(kept);
  }

  int max_depth_;
};

}  // namespace
}  // namespace yarf

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::Whitted>(registrar, "whitted", "1.0.0",
                                "Whitted ray tracer: hard shadows, mirror reflection and refraction");
}
