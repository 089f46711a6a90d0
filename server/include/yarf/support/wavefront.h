// What the wavefront transports share: grouping a batch by material or
// emitter so that each component is called once per group, batched
// SurfaceModel and Emitter calls (SurfaceBatch and EmitterBatch, the one
// way a transport fills their arrays; the query helpers build them too),
// light path starts, and the power heuristic of multiple importance
// sampling.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <numeric>
#include <span>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "yarf/error.h"
#include "yarf/parameters.h"
#include "yarf/properties.h"
#include "yarf/support/shading.h"
#include "yarf/transport.h"

namespace yarf {

// Where a ray met a surface, as scattering sees it: surface models get
// directions in the shading frame (ShadingFrame); leaving the surface and
// telling its sides apart go by the geometric normal ng.
// What a surface call knows of a point besides directions: one row of its
// SurfacePoints.
struct SurfaceSite {
  float u = 0, v = 0;
  // On a surface with a parameterisation of its own (Hit::parameterised):
  // then the footprint, position and frame below are known.
  bool parameterised = false;
  // Not parameterised, but its position is known, for the solid textures
  // that read it (SceneView::PositionsRead); footprint and frame zero.
  bool positioned = false;
  float footprint[4] = {0, 0, 0, 0};
  Vec3 position;
  Vec3 dpdu, dpdv;  // in the local shading frame
  SurfaceLocation location;

  // A point known by its uv alone (a point on a light).
  static SurfaceSite Uv(float u, float v) {
    SurfaceSite site;
    site.u = u, site.v = v;
    return site;
  }
  // Where a hit lies, without footprint or frame (an emitter seen there).
  static SurfaceSite Of(const Hit& hit) {
    SurfaceSite site = Uv(hit.u, hit.v);
    site.location = {hit.shape, hit.primitive, hit.b1, hit.b2};
    return site;
  }
};

// The SurfacePoints of a batch of at most `capacity` sites, owning its
// arrays (this runs for every surface call of every bounce): uv and
// locations always; footprints, positions and frames only once a site on
// a parameterised surface (or a positioned one) is added (zero for the
// others), else they are left empty, as unknown: what reads them
// (filtering, bump maps) needs a parameterisation, a solid texture a
// position (where none is known, a point on a light seen by its uv, it
// sees the origin).
class SurfaceRows {
 public:
  SurfaceRows(const SurfaceAttributes* attributes, size_t capacity)
      : attributes_(attributes), capacity_(capacity) {
    uv_.reserve(2 * capacity);
    location_.reserve(capacity);
  }
  void Add(const SurfaceSite& site) {
    const size_t k = location_.size();
    uv_.push_back(site.u);
    uv_.push_back(site.v);
    // Field by field: a site just made on the stack (SurfaceSite::Uv) has
    // its location stored in pieces, which a whole-struct copy would
    // reread as one wide load, a store-forwarding stall per row.
    SurfaceLocation& location = location_.emplace_back();
    location.shape = site.location.shape;
    location.primitive = site.location.primitive;
    location.b1 = site.location.b1;
    location.b2 = site.location.b2;
    if (!site.parameterised && !site.positioned) return;
    if (extras_.empty()) extras_.resize(kExtras * capacity_);
    std::copy_n(site.footprint, 4, &extras_[kFootprint * capacity_ + 4 * k]);
    site.position.Store(&extras_[kPosition * capacity_ + 3 * k]);
    site.dpdu.Store(&extras_[kDpdu * capacity_ + 3 * k]);
    site.dpdv.Store(&extras_[kDpdv * capacity_ + 3 * k]);
  }
  SurfacePoints Points() const {
    SurfacePoints points{uv_, {}, {}, {}, {}, location_, attributes_};
    if (extras_.empty()) return points;
    const size_t n = location_.size();
    const auto part = [&](size_t offset, size_t width) {
      return std::span<const float>(&extras_[offset * capacity_], width * n);
    };
    points.footprint = part(kFootprint, 4);
    points.position = part(kPosition, 3);
    points.dpdu = part(kDpdu, 3);
    points.dpdv = part(kDpdv, 3);
    return points;
  }

