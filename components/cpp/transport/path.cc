// path — the eye path tracer, as a batch Function over primary sample space.
//
// Unidirectional path tracing with next-event estimation (one light sample
// per vertex: SceneView::SampleLightsFrom, spheres by solid angle, an
// environment by its own distribution), multiple importance
// sampling of light and BSDF samples with the power heuristic, and Russian
// roulette. Paths advance together, one bounce at a time (a wavefront):
// each bounce intersects all live rays as one batch and calls each
// SurfaceModel and Emitter once per batch, never per sample, so a
// component in another process costs one call per bounce.
//
// Primary sample space: coordinates 0–1 film, 2–3 lens, 4 time, then 8 per
// bounce from 6 on, laid out so that each 2-D choice gets a pair (2k, 2k+1)
// of the sampler, the pairs low-discrepancy samplers stratify jointly:
// light position, BSDF direction, (light choice, BSDF lobe), (Russian
// roulette, unused). Point, spot and directional lights are sampled by
// next-event estimation only (nothing hits them); rays that leave the
// scene see the environment.
//
// Paths that scatter from a diffuse lobe may be made to end there (their
// light from the next vertex is still counted): with diffuse_indirect
// false the tracer computes exactly the paths a distribution ray tracer
// does, E (glossy|specular)* any-lobe L, for checking one against the
// other.
//
// Parameters: PathTracer::Parameters() below.

#include <algorithm>
#include <vector>

#include "yarf/support/per_thread.h"
#include "yarf/support/wavefront.h"
#include "yarf/plugin.h"

namespace yarf {
namespace {

constexpr uint32_t kFirstBounceDimension = kTransportDimension;
constexpr uint32_t kDimensionsPerBounce = 8;
// Offsets within a bounce's dimensions.
constexpr uint32_t kLightPosition = 0, kBsdfDirection = 2, kLightChoice = 4, kBsdfLobe = 5,
                   kRoulette = 6;

struct Path {
  Ray ray;
  Vec3 throughput{1, 1, 1};
  Vec3 radiance{0, 0, 0};
  // Solid-angle pdf of the last BSDF sample, and whether an emitter hit
  // next takes full weight (camera ray, delta lobe, or no light sample).
  float bsdf_pdf = 0;
  bool full_weight = true;
  // The path ends at the next hit, after gathering its emission.
  bool last = false;
};

// A surface hit that scatters further, made in place (emplace_back).
struct Vertex {
  Vertex(uint32_t path, const SceneView& scene, const Hit& hit, const Ray& ray)
      : path(path), at(scene, hit, ray), time(ray.time) {}
  uint32_t path;
  ShadingPoint at;
  float time;
};

// The shadow rays of the light samples that would contribute, with the
// path each belongs to and what it adds if unoccluded.
struct ShadowTests {
  std::vector<Ray> rays;
  std::vector<uint32_t> owner;
  std::vector<Vec3> contribution;
  void Clear() {
    rays.clear();
    owner.clear();
    contribution.clear();
  }
};

// One thread's buffers, kept from bounce to bounce and batch to batch:
// a bounce allocates none of them once they have grown to its batch.
struct Workspace {
  std::vector<Path> paths;
  std::vector<uint32_t> active, next;
  // The bounce's rays and hits, its vertices and their materials, and
  // which of its rays hit emitters or escaped (indices into active).
  std::vector<Ray> rays;
  std::vector<Hit> hits;
  std::vector<Vertex> vertices;
  std::vector<uint32_t> vertex_material, emitted, escaped;
  // Next-event estimation's samples, and the points and paths they are
  // drawn for.
  LightSamples lights;
  std::vector<Vec3> light_from;
  std::vector<uint32_t> light_owners;
  ShadowTests shadows;
  std::vector<uint8_t> occluded;
  // A material group's calls: directions toward the light samples, the
  // BSDF's uniform numbers, roulette's, and the paths of the group.
  std::vector<float> wo, u, roulette, coordinate;
  std::vector<uint32_t> owners;
};

class PathTracer final : public Transport {
 public:
  // Each sample lands in its own pixel: the film may be rendered in tiles.
  static std::vector<std::string> Capabilities() { return {kPixelLocalCapability}; }
  static ParameterSchema Parameters() {
    ParameterSchema schema = PathLength::Parameters();
    schema.push_back(
        Parameter::Bool("diffuse_indirect").Default(true).Doc("whether paths go on after a diffuse bounce"));
    return schema;
  }

