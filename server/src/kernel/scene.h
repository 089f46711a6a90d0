// The kernel's scene: Embree geometry, materials, emitters and the camera
// of one job, seen by transport algorithms through SceneView.
#pragma once

#include <embree3/rtcore.h>

#include <array>
#include <atomic>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "kernel/aggregate_geometry.h"
#include "kernel/alpha_cut.h"
#include "kernel/camera.h"
#include "kernel/curves.h"
#include "kernel/embree_device.h"
#include "kernel/light_bvh.h"
#include "kernel/mesh_io.h"
#include "kernel/shape_surfaces.h"
#include "yarf/texture.h"
#include "yarf/transport.h"

namespace yarf {

// What a shape is made of, besides its geometry.
struct ShapeLook {
  std::string name;
  uint32_t material = 0;
  const Emitter* emitter = nullptr;
  bool flip_normals = false;
  // Meshes: the normal of a triangle's winding is reversed before its
  // vertex normals (if any) and flip_normals have their say.
  bool flip_winding = false;
  // Meshes: the probability that a ray meets the surface at a uv (a
  // cut-out); null for an opaque one.
  std::shared_ptr<const Texture> alpha;
  // The media the surface bounds, if it is a boundary.
  MediumInterface media;
};

class KernelScene final : public SceneView {
 public:
  static constexpr uint32_t kWorld = 0;

  KernelScene(const EmbreeDevice& device, const Camera& camera, uint32_t width, uint32_t height);
  ~KernelScene() override;
  KernelScene(const KernelScene&) = delete;
  KernelScene& operator=(const KernelScene&) = delete;

  // Building: materials and emitters first, then shapes in groups (group
  // kWorld is the world itself), then placements of groups, then Commit.
  uint32_t AddMaterial(std::shared_ptr<const SurfaceModel> material);
  const Emitter* AddEmitter(std::unique_ptr<Emitter> emitter);
  // Every emitter added, in order: the lights' and the emitting shapes'.
  std::vector<const Emitter*> Emitters() const;
  // A participating medium; returns its number.
  uint32_t AddMedium(std::unique_ptr<Medium> medium);
  void SetCameraMedium(uint32_t medium) { camera_medium_ = medium; }
  uint32_t NewGroup();
  // The group's opaque triangle meshes go into `aggregate` rather than
  // Embree's BVH; set before the group's first shape.
  void SetAggregate(uint32_t group, std::shared_ptr<Aggregate> aggregate);
  // Geometry in the group's own space; returns the shape's number in its
  // group, which for kWorld is its shape id once committed.
  uint32_t AddMesh(uint32_t group, TriangleMesh mesh, const ShapeLook& look);
  // `axes`: the sphere's own x, y, z axes (unit), which its uv follows.
  uint32_t AddSphere(uint32_t group, Vec3 center, float radius, const ShapeLook& look,
                     const std::array<Vec3, 3>& axes = {Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)});
  // Curves neither emit, measure nor take cut-outs: they have no surface
  // to sample (the scene's validation refuses such shapes first).
  uint32_t AddCurves(uint32_t group, CurveGeometry curves, const ShapeLook& look);
  // The shape an irradiance meter camera measures: a number AddMesh or
  // AddSphere returned for group kWorld. Required for that camera.
  void SetMeterShape(uint32_t world_shape) { meter_shape_ = world_shape; }
  // Places a group (not kWorld) in the world; nested placements arrive
  // here already flattened, with composed transforms. With `to_world_end`
  // the placement moves from to_world to it over the shutter interval.
  void AddPlacement(uint32_t group, const Transform& to_world,
                    const std::optional<Transform>& to_world_end = std::nullopt);
  // A light without a surface (point, spot), placed by to_world.
  void AddLight(const Emitter* emitter, const Transform& to_world);
  // A light at infinity whose local frame is to_world's rotation: a
  // directional light travels along its +z and its Radiance is
  // irradiance; an environment (at most one) sends its Radiance from
  // every direction it answers for.
  void AddDirectionalLight(const Emitter* emitter, const Transform& to_world);
  void AddEnvironment(const Emitter* emitter, const Transform& to_world);
  // How lights are chosen (at Commit): in proportion to their power, as
  // estimated from their emitters; uniformly; or, for light samples from a
  // point, by a light BVH weighing power, distance and orientation (light
  // paths start by power then).
  enum class LightChoice { kPower, kUniform, kBvh };
  void ChooseLights(LightChoice choice) { light_choice_ = choice; }
  // How light samples from a point find sphere lights: by the solid angle
  // they subtend (the default), or uniformly in area.
  void SampleSpheresByArea(bool by_area) { spheres_by_area_ = by_area; }
  // Whether they find triangles that subtend a fair solid angle by that
  // solid angle (pbrt-v4), or uniformly in area (the default, Mitsuba).
  void SampleTrianglesBySolidAngle(bool by_solid_angle) { triangles_by_solid_angle_ = by_solid_angle; }
  // Whether anything reads texture footprints (SceneView::FootprintsRead).
  void ReadFootprints(bool read) { footprints_read_ = read; }
  // Whether anything reads positions (SceneView::PositionsRead).
  void ReadPositions(bool read) { positions_read_ = read; }
  void Commit();