 private:
  // Where each array starts in extras_, in units of `capacity` floats.
  static constexpr size_t kFootprint = 0, kPosition = 4, kDpdu = 7, kDpdv = 10, kExtras = 13;
  const SurfaceAttributes* attributes_;
  size_t capacity_;
  std::vector<float> uv_, extras_;
  std::vector<SurfaceLocation> location_;
};

// The hit of `ray` as scattering sees it, with the texture footprint of a
// camera sample's spacing there (SceneView::SampleSpacing) on surfaces
// with a parameterisation of their own, when anything reads footprints.
// A constructor, so that a batch's entry can be made where it lives
// (emplace_back) rather than built elsewhere and copied in.
struct ShadingPoint {
  ShadingPoint(const SceneView& scene, const Hit& hit, const Ray& ray)
      : position(ray.origin + ray.direction * hit.t),
        ng(hit.normal),
        frame(ShadingFrame(hit)),
        wi(frame.ToLocal(-ray.direction)),
        site(SurfaceSite::Of(hit)) {
    if (!hit.parameterised) {
      if (!scene.PositionsRead()) return;
      site.positioned = true;
      site.position = position;
      return;
    }
    site.parameterised = true;
    site.position = position;
    site.dpdu = frame.ToLocal(hit.dpdu);
    site.dpdv = frame.ToLocal(hit.dpdv);
    if (scene.FootprintsRead()) {
      Vec3 dpdx, dpdy;
      scene.SampleSpacing(position, hit.normal, dpdx, dpdy);
      UvFootprint(hit.dpdu, hit.dpdv, dpdx, dpdy, site.footprint);
    }
  }

  Vec3 position;
  Vec3 ng;
  Frame frame;
  Vec3 wi;  // local: back along the ray
  SurfaceSite site;
};

// What a scattering from local wi to local wo at a surface point carries
// beyond f·|cos θo|: nothing where the geometric and the shading normal
// disagree on whether it reflects (no light through the surface); for
// importance, Veach's correction (ImportanceShadingFactor).
inline float ShadingWeight(const Frame& frame, Vec3 ng, Vec3 wi, Vec3 wo, TransportMode mode) {
  if (SameVector(frame.n, ng)) return 1;  // one normal: nothing to disagree or correct
  const Vec3 wi_world = frame.ToWorld(wi), wo_world = frame.ToWorld(wo);
  if (!SidesAgree(wi_world, wo_world, ng, wi.z, wo.z)) return 0;
  return mode == TransportMode::kImportance ? ImportanceShadingFactor(wi_world, wo_world, ng, frame.n) : 1.0f;
}

// Whether light samples can find anything at a surface with these lobes:
// all but purely specular ones (a model without kind flags counts as not
// specular).
inline bool SamplesLights(uint32_t lobes) {
  return (lobes & (kScatterDiffuse | kScatterGlossy)) || !(lobes & kScatterDelta);
}

// The length properties of methods that end paths by Russian roulette:
// max_depth in segments (Mitsuba's convention, -1 unbounded) and the depth
// from which roulette may end a path.
struct PathLength {
  // Both are ints: a larger value would wrap.
  static constexpr int64_t kLongest = std::numeric_limits<int32_t>::max();
  explicit PathLength(const Properties& props)
      : max_depth(int(props.Int("max_depth", -1, -1, kLongest))),
        rr_depth(int(props.Int("rr_depth", 5, 1, kLongest))) {}
  // The declarations of the two, for the schemas of the methods that read them.
  static std::vector<Parameter> Parameters() {
    return {
        Parameter::Int("max_depth").Default(-1).Range(-1, double(kLongest)).Doc(
            "longest path in segments (Mitsuba's: 1 emitters only, 2 direct light); -1 unbounded"),
        Parameter::Int("rr_depth")
            .Default(5)
            .Range(1, double(kLongest))
            .Doc("depth from which Russian roulette may end paths"),
    };
  }
  // Bounces to reserve primary-sample dimensions for: 64 when unbounded.
  uint32_t Bounces() const { return uint32_t(max_depth < 0 ? 64 : max_depth); }

