// radiosity — progressive refinement radiosity (Cohen, Chen, Wallace &
// Greenberg 1988) with ray-cast form factors (Wallace et al. 1989).
//
// Prepare meshes every triangle of the scene by midpoint subdivision into
// elements (radiosity_mesh.h), groups them into coarser shooting patches,
// and solves for the radiosity of both sides of every element by shooting
// the largest unshot power until little is left (radiosity_solver.h).
// Evaluate then only looks the answer up: a camera ray's hit names its
// element from the hit's shape, triangle and barycentrics, and the
// radiance there is the reflected radiosity B/π, flat (the element's) or
// Gouraud shaded: linear over the element, sloped as radiosities also
// received at the elements' vertices (radiosity_shading.h), with the
// element's mean; plus what an emitter emits toward the camera. With
// final_gather the visible point gathers instead: direct light by one
// light sample, indirect light by one cosine-distributed ray whose hit's
// radiosity (less emission) it reflects.
//
// The solve ends before rendering starts, so the ambient term (the light
// still unshot, spread evenly) shows only when max_shots cut it short.
//
// Radiosity needs diffuse surfaces: a scene with a sphere (an environment
// light is one), a point light or a material with glossy, specular or
// transmitting lobes is refused. Reflectance is ρ = π f at normal
// incidence of each side; emission π L_e toward each side's normal.
//
// Primary sample space: 0–1 film, 2–3 lens, 4 time; with final_gather
// also 6–7 light position, 8–9 gather direction, 10 light choice, 11 lobe.
//
// Parameters: Radiosity::Parameters() below. Gouraud shading has the
// vertices receive too (~1.5× the rays). report prints one line
// "radiosity: elements N shooters N shots N rays N scaled_shots N" then
// "emitted", "absorbed", "escaped", "unshot" and "absorbed_by_solution",
// each three numbers (RGB power, W); emitted = absorbed + escaped + unshot.

#include <cinttypes>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "radiosity_mesh.h"
#include "radiosity_shading.h"
#include "radiosity_solver.h"
#include "yarf/support/wavefront.h"
#include "yarf/plugin.h"

namespace yarf {
namespace {

using radiosity::PatchMesh;
using radiosity::PatchPoint;
using radiosity::ProgressiveSolver;

constexpr uint32_t kLightPosition = kTransportDimension, kGatherDirection = kTransportDimension + 2,
                   kLightChoice = kTransportDimension + 4, kGatherLobe = kTransportDimension + 5;
constexpr size_t kMaxElements = size_t(1) << 20;

// Lobes radiosity can represent: diffuse reflection.
bool IsDiffuse(uint32_t lobes) { return (lobes & (kScatterDelta | kScatterGlossy | kScatterRefract)) == 0; }

// The subdivision level of a shooter's cells that gives `points` points.
int PointsLevel(int64_t points) {
  for (int level = 0; level <= 3; ++level)
    if (points == int64_t(1) << (2 * level)) return level;
  throw Error("property 'shooter_points' must be 1, 4, 16 or 64");
}

// The solved scene: its mesh, each element side's values, for display.
struct Solution {
  std::unique_ptr<PatchMesh> mesh;
  radiosity::VertexSet vertices;
  std::vector<Vec3> reflected;         // B − E per element side
  std::vector<Vec3> vertex_reflected;  // B − E per vertex side
  std::vector<Vec3> reflectance;       // ρ per element side
  Vec3 ambient;
};

class Radiosity final : public Transport {
 public:
  // Each sample lands in its own pixel: the film may be rendered in tiles.
  static std::vector<std::string> Capabilities() { return {kPixelLocalCapability}; }
  static ParameterSchema Parameters() {
    using P = Parameter;
    return {
        P::Float("max_patch_area").Min(0).Doc(
            "elements are cut until smaller, in scene units²; the scene's area / 1024 when absent"),
        P::Int("subdivision").Default(-1).Range(-1, 10).Doc("cut every triangle this many times instead; -1: by area"),
        P::Int("shooter_levels").Default(2).Range(0, 10).Doc("shooters are this many levels coarser"),
        P::Int("shooter_points").Default(4).Range(1, 64).Doc("form-factor sample points per shooter: 1, 4, 16 or 64"),
        P::Float("tolerance").Default(1e-3).Min(0).Doc(
            "stop when the unshot power is below this fraction of the emitted"),
        P::Int("max_shots").Default(100000).Range(0, 100'000'000).Doc("stop after this many shots"),
        P::Bool("ambient").Default(true).Doc("add Cohen et al.'s ambient term for the power still unshot"),
        P::String("shading").Default("gouraud").Choices({"gouraud", "flat"}).Doc("how elements are shown"),
        P::Bool("final_gather").Default(false).Doc("gather at visible points"),
        P::Bool("report").Default(false).Doc("print the solve's totals to the server's log"),
    };
  }