  explicit PathTracer(const Properties& props)
      : length_(props), diffuse_indirect_(props.Bool("diffuse_indirect", true)) {}

  uint32_t Dimensions() const override {
    return kFirstBounceDimension + kDimensionsPerBounce * length_.Bounces();
  }

  void Evaluate(const SceneView& scene, const PrimarySamples& points, FilmSamples& out) override {
    const size_t n = points.Count();
    const PerThread<Workspace>::Lease lease(workspaces_);
    Workspace& w = *lease;
    w.paths.assign(n, Path{});
    w.active.clear();
    for (uint32_t i = 0; i < n; ++i) {
      w.paths[i].ray = CameraRayOf(scene, points, i);
      w.active.push_back(i);
    }
    for (int depth = 1; !w.active.empty() && length_.max_depth != 0; ++depth) {
      Bounce(scene, points, w, depth);
      std::swap(w.active, w.next);
    }
    for (uint32_t i = 0; i < n; ++i) AddCameraSample(scene, points, i, w.paths[i].radiance, out);
  }

 private:
  // Advances the paths in w.active by one bounce; those that go on are
  // w.next.
  void Bounce(const SceneView& scene, const PrimarySamples& points, Workspace& w, int depth) const {
    std::vector<Path>& paths = w.paths;
    const std::vector<uint32_t>& active = w.active;
    std::vector<Ray>& rays = w.rays;
    std::vector<Hit>& hits = w.hits;
    rays.resize(active.size());
    hits.resize(active.size());  // every hit written by Intersect
    for (size_t k = 0; k < active.size(); ++k) rays[k] = paths[active[k]].ray;
    scene.Intersect(rays, hits);

    const bool may_scatter = length_.max_depth < 0 || depth < length_.max_depth;
    std::vector<Vertex>& vertices = w.vertices;
    std::vector<uint32_t>& vertex_material = w.vertex_material;
    std::vector<uint32_t>& emitted = w.emitted;
    std::vector<uint32_t>& escaped = w.escaped;
    vertices.clear();
    vertex_material.clear();
    emitted.clear();
    escaped.clear();
    for (size_t k = 0; k < active.size(); ++k) {
      const Hit& hit = hits[k];
      if (!hit.Found()) {
        escaped.push_back(uint32_t(k));
        continue;
      }
      if (scene.EmitterOf(hit.shape)) emitted.push_back(uint32_t(k));
      if (!may_scatter || paths[active[k]].last) continue;
      vertices.emplace_back(active[k], scene, hit, rays[k]);
      vertex_material.push_back(scene.MaterialOf(hit.shape));
    }
    AddEmission(scene, paths, active, rays, hits, emitted);
    if (scene.HasEnvironment()) AddEnvironment(scene, paths, active, rays, escaped);

    const uint32_t base = kFirstBounceDimension + kDimensionsPerBounce * uint32_t(depth - 1);
    const auto groups = GroupBy(vertex_material);
    // One light sample for every vertex whose material can use it, all in
    // one SampleLightsFrom call and one Radiance call per emitter, then
    // per material the BSDF toward them.
    SampleLights(scene, points, w, LitVertices(scene, groups), base);
    const LightSamples& lights = w.lights;
    ShadowTests& shadows = w.shadows;
    shadows.Clear();
    w.next.clear();
    for (const auto& [material, members] : groups) {
      const SurfaceModel& model = scene.Material(material);
      // The group's vertices as its model's calls take them, for both.
      SurfaceBatch batch(&scene, members.size());
      for (const uint32_t member : members) batch.Add(vertices[member].at.wi, vertices[member].at.site);
      const bool sample_lights = TakesLightSamples(scene, model);
      if (sample_lights) WeighLightSamples(model, batch, w, members, lights);
      ScatterBsdf(points, model, batch, w, members, base, depth, sample_lights);
    }
    // The shadow rays of every group, in one batch.
    std::vector<uint8_t>& occluded = w.occluded;
    occluded.assign(shadows.rays.size(), 0);
    scene.Occluded(shadows.rays, occluded);
    for (size_t q = 0; q < shadows.rays.size(); ++q)
      if (!occluded[q]) paths[shadows.owner[q]].radiance += shadows.contribution[q];
  }

