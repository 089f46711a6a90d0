// volpath — volumetric path tracing with null scattering, as pbrt-v4's
// VolPathIntegrator (after Miller, Georgiev & Jarosz 2019).
//
// In a medium, collisions are drawn by delta tracking against the
// medium's majorants in one channel, the hero, chosen per path; every
// channel's density is kept as a ratio (pbrt-v4's r_u and r_l), and each
// contribution is divided by their mean over channels: the balance
// heuristic over hero channels, so a σ_t that differs per channel is
// sampled well by one of them and never averaged away. At a real
// scattering vertex (a medium's collision or a surface) the tracer
// samples a light — its shadow ray through media by ratio tracking and
// through null boundaries — and the phase function or BSDF, the two
// combined by the balance heuristic. Null boundaries (the `null`
// material) are stepped through without counting a bounce.
//
// Paths advance together, one segment at a time: each segment intersects
// all live rays as one batch, walks each medium's rays together (one
// Majorants call, then one Coefficients call per round of tentative
// collisions), and calls each SurfaceModel, Emitter and phase function
// once per batch.
//
// Primary sample space: as `path` (8 coordinates per scattering vertex
// from 6 on: light position, scattering direction, light choice, lobe,
// roulette); the walks through media draw from a hash of the path's
// coordinates, as do vertices beyond the 64th.
//
// Parameters: VolPathTracer::Parameters() below, as `path`'s; medium
// collisions count as vertices in max_depth and rr_depth, null boundaries
// not, unless max_medium_depth bounds them apart (a random walk under the
// skin of a subsurface material scatters hundreds of times in one of
// pbrt's bounces).

#include <algorithm>
#include <bit>
#include <vector>

#include "medium_transport.h"
#include "yarf/plugin.h"

namespace yarf {
namespace {

constexpr uint32_t kFirstBounceDimension = kTransportDimension;
constexpr uint32_t kDimensionsPerBounce = 8;
// Offsets within a vertex's dimensions.
constexpr uint32_t kLightPosition = 0, kScatterDirection = 2, kLightChoice = 4, kScatterLobe = 5, kRoulette = 6;
// Vertices with primary-sample coordinates of their own.
constexpr int kPrimaryVertices = 64;

struct VolPath : SpectralPath {
  Ray ray;
  uint32_t medium = kNoMedium;
  Vec3 radiance;
  // Real scattering vertices so far: all of them, those max_depth counts
  // (all but the medium's when max_medium_depth counts those), the medium's.
  int vertices = 0, depth = 0, medium_depth = 0;
  // Emission found next takes full weight: the camera ray, a delta lobe.
  bool specular = true;
  // The last real scattering vertex, where light samples were taken.
  Vec3 scatter_point;
};

// A light sample from a vertex, before its shadow ray's transmittance.
struct LightLink {
  uint32_t path;
  Ray ray;
  uint32_t medium;
  // beta·f·L (a phase function's p·L), without transmittance or weight.
  Vec3 unweighted;
  // The path's r_u at the vertex, the light's density (its choice
  // included) and the scattering's density for the same direction.
  Vec3 r_path;
  float light_pdf = 0, scatter_pdf = 0;
  bool delta = false;
};

// A point scattered in a medium.
struct MediumVertex {
  uint32_t path;
  Vec3 position;
};

// A surface hit that scatters.
struct SurfaceVertex {
  uint32_t path;
  uint32_t shape;
  ShadingPoint at;
};

uint32_t FloatBits(float f) { return std::bit_cast<uint32_t>(f); }

class VolPathTracer final : public Transport {
 public:
  // Each sample lands in its own pixel: the film may be rendered in tiles.
  static std::vector<std::string> Capabilities() { return {kPixelLocalCapability}; }
  static ParameterSchema Parameters() {
    ParameterSchema schema = PathLength::Parameters();
    schema.push_back(Parameter::Int("max_medium_depth")
                         .Default(0)
                         .Range(-1, double(PathLength::kLongest))
                         .Doc("scatterings in media a path may have apart from max_depth, which then counts surface "
                              "vertices alone; 0: media count in max_depth, as Mitsuba's and pbrt's; -1 unbounded"));
    return schema;
  }