  explicit Radiosity(const Properties& props)
      : max_patch_area_(props.Float("max_patch_area", -1)),
        subdivision_(int(props.Int("subdivision", -1))),
        shooter_levels_(int(props.Int("shooter_levels", 2, 0, 10))),
        ambient_(props.Bool("ambient", true)),
        gouraud_(Shading(props.String("shading", "gouraud"))),
        final_gather_(props.Bool("final_gather", false)),
        report_(props.Bool("report", false)) {
    settings_.tolerance = props.Float("tolerance", 1e-3);
    const int64_t max_shots = props.Int("max_shots", 100000, 0, 100'000'000);
    settings_.sample_level = uint32_t(PointsLevel(props.Int("shooter_points", 4)));
    if (props.Has("max_patch_area") && !(max_patch_area_ > 0))
      throw Error("property 'max_patch_area' must be > 0");
    if (subdivision_ < -1 || subdivision_ > 10) throw Error("property 'subdivision' must be -1 or 0 to 10");
    if (!(settings_.tolerance >= 0)) throw Error("property 'tolerance' must be >= 0");
    settings_.max_shots = uint64_t(max_shots);
  }

  uint32_t Dimensions() const override { return final_gather_ ? kGatherLobe + 1 : kTransportDimension; }

  void Prepare(const SceneView& scene) override {
    RefuseMedia(scene, "radiosity");
    RefuseNonDiffuse(scene);
    double area = max_patch_area_;
    if (subdivision_ < 0 && !(area > 0)) area = SceneArea(scene) / 1024;
    auto mesh = std::make_unique<PatchMesh>(scene, area, subdivision_, shooter_levels_, kMaxElements);
    // Flat shading needs no vertices: an empty set receives nothing.
    if (gouraud_) solution_.vertices = radiosity::BuildVertices(*mesh);
    const std::vector<Vec3> emission = Emissions(scene, *mesh);
    ProgressiveSolver solver(*mesh, solution_.vertices, Reflectances(scene, *mesh), emission);
    solver.Solve(scene, settings_);

    solution_.reflectance = solver.reflectance();
    solution_.reflected.resize(solver.radiosity().size());
    for (size_t k = 0; k < solution_.reflected.size(); ++k)
      solution_.reflected[k] = solver.radiosity()[k] - emission[k];
    const std::vector<Vec3> vertex_emission = solution_.vertices.Mean(*mesh, emission);
    solution_.vertex_reflected.resize(vertex_emission.size());
    for (size_t k = 0; k < vertex_emission.size(); ++k)
      solution_.vertex_reflected[k] = solver.vertex_radiosity()[k] - vertex_emission[k];
    solution_.ambient = ambient_ ? solver.Ambient() : Vec3();
    if (report_) Report(*mesh, solver);
    solution_.mesh = std::move(mesh);
  }