  int max_depth;
  int rr_depth;
};

// The camera ray of point i: its film, lens and time coordinates.
inline Ray CameraRayOf(const SceneView& scene, const PrimarySamples& points, size_t i) {
  // Coordinates the camera ignores are not drawn: each pair costs the
  // sampler, and a pinhole with a closed shutter reads only the film's.
  const bool lens = scene.CameraReadsLens(), time = scene.CameraReadsTime();
  return scene.CameraRay(points.Get(i, kFilmDimension), points.Get(i, kFilmDimension + 1),
                         lens ? points.Get(i, kLensDimension) : 0.5f, lens ? points.Get(i, kLensDimension + 1) : 0.5f,
                         scene.ShutterTime(time ? points.Get(i, kTimeDimension) : 0.0f));
}

// Adds a camera sample of `radiance` where point i lies on the film.
inline void AddCameraSample(const SceneView& scene, const PrimarySamples& points, uint32_t i, Vec3 radiance,
                            FilmSamples& out) {
  out.Add(i, points.Get(i, kFilmDimension) * float(scene.FilmWidth()),
          points.Get(i, kFilmDimension + 1) * float(scene.FilmHeight()), radiance);
}

// The ray that carries a path on from surface point p (geometric normal n)
// toward `direction`: moved off the surface, at the same instant.
inline void Redirect(Ray& ray, Vec3 p, Vec3 n, Vec3 direction) {
  ray.origin = OffsetRayOrigin(p, n, direction);
  ray.direction = direction;
  ray.tnear = 0;
  ray.tfar = kInfinity;
}

// Russian roulette: the path goes on with probability min(max throughput
// / start, 0.95), its throughput scaled up to stay unbiased. `start` is the
// largest channel of the throughput where the walk began (a light
// subpath's starts at the light's emitted power, not at 1).
inline bool Survives(Vec3& throughput, float u, float start = 1) {
  const float survive = std::min(MaxComponent(throughput) / start, 0.95f);
  if (u >= survive) return false;
  throughput *= 1.0f / survive;
  return true;
}

// Veach's power heuristic with β = 2 for two strategies.
inline float PowerHeuristic(float a, float b) {
  a *= a;
  b *= b;
  return a + b > 0 ? a / (a + b) : 0;
}

// Indices 0..keys.size()-1 grouped by key, groups in order of first
// appearance. Linear while groups are few, as a batch's materials are.
template <typename Key>
std::vector<std::pair<Key, std::vector<uint32_t>>> GroupBy(const std::vector<Key>& keys) {
  std::vector<std::pair<Key, std::vector<uint32_t>>> groups;
  // One key for all, as a scene with one light or a batch of one material
  // often has: a scan that vectorises, not a search per index.
  if (!keys.empty() && std::all_of(keys.begin(), keys.end(), [&](const Key& key) { return key == keys[0]; })) {
    std::vector<uint32_t> all(keys.size());
    std::iota(all.begin(), all.end(), 0u);
    groups.emplace_back(keys[0], std::move(all));
    return groups;
  }
  std::unordered_map<Key, size_t> index;  // used once groups are many
  constexpr size_t kLinearSearch = 16;
  for (uint32_t i = 0; i < keys.size(); ++i) {
    size_t g = groups.size();
    if (groups.size() <= kLinearSearch) {
      for (size_t j = 0; j < groups.size(); ++j)
        if (groups[j].first == keys[i]) g = j;
    } else if (auto it = index.find(keys[i]); it != index.end()) {
      g = it->second;
    }
    if (g == groups.size()) {
      groups.push_back({keys[i], {}});
      if (groups.size() > kLinearSearch)
        for (size_t j = index.size(); j < groups.size(); ++j) index[groups[j].first] = j;
    }
    groups[g].second.push_back(i);
  }
  return groups;
}


// The densities a batch of surface or emitter queries asks for besides
// its values: each costs a call per material (or emitter), and only
// bidirectional weights need the reverse one (wi given wo).
enum class Densities { kNone, kForward, kBoth };

// The rows of a batched component call: a direction in the local frame
// (3 floats) and a SurfacePoints row each.
class DirectedRows {
 public:
  DirectedRows(const SurfaceAttributes* attributes, size_t capacity) : rows_(attributes, capacity) {
    directions_.reserve(3 * capacity);
  }
  void Add(Vec3 direction, const SurfaceSite& site) {
    directions_.push_back(direction.x);
    directions_.push_back(direction.y);
    directions_.push_back(direction.z);
    rows_.Add(site);
  }
  size_t Size() const { return directions_.size() / 3; }

 protected:
  std::vector<float> directions_;
  SurfaceRows rows_;
};

// One material's batch of vertices, as its SurfaceModel calls take them:
// wi (toward where the path came from) and the SurfacePoints row of each,
// added once and shared by the calls made on it (light samples evaluated,
// then the BSDF sampled). Answers come in arrays of their own.
class SurfaceBatch : public DirectedRows {
 public:
  using DirectedRows::DirectedRows;