  explicit VolPathTracer(const Properties& props)
      : length_(props), max_medium_depth_(int(props.Int("max_medium_depth", 0, -1, PathLength::kLongest))) {}

  uint32_t Dimensions() const override {
    // Vertices a path may have: max_depth's, and the media's apart.
    uint64_t vertices = length_.Bounces();
    if (max_medium_depth_ != 0) vertices += max_medium_depth_ < 0 ? kPrimaryVertices : uint64_t(max_medium_depth_);
    return kFirstBounceDimension + kDimensionsPerBounce * uint32_t(std::min<uint64_t>(vertices, kPrimaryVertices));
  }

  void Prepare(const SceneView& scene) override { null_boundaries_ = HasNullBoundaries(scene); }

  void Evaluate(const SceneView& scene, const PrimarySamples& points, FilmSamples& out) override {
    const size_t n = points.Count();
    std::vector<VolPath> paths(n);
    std::vector<uint32_t> active;
    active.reserve(n);
    for (uint32_t i = 0; i < n; ++i) {
      VolPath& p = paths[i];
      p.ray = CameraRayOf(scene, points, i);
      p.scatter_point = p.ray.origin;
      p.medium = scene.CameraMedium();
      p.random.seed = Hash(FloatBits(points.Get(i, 0)), FloatBits(points.Get(i, 1)), FloatBits(points.Get(i, 2)),
                           FloatBits(points.Get(i, 3)), FloatBits(points.Get(i, 4)), FloatBits(points.Get(i, 5)));
      p.ChooseHero();
      active.push_back(i);
    }
    if (length_.max_depth != 0)
      while (!active.empty()) active = Segment(scene, points, paths, active);
    for (uint32_t i = 0; i < n; ++i) AddCameraSample(scene, points, i, paths[i].radiance, out);
  }

 private:
  bool MayScatter(const VolPath& p) const { return length_.max_depth < 0 || p.depth + 1 < length_.max_depth; }
  bool MayScatterInMedium(const VolPath& p) const {
    if (max_medium_depth_ == 0) return MayScatter(p);
    return max_medium_depth_ < 0 || p.medium_depth < max_medium_depth_;
  }
  // Counts a scattering vertex the path just made.
  void Scattered(VolPath& p, bool in_medium) const {
    ++p.vertices;
    ++(in_medium && max_medium_depth_ != 0 ? p.medium_depth : p.depth);
  }

  // Coordinate `offset` of the path's current vertex.
  static float Uniform(const PrimarySamples& points, uint32_t i, VolPath& p, uint32_t offset) {
    if (p.vertices >= kPrimaryVertices) return p.random.Next();
    return points.Get(i, kFirstBounceDimension + kDimensionsPerBounce * uint32_t(p.vertices) + offset);
  }

  // Russian roulette on the path's weight relative to its density (pbrt-v4's β/mean r_u).
  bool Survives(const PrimarySamples& points, uint32_t i, VolPath& p) const {
    if (p.vertices < length_.rr_depth) return true;
    const float mean = ChannelMean(p.r_u);
    const float survive = mean > 0 ? std::min(MaxComponent(p.beta) / mean, 0.95f) : 0.0f;
    if (!(Uniform(points, i, p, kRoulette) < survive)) return false;
    p.beta *= 1.0f / survive;
    return true;
  }