  void Evaluate(const SceneView& scene, const PrimarySamples& points, FilmSamples& out) override {
    const size_t n = points.Count();
    std::vector<Ray> rays(n);
    std::vector<Hit> hits(n);
    for (uint32_t i = 0; i < n; ++i) rays[i] = CameraRayOf(scene, points, i);
    scene.Intersect(rays, hits);
    std::vector<Vec3> radiance(n);
    AddEmission(scene, rays, hits, radiance);
    if (final_gather_) {
      Gather(scene, points, rays, hits, radiance);
    } else {
      for (uint32_t i = 0; i < n; ++i)
        if (hits[i].Found()) radiance[i] += Reflected(rays[i], hits[i]);
    }
    for (uint32_t i = 0; i < n; ++i) AddCameraSample(scene, points, i, radiance[i], out);
  }

 private:
  static bool Shading(const std::string& name) {
    if (name == "gouraud") return true;
    if (name == "flat") return false;
    throw Error("property 'shading' must be \"gouraud\" or \"flat\", not \"" + name + "\"");
  }

  static void RefuseNonDiffuse(const SceneView& scene) {
    for (uint32_t shape = 0; shape < scene.ShapeCount(); ++shape) {
      const uint32_t material = scene.MaterialOf(shape);
      if (!IsDiffuse(scene.Material(material).Lobes()))
        throw Error("radiosity: material " + std::to_string(material) + " of shape " + std::to_string(shape) +
                    " is not diffuse (it has glossy, specular or transmitting lobes); radiosity needs "
                    "diffuse reflectors only");
    }
    for (uint32_t light = 0; light < scene.LightCount(); ++light)
      if (!IsAreaLight(scene, light))
        throw Error("radiosity: point, spot, directional and environment lights are not supported, only "
                    "emitting triangle surfaces");
  }

  // LightPoint answers no emitter for an environment, and for an area
  // light only from the point it is gathered into: two points tell.
  static bool IsAreaLight(const SceneView& scene, uint32_t light) {
    for (const Vec3 seen_from : {Vec3(0, 0, 0), Vec3(1, 1, 1)})
      if (const LightDirection l = scene.LightPoint(light, seen_from); l.emitter) return !l.delta;
    return false;
  }

  static double SceneArea(const SceneView& scene) {
    double area = 0;
    for (uint32_t shape = 0; shape < scene.ShapeCount(); ++shape)
      for (uint32_t primitive = 0; primitive < scene.PrimitiveCount(shape); ++primitive) {
        Vec3 c[3];
        if (scene.Triangle(shape, primitive, c)) area += 0.5 * Length(Cross(c[1] - c[0], c[2] - c[0]));
      }
    return area;
  }

  // ρ = π f(n, n) of each element side, at its centre: one call per material.
  static std::vector<Vec3> Reflectances(const SceneView& scene, const PatchMesh& mesh) {
    const std::vector<radiosity::Patch>& elements = mesh.elements();
    std::vector<SurfaceQuery> queries(2 * elements.size());
    for (size_t k = 0; k < queries.size(); ++k) {
      const radiosity::Patch& e = elements[k / 2];
      const Vec3 normal(0, 0, k % 2 ? -1.0f : 1.0f);
      queries[k] = {scene.MaterialOf(mesh.triangles()[e.triangle].shape), normal, normal, SurfaceSite::Uv(e.u, e.v)};
    }
    const std::vector<SurfaceAnswer> f = EvaluateSurfaces(scene, TransportMode::kRadiance, queries, Densities::kNone);
    std::vector<Vec3> rho(queries.size());
    for (size_t k = 0; k < rho.size(); ++k) {
      const Vec3 r = f[k].f * kPi;
      rho[k] = {std::clamp(r.x, 0.0f, 1.0f), std::clamp(r.y, 0.0f, 1.0f), std::clamp(r.z, 0.0f, 1.0f)};
    }
    return rho;
  }