  // f toward wo (3 per row, local) and the densities asked for: of wo
  // given wi, and of wi given wo.
  struct Evaluation {
    std::vector<float> f, pdf, pdf_reverse;
    Vec3 F(size_t j) const { return Vec3::Load(&f[3 * j]); }
  };
  Evaluation Evaluate(const SurfaceModel& model, TransportMode mode, std::span<const float> wo,
                      Densities densities) const {
    const size_t n = Size();
    Evaluation out{std::vector<float>(3 * n), std::vector<float>(n), std::vector<float>(n)};
    const SurfacePoints at = rows_.Points();
    const std::span<const float> wi = directions_;
    model.Evaluate(mode, wi, wo, at, out.f);
    if (densities != Densities::kNone) model.Pdf(wi, wo, at, out.pdf);
    if (densities == Densities::kBoth) model.Pdf(wo, wi, at, out.pdf_reverse);
    return out;
  }

  // A direction per row from `uniform` (3 per row: the lobe choice, then
  // the direction's two numbers), restricted to the `allowed` lobes (0:
  // all), with its weight f·|cos|/pdf, densities and lobe flags.
  struct Samples {
    std::vector<float> wo, weight, pdf, pdf_reverse;
    std::vector<uint32_t> flags;
    Vec3 Wo(size_t j) const { return Vec3::Load(&wo[3 * j]); }
    Vec3 Weight(size_t j) const { return Vec3::Load(&weight[3 * j]); }
  };
  Samples Sample(const SurfaceModel& model, TransportMode mode, uint32_t allowed, std::span<const float> uniform,
                 Densities densities) const {
    const size_t n = Size();
    Samples out{std::vector<float>(3 * n), std::vector<float>(3 * n), std::vector<float>(n),
                std::vector<float>(n), std::vector<uint32_t>(n)};
    const SurfacePoints at = rows_.Points();
    const std::span<const float> wi = directions_;
    model.Sample(mode, wi, at, uniform, allowed, out.wo, out.weight, out.pdf, out.flags);
    if (densities == Densities::kBoth) model.Pdf(out.wo, wi, at, out.pdf_reverse);
    return out;
  }
};

// A SurfaceModel query at a vertex, directions in its local frame: wi
// toward where the path came from, wo toward where it goes.
struct SurfaceQuery {
  uint32_t material;
  Vec3 wi, wo;
  SurfaceSite site;
};
struct SurfaceAnswer {
  Vec3 f;
  // Densities of sampling wo given wi, and wi given wo (solid angle).
  float pdf = 0, pdf_reverse = 0;
};

// f and the densities asked for of every query: one call each per
// material.
inline std::vector<SurfaceAnswer> EvaluateSurfaces(const SceneView& scene, TransportMode mode,
                                                   const std::vector<SurfaceQuery>& queries,
                                                   Densities densities = Densities::kBoth) {
  std::vector<SurfaceAnswer> answers(queries.size());
  std::vector<uint32_t> keys(queries.size());
  for (size_t k = 0; k < queries.size(); ++k) keys[k] = queries[k].material;
  for (const auto& [material, members] : GroupBy(keys)) {
    const size_t m = members.size();
    std::vector<float> wo(3 * m);
    SurfaceBatch batch(&scene, m);
    for (size_t j = 0; j < m; ++j) {
      const SurfaceQuery& q = queries[members[j]];
      batch.Add(q.wi, q.site);
      q.wo.Store(&wo[3 * j]);
    }
    const SurfaceBatch::Evaluation e = batch.Evaluate(scene.Material(material), mode, wo, densities);
    for (size_t j = 0; j < m; ++j) answers[members[j]] = {e.F(j), e.pdf[j], e.pdf_reverse[j]};
  }
  return answers;
}

// A SurfaceModel sample at a vertex: wi toward where the path came from.
struct ScatterQuery {
  uint32_t material;
  Vec3 wi;
  SurfaceSite site;
  // Lobe choice, then the direction's two numbers.
  float uniform[3] = {0, 0, 0};
};
struct ScatterAnswer {
  Vec3 wo, weight;
  float pdf = 0, pdf_reverse = 0;
  uint32_t flags = kScatterNone;
};

// Samples every query, with the reverse density (wi given wo) when asked
// for both: one call each per material.
inline std::vector<ScatterAnswer> SampleSurfaces(const SceneView& scene, TransportMode mode, uint32_t allowed,
                                                 const std::vector<ScatterQuery>& queries,
                                                 Densities densities = Densities::kBoth) {
  std::vector<ScatterAnswer> answers(queries.size());
  std::vector<uint32_t> keys(queries.size());
  for (size_t k = 0; k < queries.size(); ++k) keys[k] = queries[k].material;
  for (const auto& [material, members] : GroupBy(keys)) {
    const size_t m = members.size();
    std::vector<float> u(3 * m);
    SurfaceBatch batch(&scene, m);
    for (size_t j = 0; j < m; ++j) {
      const ScatterQuery& q = queries[members[j]];
      batch.Add(q.wi, q.site);
      std::copy_n(q.uniform, 3, &u[3 * j]);
    }
    const SurfaceBatch::Samples s = batch.Sample(scene.Material(material), mode, allowed, u, densities);
    for (size_t j = 0; j < m; ++j)
      answers[members[j]] = {s.Wo(j), s.Weight(j), s.pdf[j], s.pdf_reverse[j], s.flags[j]};
  }
  return answers;
}

// One emitter's batch: directions leaving it and the SurfacePoints rows
// of the points they leave from.
class EmitterBatch : public DirectedRows {
 public:
  using DirectedRows::DirectedRows;
  // Radiance along each direction (3 per row), and unless kNone the
  // density of SampleDirection for it.
  void Radiance(const Emitter& emitter, Densities densities, std::vector<float>& radiance,
                std::vector<float>& pdf) const {
    radiance.assign(directions_.size(), 0.0f);
    pdf.assign(Size(), 0.0f);
    emitter.Radiance(directions_, rows_.Points(), radiance);
    if (densities != Densities::kNone) emitter.PdfDirection(directions_, pdf);
  }
};

// An Emitter query: w in the emitter's local frame, leaving it.
struct EmitterQuery {
  const Emitter* emitter;
  Vec3 w;
  SurfaceSite site;