  // Advances every path in `active` by one segment; returns those that go on.
  std::vector<uint32_t> Segment(const SceneView& scene, const PrimarySamples& points, std::vector<VolPath>& paths,
                                const std::vector<uint32_t>& active) const {
    const size_t count = active.size();
    std::vector<Ray> rays(count);
    std::vector<Hit> hits(count);
    for (size_t k = 0; k < count; ++k) rays[k] = paths[active[k]].ray;
    scene.Intersect(rays, hits);

    // Through the media: each path scatters, is absorbed or reaches its hit.
    std::vector<MediumVertex> scattered;
    const std::vector<uint8_t> at_surface = WalkToHits(
        scene, active, hits, [&](uint32_t i) { return WalkStateOf(paths[i]); },
        [&](uint32_t i, const Collision& c) { AddEmission(paths[i], c); },
        [&](uint32_t i, const Collision& c) { scattered.push_back({i, c.position}); });

    std::vector<uint32_t> next;
    std::vector<LightLink> links;
    ScatterInMedia(scene, points, paths, scattered, links, next);

    std::vector<uint32_t> escaped, emitted;
    std::vector<SurfaceVertex> vertices;
    for (size_t k = 0; k < count; ++k) {
      if (!at_surface[k]) continue;
      const uint32_t i = active[k];
      VolPath& p = paths[i];
      const Hit& hit = hits[k];
      if (!hit.Found()) {
        escaped.push_back(uint32_t(k));
        continue;
      }
      if (scene.EmitterOf(hit.shape)) emitted.push_back(uint32_t(k));
      const Vec3 position = rays[k].origin + rays[k].direction * hit.t;
      if (IsNullBoundary(scene, hit.shape)) {
        // A boundary only: on through it, no bounce counted.
        p.medium = scene.MediaOf(hit.shape).Beyond(p.ray.direction, hit.normal, p.medium);
        Redirect(p.ray, position, hit.normal, p.ray.direction);
        next.push_back(i);
        continue;
      }
      if (!MayScatter(p)) continue;
      vertices.push_back({i, hit.shape, ShadingPoint(scene, hit, rays[k])});
    }
    AddEmission(scene, paths, active, rays, hits, emitted);
    if (scene.HasEnvironment()) AddEnvironment(scene, paths, active, rays, escaped);
    ScatterAtSurfaces(scene, points, paths, vertices, links, next);

    AddLightSamples(scene, paths, links);
    return next;
  }

  // The light a medium emits at a tentative collision of path p, before
  // delta tracking decides what the collision is (pbrt-v4's estimator).
  static void AddEmission(VolPath& p, const Collision& c) {
    if (!(MaxComponent(c.emission) > 0)) return;
    const int h = int(p.hero);
    const float pdf = c.sigma_maj[h] * c.transmittance_maj[h];
    const Vec3 r_e = p.r_u * c.sigma_maj * c.transmittance_maj / pdf;
    if (MaxComponent(r_e) > 0)
      p.radiance += p.beta * c.transmittance_maj * c.sigma_a * c.emission / (pdf * ChannelMean(r_e));
  }