  // Commit (the BVH builds) and every later Intersect and Occluded throw
  // Error once `stop` is set: whatever loop a transport runs (photon
  // shooting, cache building, a render pass) traces rays, so a cancelled
  // job ends within one batch.
  void StopWhen(const std::atomic<bool>& stop) { stop_ = &stop; }
  bool Stopped() const;
  // Throws Error("the job was stopped") once it is.
  void ThrowIfStopped() const;

  // SceneView
  void Intersect(std::span<const Ray> rays, std::span<Hit> hits) const override;
  void Occluded(std::span<const Ray> rays, std::span<uint8_t> occluded) const override;
  uint32_t MaterialCount() const override { return uint32_t(materials_.size()); }
  const SurfaceModel& Material(uint32_t material) const override { return *materials_[material]; }
  uint32_t MaterialOf(uint32_t shape) const override { return shapes_[shape].look.material; }
  const Emitter* EmitterOf(uint32_t shape) const override { return shapes_[shape].look.emitter; }
  bool HasLights() const override { return !lights_.empty(); }
  LightSample SampleLight(float u_choice, float u0, float u1) const override;
  float LightPdfArea(uint32_t shape) const override { return shape_light_pdf_[shape]; }
  Vec3 InfiniteLightOrigin(Vec3 d, float u0, float u1, float& pdf_area) const override;
  void SampleLightsFrom(std::span<const Vec3> points, std::span<const float> uniform,
                        std::span<LightDirection> out) const override;
  float LightPdfFrom(const Ray& ray, const Hit& hit) const override;
  bool HasEnvironment() const override { return environment_ != kNoLight; }
  void Escaped(std::span<const Vec3> directions, std::span<Vec3> radiance, std::span<float> pdf) const override;
  uint32_t LightCount() const override { return uint32_t(lights_.size()); }
  LightDirection LightPoint(uint32_t light, Vec3 seen_from) const override;
  // The probability of choosing each light (for tests and benchmarks).
  float LightProbability(uint32_t light) const { return lights_[light].probability; }
  float ShutterTime(float u) const override { return camera_.Time(u); }
  Ray CameraRay(float film_x, float film_y, float lens_u, float lens_v, float time) const override {
    return camera_.Generate(film_x, film_y, lens_u, lens_v, time);
  }
  bool ConnectToCamera(Vec3 p, float lens_u, float lens_v, CameraConnection& out) const override;
  // Footprints are a film sample's spacing: a pixel's over √spp for the
  // job's samples per pixel. pbrt-v4 stops shrinking at 1/8 of a pixel;
  // yarf does not, so that a render of many samples converges to the
  // pixel's own integral (what a reference renders) rather than to a
  // prefiltered texture's.
  void SetSamplesPerPixel(uint32_t spp);
  void SampleSpacing(Vec3 p, Vec3 n, Vec3& dpdx, Vec3& dpdy) const override;
  bool FootprintsRead() const override { return footprints_read_; }
  bool PositionsRead() const override { return positions_read_; }
  void Attribute(std::string_view name, std::span<const SurfaceLocation> at, std::span<float> rgb) const override;
  bool CameraHasLens() const override { return camera_.HasLens(); }
  bool CameraReadsLens() const override { return camera_.ReadsLens(); }
  bool CameraReadsTime() const override { return camera_.ReadsTime(); }
  std::string_view CameraUnreachableReason() const override { return camera_.UnreachableReason(); }
  // What each camera sample's radiance counts for on the film (π for an
  // irradiance meter); the film target applies it.
  float CameraRayWeight() const { return camera_.RayWeight(); }
  float CameraDirectionPdf(Vec3 direction) const override { return camera_.DirectionPdf(direction); }
  uint32_t FilmWidth() const override { return width_; }
  uint32_t FilmHeight() const override { return height_; }
  uint32_t MediumCount() const override { return uint32_t(media_.size()); }
  const Medium& MediumAt(uint32_t medium) const override { return *media_.at(medium); }
  MediumInterface MediaOf(uint32_t shape) const override { return shapes_[shape].look.media; }
  uint32_t CameraMedium() const override { return camera_medium_; }
  uint64_t ServiceHandle() const override { return service_handle_; }
  void SetServiceHandle(uint64_t handle) { service_handle_ = handle; }