  // π L_e toward each emitting element side's normal: one call per emitter.
  static std::vector<Vec3> Emissions(const SceneView& scene, const PatchMesh& mesh) {
    const std::vector<radiosity::Patch>& elements = mesh.elements();
    std::vector<EmitterQuery> queries(2 * elements.size());
    for (size_t k = 0; k < queries.size(); ++k) {
      const radiosity::Patch& e = elements[k / 2];
      queries[k] = {scene.EmitterOf(mesh.triangles()[e.triangle].shape), Vec3(0, 0, k % 2 ? -1.0f : 1.0f),
                    SurfaceSite::Uv(e.u, e.v)};
    }
    const std::vector<EmitterAnswer> le = EvaluateEmitters(scene, queries, Densities::kNone);
    std::vector<Vec3> exitance(queries.size());
    for (size_t k = 0; k < exitance.size(); ++k) exitance[k] = le[k].radiance * kPi;
    return exitance;
  }

  void Report(const PatchMesh& mesh, const ProgressiveSolver& solver) const {
    const radiosity::EnergyTotals& t = solver.totals();
    const radiosity::Power by_solution = solver.AbsorbedBySolution();
    auto rgb = [](const radiosity::Power& p) {
      char text[96];
      std::snprintf(text, sizeof text, "%.7g %.7g %.7g", p.rgb[0], p.rgb[1], p.rgb[2]);
      return std::string(text);
    };
    std::fprintf(stderr,
                 "radiosity: elements %zu shooters %zu shots %" PRIu64 " rays %" PRIu64 " scaled_shots %" PRIu64
                 " emitted %s absorbed %s escaped %s unshot %s absorbed_by_solution %s\n",
                 mesh.elements().size(), mesh.shooters().size(), t.shots, t.rays, t.scaled_shots,
                 rgb(t.emitted).c_str(), rgb(t.absorbed).c_str(), rgb(t.escaped).c_str(), rgb(t.unshot).c_str(),
                 rgb(by_solution).c_str());
    std::fflush(stderr);
  }

  // The element side a ray's hit lies on, and the hit's place in it.
  struct SidePoint {
    uint32_t side;  // 2e or 2e + 1
    PatchPoint point;
  };
  SidePoint Locate(const Ray& ray, const Hit& hit) const {
    const PatchPoint p = solution_.mesh->Locate(hit.shape, hit.primitive, hit.b1, hit.b2);
    const bool back = Dot(solution_.mesh->elements()[p.patch].normal, ray.direction) > 0;
    return {2 * p.patch + (back ? 1 : 0), p};
  }

  // Radiance reflected toward the ray at its hit: B/π less emission,
  // with the ambient term. Gouraud shading is linear over the element,
  // sloped as the radiosities received at its vertices and shifted so
  // that its mean is the element's own radiosity: vertices alone would
  // darken a whole element along a wall's corner where only its edge is
  // dark, and the element's mean is what its form factors estimate best.
  Vec3 Reflected(const Ray& ray, const Hit& hit) const {
    const SidePoint s = Locate(ray, hit);
    Vec3 b = solution_.reflected[s.side];
    if (gouraud_) {
      b = Vec3();
      Vec3 mean;
      for (uint32_t c = 0; c < 3; ++c) {
        const Vec3 corner = solution_.vertex_reflected[solution_.vertices.SideOf(s.side, c)];
        b += corner * s.point.weight[c];
        mean += corner / 3.0f;
      }
      b += solution_.reflected[s.side] - mean;
    }
    return (b + solution_.ambient * solution_.reflectance[s.side]) * kInvPi;
  }

  // Emitters seen by the rays, toward the rays.
  static void AddEmission(const SceneView& scene, const std::vector<Ray>& rays, const std::vector<Hit>& hits,
                          std::vector<Vec3>& radiance) {
    std::vector<EmitterQuery> queries;
    std::vector<uint32_t> owners;
    for (uint32_t i = 0; i < hits.size(); ++i) {
      if (!hits[i].Found()) continue;
      if (const Emitter* emitter = scene.EmitterOf(hits[i].shape)) {
        queries.push_back(EmitterQuery::Seen(emitter, rays[i], hits[i]));
        owners.push_back(i);
      }
    }
    const std::vector<EmitterAnswer> le = EvaluateEmitters(scene, queries, Densities::kNone);
    for (size_t q = 0; q < owners.size(); ++q) radiance[owners[q]] += le[q].radiance;
  }