  // Light samples and phase samples at the points scattered in media.
  void ScatterInMedia(const SceneView& scene, const PrimarySamples& points, std::vector<VolPath>& paths,
                      const std::vector<MediumVertex>& scattered, std::vector<LightLink>& links,
                      std::vector<uint32_t>& next) const {
    std::vector<uint32_t> keys, all;
    std::vector<MediumVertex> vertices;
    // Each vertex's phase sample numbers, drawn before its light sample's
    // (a deep path draws them from its own stream, in this order).
    std::vector<float> u_phase;
    for (const MediumVertex& v : scattered) {
      VolPath& p = paths[v.path];
      if (!MayScatterInMedium(p)) continue;
      p.scatter_point = v.position;
      all.push_back(uint32_t(vertices.size()));
      vertices.push_back(v);
      keys.push_back(p.medium);
      u_phase.push_back(Uniform(points, v.path, p, kScatterDirection));
      u_phase.push_back(Uniform(points, v.path, p, kScatterDirection + 1));
    }
    // The light samples of every medium's vertices, in one SampleLightsFrom
    // call and one Radiance call per emitter.
    const LightSamples lights = scene.HasLights() ? SampleLightsAt(scene, points, paths, vertices, all) : LightSamples{};
    for (const auto& [medium_index, members] : GroupBy(keys)) {
      const Medium& medium = scene.MediumAt(medium_index);
      const size_t m = members.size();
      std::vector<Vec3> from(m);
      std::vector<uint32_t> owners(m);
      std::vector<float> wi(3 * m), position(3 * m), u(2 * m);
      for (size_t j = 0; j < m; ++j) {
        const MediumVertex& v = vertices[members[j]];
        from[j] = v.position;
        owners[j] = v.path;
        (-paths[v.path].ray.direction).Store(&wi[3 * j]);
        v.position.Store(&position[3 * j]);
        u[2 * j] = u_phase[2 * members[j]];
        u[2 * j + 1] = u_phase[2 * members[j] + 1];
      }
      if (scene.HasLights()) {
        std::vector<float> wo(3 * m), value(m), pdf(m);
        for (size_t j = 0; j < m; ++j) lights.Direction(members[j]).direction.Store(&wo[3 * j]);
        medium.EvaluatePhase(wi, wo, position, value, pdf);
        for (size_t j = 0; j < m; ++j) {
          const LightDirection& light = lights.Direction(members[j]);
          const VolPath& p = paths[owners[j]];
          if (!light.emitter || !(light.pdf > 0) || !(value[j] > 0)) continue;
          Ray ray;
          ray.origin = from[j];
          ray.direction = light.direction;
          ray.tfar = light.AtInfinity() ? kInfinity
                                        : (light.delta ? light.distance
                                                       : std::max(0.0f, light.distance - SurfaceOffset(light.position)));
          ray.time = p.ray.time;
          links.push_back({owners[j], ray, p.medium, p.beta * lights.Radiance(members[j]) * value[j], p.r_u, light.pdf,
                           pdf[j], light.delta});
        }
      }
      std::vector<float> wo(3 * m), weight(m), pdf(m);
      medium.SamplePhase(wi, position, u, wo, weight, pdf);
      for (size_t j = 0; j < m; ++j) {
        VolPath& p = paths[owners[j]];
        if (!(pdf[j] > 0) || !(weight[j] > 0)) continue;
        p.beta *= weight[j];
        p.r_l = p.r_u / pdf[j];
        p.specular = false;
        p.ray.origin = from[j];
        p.ray.direction = Normalize(Vec3::Load(&wo[3 * j]));
        p.ray.tnear = 0;
        p.ray.tfar = kInfinity;
        Scattered(p, true);
        if (Survives(points, owners[j], p)) next.push_back(owners[j]);
      }
    }
  }