  // Emitters hit by the rays of this bounce, weighted against light sampling.
  void AddEmission(const SceneView& scene, std::vector<Path>& paths, const std::vector<uint32_t>& active,
                   const std::vector<Ray>& rays, const std::vector<Hit>& hits,
                   const std::vector<uint32_t>& emitted) const {
    const std::vector<Vec3> le = EmissionSeen(scene, rays, hits, emitted);
    for (size_t j = 0; j < emitted.size(); ++j) {
      const uint32_t k = emitted[j];
      Path& p = paths[active[k]];
      const float weight = p.full_weight ? 1 : PowerHeuristic(p.bsdf_pdf, scene.LightPdfFrom(rays[k], hits[k]));
      p.radiance += p.throughput * le[j] * weight;
    }
  }

  // The environment seen by the rays of this bounce that left the scene,
  // weighted against light sampling.
  void AddEnvironment(const SceneView& scene, std::vector<Path>& paths, const std::vector<uint32_t>& active,
                      const std::vector<Ray>& rays, const std::vector<uint32_t>& escaped) const {
    std::vector<Vec3> directions(escaped.size()), le(escaped.size());
    std::vector<float> light_pdf(escaped.size());
    for (size_t j = 0; j < escaped.size(); ++j) directions[j] = rays[escaped[j]].direction;
    scene.Escaped(directions, le, light_pdf);
    for (size_t j = 0; j < escaped.size(); ++j) {
      Path& p = paths[active[escaped[j]]];
      const float weight = p.full_weight ? 1 : PowerHeuristic(p.bsdf_pdf, light_pdf[j]);
      p.radiance += p.throughput * le[j] * weight;
    }
  }

  // Next-event estimation's light samples, one for each vertex of `lit`,
  // into w.lights.
  void SampleLights(const SceneView& scene, const PrimarySamples& points, Workspace& w,
                    const std::vector<uint32_t>& lit, uint32_t base) const {
    w.light_owners.resize(lit.size());
    w.light_from.resize(lit.size());
    for (size_t j = 0; j < lit.size(); ++j) {
      w.light_owners[j] = w.vertices[lit[j]].path;
      w.light_from[j] = w.vertices[lit[j]].at.position;
    }
    SampleLightsFrom(scene, points, w.light_from, w.light_owners, base + kLightChoice, base + kLightPosition,
                     w.lights.direction);
    w.lights.Weigh(scene, lit, w.vertices.size());
  }