  // The emitter a ray hit, seen back along the ray.
  static EmitterQuery Seen(const Emitter* emitter, const Ray& ray, const Hit& hit) {
    return {emitter, Frame(hit.normal).ToLocal(-ray.direction), SurfaceSite::Of(hit)};
  }
};
struct EmitterAnswer {
  Vec3 radiance;
  // SampleDirection's density for w.
  float pdf_direction = 0;
};

// Row k of a batch goes to emitters[k] (none: skipped): each emitter is
// called once, with the rows add(batch, k) puts in its batch for each of
// its k; take(k, radiance, pdf_direction) gets each row's answer.
template <typename AddRow, typename TakeAnswer>
void CallEmitters(const SceneView& scene, const std::vector<const Emitter*>& emitters, Densities densities,
                  AddRow&& add, TakeAnswer&& take) {
  // The rows with an emitter, grouped apart from the rest: light samples
  // that found none (a lamp seen edge-on) would otherwise break up a
  // scene's one light into two groups.
  std::vector<uint32_t> rows;
  std::vector<const Emitter*> keys;
  rows.reserve(emitters.size());
  keys.reserve(emitters.size());
  for (uint32_t k = 0; k < emitters.size(); ++k)
    if (emitters[k]) {
      rows.push_back(k);
      keys.push_back(emitters[k]);
    }
  std::vector<float> radiance, pdf;
  for (const auto& [emitter, members] : GroupBy(keys)) {
    EmitterBatch batch(&scene, members.size());
    for (const uint32_t member : members) add(batch, rows[member]);
    batch.Radiance(*emitter, densities, radiance, pdf);
    for (size_t j = 0; j < members.size(); ++j) take(rows[members[j]], Vec3::Load(&radiance[3 * j]), pdf[j]);
  }
}

// Radiance (and, unless kNone, the direction density) of every query:
// one call each per emitter.
inline std::vector<EmitterAnswer> EvaluateEmitters(const SceneView& scene, const std::vector<EmitterQuery>& queries,
                                                   Densities densities = Densities::kForward) {
  std::vector<EmitterAnswer> answers(queries.size());
  std::vector<const Emitter*> emitters(queries.size());
  for (size_t k = 0; k < queries.size(); ++k) emitters[k] = queries[k].emitter;
  CallEmitters(
      scene, emitters, densities, [&](EmitterBatch& batch, uint32_t k) { batch.Add(queries[k].w, queries[k].site); },
      [&](uint32_t k, Vec3 radiance, float pdf) { answers[k] = {radiance, pdf}; });
  return answers;
}

// The radiance of the emitters rays[k] hit, seen back along them, for
// each k of `which`: one call per emitter.
inline std::vector<Vec3> EmissionSeen(const SceneView& scene, const std::vector<Ray>& rays,
                                      const std::vector<Hit>& hits, const std::vector<uint32_t>& which) {
  std::vector<EmitterQuery> queries(which.size());
  for (size_t j = 0; j < which.size(); ++j) {
    const uint32_t k = which[j];
    queries[j] = EmitterQuery::Seen(scene.EmitterOf(hits[k].shape), rays[k], hits[k]);
  }
  const std::vector<EmitterAnswer> answers = EvaluateEmitters(scene, queries, Densities::kNone);
  std::vector<Vec3> out(which.size());
  for (size_t j = 0; j < which.size(); ++j) out[j] = answers[j].radiance;
  return out;
}

// The radiance each sampled light sends toward the point it was sampled
// from (zero for a sample without an emitter): one call per emitter.
inline void LightRadiance(const SceneView& scene, const std::vector<LightDirection>& lights,
                          std::vector<Vec3>& out) {
  out.assign(lights.size(), Vec3(0, 0, 0));
  std::vector<const Emitter*> emitters(lights.size());
  for (size_t k = 0; k < lights.size(); ++k) emitters[k] = lights[k].emitter;
  CallEmitters(
      scene, emitters, Densities::kNone,
      [&](EmitterBatch& batch, uint32_t k) { batch.Add(lights[k].w, SurfaceSite::Uv(lights[k].u, lights[k].v)); },
      [&](uint32_t k, Vec3 radiance, float) { out[k] = radiance; });
}

// Next-event estimation's light samples for the vertices of a bounce that
// take one, made together whatever their materials or media: vertex v's
// sample and the radiance its light sends back are at slot[v] (only for
// the vertices that took one).
struct LightSamples {
  std::vector<uint32_t> slot;
  std::vector<LightDirection> direction;
  std::vector<Vec3> radiance;