  uint32_t ShapeCount() const override { return uint32_t(shapes_.size()); }
  // Shape `shape`'s surface, as placed at shutter open, sampled as this
  // scene samples its lights.
  std::unique_ptr<ShapeSurface> MakeSurface(uint32_t shape) const;
  uint32_t PrimitiveCount(uint32_t shape) const override;
  bool Triangle(uint32_t shape, uint32_t primitive, Vec3 corners[3]) const override;
  // The committed Embree scene (for measuring Embree itself).
  RTCScene embree_scene() const { return groups_[kWorld].scene; }
  uint64_t ClosestHitRays() const { return closest_hit_rays_.load(std::memory_order_relaxed); }
  uint64_t ShadowRays() const { return shadow_rays_.load(std::memory_order_relaxed); }

 private:
  // Commits `scene`, stopping early when the job stops.
  void Build(RTCScene scene) const;
  // A mesh as Embree triangles, geometry `id` of `scene`.
  void AttachMesh(RTCScene scene, uint32_t id, const TriangleMesh& mesh, const ShapeLook& look);

  enum class Kind { kTriangles, kSphere, kCurves };
  struct ShapeRecord {
    Kind kind = Kind::kTriangles;
    uint32_t mesh = 0;  // into meshes_, or curves_ for curves
    Vec3 center;
    float radius = 0;
    // A sphere's own axes, in its group's space (world once placed).
    std::array<Vec3, 3> axes{Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
    bool placed = false;  // false: world geometry, already in world space
    Transform to_world;
    // Placed shapes that move: where they are when the shutter closes.
    bool moving = false;
    Transform to_world_end;
    ShapeLook look;
  };
  struct Placement {
    uint32_t group;
    Transform to_world;
    std::optional<Transform> to_world_end;
  };
  struct Group {
    RTCScene scene = nullptr;
    std::vector<ShapeRecord> shapes;
    // A custom aggregate, and the shapes (by number in the group) it holds.
    std::shared_ptr<Aggregate> aggregate;
    std::vector<uint32_t> aggregated;
  };
  // Fills the group's aggregate with its meshes and attaches it to the
  // group's scene as geometry `id`, if it holds any.
  void AttachAggregate(Group& group, uint32_t id);

  // A placed shape's to_world at shutter time `time` (moving ones interpolated).
  static Transform PlacementAt(const ShapeRecord& shape, float time);
  Vec3 Normal(const ShapeRecord& shape, uint32_t primitive, Vec3 position, float time) const;
  // Fills a curve hit's normal, uv, shading normal and ∂p/∂u, ∂p/∂v (its
  // shape, primitive and Embree's u and v set): a tube's normal is
  // Embree's `ng` (in its group's space), a ribbon's faces the ray's
  // reverse, `toward`.
  void ShadeCurve(const ShapeRecord& shape, float time, Vec3 ng, Vec3 toward, Hit& hit) const;
  // Fills a surface hit's uv, shading normal and ∂p/∂u, ∂p/∂v (its shape,
  // primitive, barycentrics and geometric normal set) at `position`.
  void Shade(const ShapeRecord& shape, Vec3 position, float time, Hit& hit) const;
  // Intersect and Occluded in packets of N rays (8 or 16).
  template <size_t N>
  void IntersectPackets(std::span<const Ray> rays, std::span<Hit> hits) const;
  template <size_t N>
  void OccludedPackets(std::span<const Ray> rays, std::span<uint8_t> occluded) const;
  // The lights of the emitting shapes, after the point and infinite ones.
  void AddSurfaceLights();
  // Each light's power estimated from its emitter, and the probabilities
  // of choosing them.
  void ChooseLightsByPower();
  struct Light;
  float EstimatePower(const Light& light) const;
  // The light u_choice picks, and u_choice rescaled within its share.
  uint32_t PickLight(float u_choice, float& u_rest) const;
  // The light u_choice picks for a light sample from point p, its
  // probability, and u_choice rescaled; kNoLight when none can reach p.
  uint32_t PickLightFor(Vec3 p, float u_choice, float& u_rest, float& probability) const;
  // SampleLightsFrom's points `on_surface` (indices into points), whose
  // lights `picked` are surfaces, with PickLightFor's probability and
  // u_rest for every point.
  void SampleSurfaceLights(std::span<const Vec3> points, std::span<const float> uniform,
                           std::span<const uint32_t> picked, std::span<const float> probability,
                           std::span<const float> u_primitive, std::span<const uint32_t> on_surface,
                           std::span<LightDirection> out) const;
  // SampleLightsFrom's points `from_environment`, whose light is the
  // environment: their directions, and their pdf multiplied by the map's.
  void SampleEnvironment(std::span<const float> uniform, std::span<const uint32_t> from_environment,
                         std::span<LightDirection> out) const;
  // The probability PickLightFor picks `light` from p.
  float ProbabilityFrom(uint32_t light, Vec3 p) const;
  // The light BVH over the surface and point lights, and the lights at
  // infinity beside it.
  void BuildLightBvh();
  // A point uniform in area on surface light `light` (u_primitive chooses
  // its primitive).
  LightSample PointOnSurfaceLight(const Light& light, float u_primitive, float u0, float u1) const;
  void Triangle(const ShapeRecord& shape, uint32_t primitive, Vec3 v[3]) const;