  // Weighs the light samples of a material's vertices by the BSDF and
  // MIS, and adds the shadow rays of those that would contribute.
  void WeighLightSamples(const SurfaceModel& model, const SurfaceBatch& batch, Workspace& w,
                         const std::vector<uint32_t>& members, const LightSamples& lights) const {
    const std::vector<Path>& paths = w.paths;
    const std::vector<Vertex>& vertices = w.vertices;
    ShadowTests& shadows = w.shadows;
    const size_t m = members.size();
    std::vector<float>& wo = w.wo;
    wo.resize(3 * m);
    for (size_t j = 0; j < m; ++j)
      vertices[members[j]].at.frame.ToLocal(lights.Direction(members[j]).direction).Store(&wo[3 * j]);
    const SurfaceBatch::Evaluation bsdf = batch.Evaluate(model, TransportMode::kRadiance, wo, Densities::kForward);
    for (size_t j = 0; j < m; ++j) {
      const LightDirection& light = lights.Direction(members[j]);
      if (!light.emitter || !(light.pdf > 0)) continue;
      const Vertex& v = vertices[members[j]];
      const Path& p = paths[v.path];
      const float cos_surface = std::abs(wo[3 * j + 2]);
      const float mis = light.delta ? 1.0f : PowerHeuristic(light.pdf, bsdf.pdf[j]);
      const float shading =
          ShadingWeight(v.at.frame, v.at.ng, v.at.wi, Vec3::Load(&wo[3 * j]), TransportMode::kRadiance);
      const Vec3 c = p.throughput * bsdf.F(j) * lights.Radiance(members[j]) * (cos_surface * mis * shading / light.pdf);
      if (!(MaxComponent(c) > 0)) continue;
      // Field by field: copying the whole Ray rereads, as one wide load,
      // fields just stored one at a time, a stall per shadow ray.
      const Ray ray = ShadowRayToLight(v.at.position, v.at.ng, light, v.time);
      shadows.rays.emplace_back(ray.origin, ray.tnear, ray.direction, ray.tfar, ray.time);
      shadows.owner.push_back(v.path);
      shadows.contribution.push_back(c);
    }
  }

  // Samples the BSDF for each vertex, extends the path, applies roulette.
  void ScatterBsdf(const PrimarySamples& points, const SurfaceModel& model, const SurfaceBatch& batch,
                   Workspace& w, const std::vector<uint32_t>& members, uint32_t base, int depth,
                   bool sampled_lights) const {
    std::vector<Path>& paths = w.paths;
    const std::vector<Vertex>& vertices = w.vertices;
    const size_t m = members.size();
    std::vector<float>&u = w.u, &roulette = w.roulette, &coordinate = w.coordinate;
    std::vector<uint32_t>& owners = w.owners;
    u.resize(3 * m);
    roulette.resize(m);
    coordinate.resize(m);
    owners.resize(m);
    for (size_t j = 0; j < m; ++j) owners[j] = vertices[members[j]].path;
    // The lobe choice and the direction, interleaved per vertex.
    for (uint32_t j = 0; j < 3; ++j) {
      points.Gather(owners, base + (j == 0 ? kBsdfLobe : kBsdfDirection + j - 1), coordinate);
      for (size_t q = 0; q < m; ++q) u[3 * q + j] = coordinate[q];
    }
    if (depth >= length_.rr_depth) points.Gather(owners, base + kRoulette, roulette);
    const SurfaceBatch::Samples sampled = batch.Sample(model, TransportMode::kRadiance, 0, u, Densities::kForward);
    for (size_t j = 0; j < m; ++j) {
      const Vertex& v = vertices[members[j]];
      Path& p = paths[v.path];
      const Vec3 out = sampled.Wo(j);
      const Vec3 weight =
          sampled.Weight(j) * ShadingWeight(v.at.frame, v.at.ng, v.at.wi, out, TransportMode::kRadiance);
      if (!(sampled.pdf[j] > 0) || !(MaxComponent(weight) > 0)) continue;
      p.throughput *= weight;
      p.bsdf_pdf = sampled.pdf[j];
      p.full_weight = !sampled_lights || (sampled.flags[j] & kScatterDelta);
      p.last = !diffuse_indirect_ && (sampled.flags[j] & kScatterDiffuse);
      const Vec3 dir = Normalize(v.at.frame.ToWorld(out));
      Redirect(p.ray, v.at.position, v.at.ng, dir);
      if (depth >= length_.rr_depth && !Survives(p.throughput, roulette[j])) continue;
      w.next.push_back(v.path);
    }
  }

  PathLength length_;
  bool diffuse_indirect_;
  PerThread<Workspace> workspaces_;
};

}  // namespace
}  // namespace yarf

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::PathTracer>(registrar, "path", "1.0.0",
                                   "eye path tracer with next-event estimation and MIS");
}