  // Of `count` vertices, which[j] took sample drawn[j]: its radiance is
  // asked of each emitter in one call.
  static LightSamples Of(const SceneView& scene, std::vector<LightDirection> drawn,
                         const std::vector<uint32_t>& which, size_t count) {
    LightSamples samples;
    samples.direction = std::move(drawn);
    samples.Weigh(scene, which, count);
    return samples;
  }
  // The same for samples drawn into `direction` in place: a workspace's
  // LightSamples keeps its buffers from bounce to bounce.
  void Weigh(const SceneView& scene, const std::vector<uint32_t>& which, size_t count) {
    slot.assign(count, 0);
    for (uint32_t j = 0; j < which.size(); ++j) slot[which[j]] = j;
    LightRadiance(scene, direction, radiance);
  }
  const LightDirection& Direction(uint32_t v) const { return direction[slot[v]]; }
  Vec3 Radiance(uint32_t v) const { return radiance[slot[v]]; }
};

// Whether a surface vertex of this model takes a light sample: the scene
// has lights, and the model's lobes can use one.
inline bool TakesLightSamples(const SceneView& scene, const SurfaceModel& model) {
  return scene.HasLights() && SamplesLights(model.Lobes());
}

// The vertices of a bounce, grouped by material (GroupBy), that take a
// light sample (TakesLightSamples).
inline std::vector<uint32_t> LitVertices(const SceneView& scene,
                                         const std::vector<std::pair<uint32_t, std::vector<uint32_t>>>& groups) {
  std::vector<uint32_t> lit;
  for (const auto& [material, members] : groups)
    if (TakesLightSamples(scene, scene.Material(material))) lit.insert(lit.end(), members.begin(), members.end());
  return lit;
}

// Methods that connect light paths to the camera (light tracing, bdpt)
// cannot render a camera light paths cannot reach (orthographic, meters).
inline void RefuseUnreachableCamera(const SceneView& scene, const std::string& transport) {
  if (const std::string_view reason = scene.CameraUnreachableReason(); !reason.empty())
    throw Error(transport + ": " + std::string(reason) +
                ": render it with path, whitted, distribution, photon_map or sppm");
}

// Methods that know nothing of participating media refuse scenes that
// have them, rather than render them as vacuum (path alone ignores them,
// as Mitsuba's and pbrt-v4's path tracers do).
inline void RefuseMedia(const SceneView& scene, const std::string& transport) {
  if (scene.MediumCount() > 0)
    throw Error(transport + " does not render participating media: render this scene with volpath, light or bdpt");
}

// Where light paths start: a point on a light and a direction leaving it.
struct LightStart {
  LightSample light;
  // Direction of emission, world space, and its density (solid angle).
  Vec3 direction;
  float pdf_direction = 0;
  // Radiance (a point light: intensity) along it.
  Vec3 radiance;
  bool Valid() const { return light.emitter && pdf_direction > 0 && light.pdf > 0; }
  // Throughput of the first segment: L·|cos|/(p_position·p_direction).
  Vec3 Throughput() const {
    const float cos = light.delta_position ? 1.0f : std::abs(Dot(light.normal, direction));
    return radiance * (cos / (light.pdf * pdf_direction));
  }
  // The first ray, leaving the light's surface (a light at infinity: its
  // disk, which no surface lies on).
  Ray FirstRay(float time) const {
    Ray ray;
    ray.origin = light.delta_position || light.infinite ? light.position
                                                         : OffsetRayOrigin(light.position, light.normal, direction);
    ray.direction = direction;
    ray.time = time;
    return ray;
  }
};

// One light path start per point, from the given coordinates: light choice
// `choice`, position (position, position + 1), direction (direction,
// direction + 1). One SampleDirection and Radiance call per emitter. A
// light at infinity chooses its direction first, then its point on the
// disk facing it (the position coordinates); a directional light has
// one direction, its frame's +z.
inline std::vector<LightStart> StartLightPaths(const SceneView& scene, const PrimarySamples& points,
                                               uint32_t choice, uint32_t position, uint32_t direction) {
  const size_t n = points.Count();
  std::vector<LightStart> starts(n);
  std::vector<const Emitter*> keys(n);
  for (uint32_t i = 0; i < n; ++i) {
    starts[i].light = scene.SampleLight(points.Get(i, choice), points.Get(i, position), points.Get(i, position + 1));
    keys[i] = starts[i].light.emitter;
  }
  for (const auto& [emitter, members] : GroupBy(keys)) {
    if (!emitter) continue;
    const size_t m = members.size();
    std::vector<float> u(2 * m), w(3 * m), pdf(m), radiance(3 * m);
    SurfaceRows rows(&scene, m);
    for (size_t j = 0; j < m; ++j) {
      u[2 * j] = points.Get(members[j], direction);
      u[2 * j + 1] = points.Get(members[j], direction + 1);
      rows.Add(SurfaceSite::Uv(starts[members[j]].light.u, starts[members[j]].light.v));
    }
    if (starts[members[0]].light.delta_direction) {
      for (size_t j = 0; j < m; ++j) w[3 * j + 2] = 1, pdf[j] = 1;
    } else {
      emitter->SampleDirection(u, w, pdf);
    }
    emitter->Radiance(w, rows.Points(), radiance);
    for (size_t j = 0; j < m; ++j) {
      LightStart& s = starts[members[j]];
      const Vec3 local = Vec3::Load(&w[3 * j]);
      s.pdf_direction = pdf[j];
      s.radiance = Vec3::Load(&radiance[3 * j]);
      if (!s.light.infinite) {
        s.direction = Normalize(Frame(s.light.normal).ToWorld(local));
        continue;
      }
      s.direction = Normalize(s.light.frame.ToWorld(local));
      float pdf_area = 0;
      s.light.position = scene.InfiniteLightOrigin(s.direction, points.Get(members[j], position),
                                                   points.Get(members[j], position + 1), pdf_area);
      s.light.normal = s.direction;
      s.light.pdf *= pdf_area;
    }
  }
  return starts;
}

// The shadow ray from a scene point (normal n; zero for a point light) to
// a point of the lens.
inline Ray RayToLens(Vec3 p, Vec3 n, Vec3 lens_point, float time) {
  Ray ray;
  if (Length(n) > 0) {
    ray = ShadowRay(p, n, lens_point);
  } else {
    const Vec3 d = lens_point - p;
    ray.origin = p;
    ray.tfar = Length(d);
    ray.direction = ray.tfar > 0 ? d / ray.tfar : Vec3(0, 0, 1);
  }
  ray.time = time;
  return ray;
}

}  // namespace yarf