  // Light samples and BSDF samples at the surface vertices, one call per material.
  void ScatterAtSurfaces(const SceneView& scene, const PrimarySamples& points, std::vector<VolPath>& paths,
                         const std::vector<SurfaceVertex>& vertices, std::vector<LightLink>& links,
                         std::vector<uint32_t>& next) const {
    std::vector<uint32_t> keys(vertices.size());
    for (size_t k = 0; k < vertices.size(); ++k) keys[k] = scene.MaterialOf(vertices[k].shape);
    const auto groups = GroupBy(keys);
    // One light sample for every vertex whose material can use it, all in
    // one SampleLightsFrom call and one Radiance call per emitter, then
    // per material the BSDF toward them.
    const LightSamples lights = SampleLightsAt(scene, points, paths, vertices, LitVertices(scene, groups));
    for (const auto& [material, members] : groups) {
      const SurfaceModel& model = scene.Material(material);
      const size_t m = members.size();
      SurfaceBatch batch(&scene, m);
      for (size_t j = 0; j < m; ++j) {
        const SurfaceVertex& v = vertices[members[j]];
        batch.Add(v.at.wi, v.at.site);
        paths[v.path].scatter_point = v.at.position;
      }
      if (TakesLightSamples(scene, model)) {
        std::vector<float> wo(3 * m);
        for (size_t j = 0; j < m; ++j)
          vertices[members[j]].at.frame.ToLocal(lights.Direction(members[j]).direction).Store(&wo[3 * j]);
        const SurfaceBatch::Evaluation bsdf =
            batch.Evaluate(model, TransportMode::kRadiance, wo, Densities::kForward);
        for (size_t j = 0; j < m; ++j) {
          const SurfaceVertex& v = vertices[members[j]];
          const VolPath& p = paths[v.path];
          const LightDirection& light = lights.Direction(members[j]);
          if (!light.emitter || !(light.pdf > 0)) continue;
          const Vec3 out = Vec3::Load(&wo[3 * j]);
          const float cos = std::abs(out.z) *
                            ShadingWeight(v.at.frame, v.at.ng, v.at.wi, out, TransportMode::kRadiance);
          const Vec3 unweighted = p.beta * bsdf.F(j) * lights.Radiance(members[j]) * cos;
          if (!(MaxComponent(unweighted) > 0)) continue;
          const uint32_t medium = scene.MediaOf(v.shape).Beyond(light.direction, v.at.ng, p.medium);
          links.push_back({v.path, ShadowRayToLight(v.at.position, v.at.ng, light, p.ray.time), medium, unweighted,
                           p.r_u, light.pdf, bsdf.pdf[j], light.delta});
        }
      }
      std::vector<float> u(3 * m);
      for (size_t j = 0; j < m; ++j) {
        const SurfaceVertex& v = vertices[members[j]];
        VolPath& p = paths[v.path];
        u[3 * j] = Uniform(points, v.path, p, kScatterLobe);
        u[3 * j + 1] = Uniform(points, v.path, p, kScatterDirection);
        u[3 * j + 2] = Uniform(points, v.path, p, kScatterDirection + 1);
      }
      const SurfaceBatch::Samples sampled =
          batch.Sample(model, TransportMode::kRadiance, 0, u, Densities::kForward);
      for (size_t j = 0; j < m; ++j) {
        const SurfaceVertex& v = vertices[members[j]];
        VolPath& p = paths[v.path];
        const Vec3 out = sampled.Wo(j);
        const Vec3 w = sampled.Weight(j) * ShadingWeight(v.at.frame, v.at.ng, v.at.wi, out, TransportMode::kRadiance);
        if (!(sampled.pdf[j] > 0) || !(MaxComponent(w) > 0)) continue;
        p.beta *= w;
        p.r_l = p.r_u / sampled.pdf[j];
        p.specular = (sampled.flags[j] & kScatterDelta) != 0;
        const Vec3 direction = Normalize(v.at.frame.ToWorld(out));
        p.medium = scene.MediaOf(v.shape).Beyond(direction, v.at.ng, p.medium);
        Redirect(p.ray, v.at.position, v.at.ng, direction);
        Scattered(p, false);
        if (Survives(points, v.path, p)) next.push_back(v.path);
      }
    }
  }

  // One light chosen and sampled from each of the vertices `which` (of a
  // bounce's surface or medium vertices), with the coordinates of its
  // owner's current vertex.
  template <typename Vertex>
  static LightSamples SampleLightsAt(const SceneView& scene, const PrimarySamples& points,
                                     std::vector<VolPath>& paths, const std::vector<Vertex>& vertices,
                                     const std::vector<uint32_t>& which) {
    const size_t n = which.size();
    std::vector<Vec3> from(n);
    std::vector<float> u(3 * n);
    for (size_t j = 0; j < n; ++j) {
      const Vertex& v = vertices[which[j]];
      VolPath& p = paths[v.path];
      from[j] = PositionOf(v);
      u[3 * j] = Uniform(points, v.path, p, kLightChoice);
      u[3 * j + 1] = Uniform(points, v.path, p, kLightPosition);
      u[3 * j + 2] = Uniform(points, v.path, p, kLightPosition + 1);
    }
    std::vector<LightDirection> drawn(n);
    scene.SampleLightsFrom(from, u, drawn);
    return LightSamples::Of(scene, std::move(drawn), which, vertices.size());
  }
  static Vec3 PositionOf(const MediumVertex& v) { return v.position; }
  static Vec3 PositionOf(const SurfaceVertex& v) { return v.at.position; }