  const EmbreeDevice& device_;
  // Whether Embree runs 16-ray packets natively (AVX-512) on this CPU;
  // else rays go 8 at a time.
  bool wide_packets_;
  Camera camera_;
  uint64_t service_handle_ = 0;
  float sample_spacing_ = 1;
  bool footprints_read_ = true;
  bool positions_read_ = true;
  uint32_t width_, height_;
  // Shared: a material may wrap another (normalmap).
  std::vector<std::shared_ptr<const SurfaceModel>> materials_;
  std::vector<std::unique_ptr<Emitter>> emitters_;
  std::vector<std::unique_ptr<Medium>> media_;
  uint32_t camera_medium_ = kNoMedium;
  std::optional<uint32_t> meter_shape_;
  std::vector<TriangleMesh> meshes_;
  std::vector<CurveGeometry> curves_;
  // The cut-outs of meshes with an alpha texture, Embree's filter data.
  std::vector<std::unique_ptr<AlphaCut>> alpha_cuts_;
  std::vector<Group> groups_;
  std::vector<std::unique_ptr<AggregateGeometry>> aggregate_geometries_;
  std::vector<Placement> placements_;
  // Unit normals of each mesh's triangles in the mesh's own space.
  std::vector<std::vector<Vec3>> face_normals_;
  // Every shape placement; Hit::shape indexes it.
  std::vector<ShapeRecord> shapes_;
  // First shape id of each world-level Embree geometry (by geomID).
  std::vector<uint32_t> geometry_base_;
  // A light: an emitting shape's surface, a point light, or a light at
  // infinity.
  enum class LightKind { kSurface, kPoint, kDirectional, kEnvironment };
  struct Light {
    LightKind kind = LightKind::kSurface;
    uint32_t shape = kNoShape;
    std::shared_ptr<const ShapeSurface> surface;
    const Emitter* emitter = nullptr;
    // Point lights: where they are and their axis.
    Vec3 position, axis;
    // Lights at infinity: the emitter's local frame in the world.
    Frame frame{Vec3(0, 0, 1)};
    // Of being chosen.
    float probability = 0;
    float power = 0;
  };
  static constexpr uint32_t kNoLight = 0xFFFFFFFFu;
  std::vector<Light> lights_;
  // The running sum of the lights' probabilities, apart for PickLight's search.
  std::vector<float> light_cdf_;
  uint32_t environment_ = kNoLight;
  LightChoice light_choice_ = LightChoice::kPower;
  LightBvh light_bvh_;
  // kBvh: the lights at infinity, chosen evenly with the BVH as one more.
  std::vector<uint32_t> infinite_lights_;
  float infinite_probability_ = 0;
  bool spheres_by_area_ = false;
  bool triangles_by_solid_angle_ = false;
  // The sphere around the scene and the camera that lights at infinity
  // send their light paths through.
  Vec3 bounds_center_;
  float bounds_radius_ = 1;
  // SampleLight's area density on each shape (0 when it does not emit),
  // and the light each emitting shape is.
  std::vector<float> shape_light_pdf_;
  std::vector<uint32_t> shape_light_;
  mutable std::atomic<uint64_t> closest_hit_rays_{0}, shadow_rays_{0};
  const std::atomic<bool>* stop_ = nullptr;
};

}  // namespace yarf