namespace yarf {

// The shadow ray from surface point p (geometric normal ng) toward a
// light seen from it: unbounded toward a light at infinity, up to a point
// light itself, short of a surface light's surface.
inline Ray ShadowRayToLight(Vec3 p, Vec3 ng, const LightDirection& light, float time) {
  if (light.AtInfinity()) return {OffsetRayOrigin(p, ng, light.direction), 0, light.direction, kInfinity, time};
  // A point light has no surface to stop short of.
  return ShadowRay(p, ng, light.position, light.delta ? 0.0f : SurfaceOffset(light.position), time);
}

// A surface point joined to a light seen from it (next-event estimation
// without MIS): directions in the vertex's local frame.
struct LightConnection {
  uint32_t material;
  Vec3 position;
  Vec3 ng;  // geometric normal
  Frame frame;  // shading frame
  Vec3 wi;
  SurfaceSite site;
  float time = 0;
  LightDirection light;
};

// f·L·|cos|/pdf of each connection, its shadow ray not traced (a method
// that crosses media tracks it itself): one call per material and per
// emitter.
inline std::vector<Vec3> UnshadowedDirectLight(const SceneView& scene,
                                               const std::vector<LightConnection>& connections) {
  const size_t n = connections.size();
  std::vector<SurfaceQuery> surfaces(n);
  std::vector<EmitterQuery> lights(n);
  for (size_t k = 0; k < n; ++k) {
    const LightConnection& c = connections[k];
    surfaces[k] = {c.material, c.wi, c.frame.ToLocal(c.light.direction), c.site};
    lights[k] = {c.light.emitter, c.light.w, SurfaceSite::Uv(c.light.u, c.light.v)};
  }
  const std::vector<SurfaceAnswer> f = EvaluateSurfaces(scene, TransportMode::kRadiance, surfaces, Densities::kNone);
  const std::vector<EmitterAnswer> le = EvaluateEmitters(scene, lights, Densities::kNone);
  std::vector<Vec3> out(n);
  for (size_t k = 0; k < n; ++k) {
    const LightConnection& c = connections[k];
    if (!c.light.emitter || !(c.light.pdf > 0)) continue;
    const float shading = ShadingWeight(c.frame, c.ng, c.wi, surfaces[k].wo, TransportMode::kRadiance);
    out[k] = f[k].f * le[k].radiance * (std::abs(surfaces[k].wo.z) * shading / c.light.pdf);
  }
  return out;
}

// The same, zero where the shadow ray is blocked: one ray batch, of the
// connections that would contribute.
inline std::vector<Vec3> DirectLight(const SceneView& scene, const std::vector<LightConnection>& connections) {
  std::vector<Vec3> out = UnshadowedDirectLight(scene, connections);
  std::vector<Ray> shadow;
  std::vector<uint32_t> shadowed;
  for (size_t k = 0; k < out.size(); ++k) {
    if (!(MaxComponent(out[k]) > 0)) continue;
    const LightConnection& c = connections[k];
    shadow.push_back(ShadowRayToLight(c.position, c.ng, c.light, c.time));
    shadowed.push_back(uint32_t(k));
  }
  std::vector<uint8_t> occluded(shadow.size());
  scene.Occluded(shadow, occluded);
  for (size_t q = 0; q < shadow.size(); ++q)
    if (occluded[q]) out[shadowed[q]] = Vec3();
  return out;
}

// The environment's radiance arriving back along rays that left the
// scene in `directions` (zero without an environment): one call.
inline std::vector<Vec3> EnvironmentAlong(const SceneView& scene, const std::vector<Vec3>& directions) {
  std::vector<Vec3> radiance(directions.size());
  if (!scene.HasEnvironment() || directions.empty()) return radiance;
  std::vector<float> pdf(directions.size());
  scene.Escaped(directions, radiance, pdf);
  return radiance;
}

// The lights seen from each point, for next-event estimation: light
// choice from coordinate `choice`, the direction from (direction,
// direction + 1) of point owners[k].
inline void SampleLightsFrom(const SceneView& scene, const PrimarySamples& points, const std::vector<Vec3>& from,
                             const std::vector<uint32_t>& owners, uint32_t choice, uint32_t direction,
                             std::vector<LightDirection>& out) {
  const size_t n = from.size();
  std::vector<float> coordinates(3 * n), u(3 * n);
  points.Gather(owners, choice, std::span(coordinates).first(n));
  points.Gather(owners, direction, std::span(coordinates).subspan(n, n));
  points.Gather(owners, direction + 1, std::span(coordinates).subspan(2 * n, n));
  for (size_t k = 0; k < n; ++k)
    for (size_t j = 0; j < 3; ++j) u[3 * k + j] = coordinates[j * n + k];
  out.resize(n);  // every element written by the scene: a reused vector is not cleared twice
  scene.SampleLightsFrom(from, u, out);
}
inline std::vector<LightDirection> SampleLightsFrom(const SceneView& scene, const PrimarySamples& points,
                                                    const std::vector<Vec3>& from,
                                                    const std::vector<uint32_t>& owners, uint32_t choice,
                                                    uint32_t direction) {
  std::vector<LightDirection> out;
  SampleLightsFrom(scene, points, from, owners, choice, direction, out);
  return out;
}

}  // namespace yarf