  // Final gather at the visible points: direct light by one light
  // sample, indirect by one ray that reads the radiosity where it lands.
  void Gather(const SceneView& scene, const PrimarySamples& points, const std::vector<Ray>& rays,
              const std::vector<Hit>& hits, std::vector<Vec3>& radiance) const {
    std::vector<LightConnection> connections;
    std::vector<ScatterQuery> scatters;
    std::vector<uint32_t> owners;
    for (uint32_t i = 0; i < hits.size(); ++i) {
      if (!hits[i].Found()) continue;
      // Radiosity shades flat: its elements carry one normal each.
      const Frame frame(hits[i].normal);
      LightConnection c{scene.MaterialOf(hits[i].shape),
                        rays[i].origin + rays[i].direction * hits[i].t,
                        hits[i].normal,
                        frame,
                        frame.ToLocal(-rays[i].direction),
                        SurfaceSite::Uv(hits[i].u, hits[i].v),
                        rays[i].time,
                        LightDirection{}};
      ScatterQuery q{c.material, c.wi, c.site};
      q.uniform[0] = points.Get(i, kGatherLobe);
      q.uniform[1] = points.Get(i, kGatherDirection);
      q.uniform[2] = points.Get(i, kGatherDirection + 1);
      connections.push_back(c);
      scatters.push_back(q);
      owners.push_back(i);
    }
    std::vector<Vec3> from;
    for (const LightConnection& c : connections) from.push_back(c.position);
    const std::vector<LightDirection> lights =
        SampleLightsFrom(scene, points, from, owners, kLightChoice, kLightPosition);
    for (size_t k = 0; k < connections.size(); ++k) connections[k].light = lights[k];
    std::vector<LightConnection> lit;
    std::vector<uint32_t> lit_owners;
    for (size_t k = 0; k < connections.size(); ++k)
      if (connections[k].light.emitter) {
        lit.push_back(connections[k]);
        lit_owners.push_back(owners[k]);
      }
    const std::vector<Vec3> direct = DirectLight(scene, lit);
    for (size_t k = 0; k < lit.size(); ++k) radiance[lit_owners[k]] += direct[k];

    const std::vector<ScatterAnswer> answers =
        SampleSurfaces(scene, TransportMode::kRadiance, 0, scatters, Densities::kForward);
    std::vector<Ray> gather;
    std::vector<Vec3> weights;
    std::vector<uint32_t> gather_owners;
    for (size_t k = 0; k < answers.size(); ++k) {
      if (!(answers[k].pdf > 0) || !(MaxComponent(answers[k].weight) > 0)) continue;
      const LightConnection& c = connections[k];
      Ray ray = rays[owners[k]];
      Redirect(ray, c.position, c.ng, Normalize(c.frame.ToWorld(answers[k].wo)));
      gather.push_back(ray);
      weights.push_back(answers[k].weight);
      gather_owners.push_back(owners[k]);
    }
    std::vector<Hit> gathered(gather.size());
    scene.Intersect(gather, gathered);
    for (size_t k = 0; k < gather.size(); ++k)
      if (gathered[k].Found()) radiance[gather_owners[k]] += weights[k] * Reflected(gather[k], gathered[k]);
  }

  double max_patch_area_;
  int subdivision_;
  int shooter_levels_;
  bool ambient_;
  bool gouraud_;
  bool final_gather_;
  bool report_;
  radiosity::SolverSettings settings_;
  Solution solution_;
};

}  // namespace
}  // namespace yarf

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::Radiosity>(registrar, "radiosity", "1.0.0",
                                  "progressive refinement radiosity with ray-cast form factors");
}