  // Emitting surfaces the rays reached, weighted against light sampling
  // from the path's last scattering vertex.
  void AddEmission(const SceneView& scene, std::vector<VolPath>& paths, const std::vector<uint32_t>& active,
                   const std::vector<Ray>& rays, const std::vector<Hit>& hits,
                   const std::vector<uint32_t>& emitted) const {
    const std::vector<Vec3> seen = EmissionSeen(scene, rays, hits, emitted);
    for (size_t j = 0; j < emitted.size(); ++j) {
      const uint32_t k = emitted[j];
      VolPath& p = paths[active[k]];
      const Vec3 le = seen[j];
      if (p.specular) {
        p.radiance += p.beta * le / ChannelMean(p.r_u);
        continue;
      }
      // The light's density as seen from the last scattering vertex.
      const Vec3 position = rays[k].origin + rays[k].direction * hits[k].t;
      Ray from{p.scatter_point, 0, rays[k].direction, kInfinity, rays[k].time};
      Hit seen = hits[k];
      seen.t = Length(position - p.scatter_point);
      const Vec3 r_l = p.r_l * scene.LightPdfFrom(from, seen);
      p.radiance += p.beta * le / ChannelMean(p.r_u + r_l);
    }
  }

  // The environment seen by the rays that left the scene.
  void AddEnvironment(const SceneView& scene, std::vector<VolPath>& paths, const std::vector<uint32_t>& active,
                      const std::vector<Ray>& rays, const std::vector<uint32_t>& escaped) const {
    std::vector<Vec3> directions(escaped.size()), le(escaped.size());
    std::vector<float> light_pdf(escaped.size());
    for (size_t j = 0; j < escaped.size(); ++j) directions[j] = rays[escaped[j]].direction;
    scene.Escaped(directions, le, light_pdf);
    for (size_t j = 0; j < escaped.size(); ++j) {
      VolPath& p = paths[active[escaped[j]]];
      const Vec3 r = p.specular ? p.r_u : p.r_u + p.r_l * light_pdf[j];
      p.radiance += p.beta * le[j] / ChannelMean(r);
    }
  }

  // Adds the light samples whose shadow rays get through, weighted.
  void AddLightSamples(const SceneView& scene, std::vector<VolPath>& paths, const std::vector<LightLink>& links) const {
    std::vector<ShadowWalk> shadows(links.size());
    for (size_t k = 0; k < links.size(); ++k) {
      const VolPath& p = paths[links[k].path];
      shadows[k] = {links[k].ray, links[k].medium, p.hero, Hash(p.random.seed, uint32_t(p.vertices), k)};
    }
    const std::vector<ShadowTransmittance> through = Transmittances(scene, shadows, null_boundaries_);
    for (size_t k = 0; k < links.size(); ++k) {
      const LightLink& link = links[k];
      const ShadowTransmittance& t = through[k];
      if (!(MaxComponent(t.value) > 0)) continue;
      const Vec3 r_l = link.r_path * t.r_l * link.light_pdf;
      const Vec3 r_u = link.r_path * t.r_u * link.scatter_pdf;
      const float mean = ChannelMean(link.delta ? r_l : r_l + r_u);
      if (mean > 0) paths[link.path].radiance += link.unweighted * t.value / mean;
    }
  }

  PathLength length_;
  int max_medium_depth_;
  bool null_boundaries_ = false;
};

}  // namespace
}  // namespace yarf

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::VolPathTracer>(registrar, "volpath",
                                      "1.0.0", "volumetric path tracer: null-scattering media, light sampling and MIS");
}
