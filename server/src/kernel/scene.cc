#include "kernel/scene.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <type_traits>

#include "yarf/error.h"
#include "yarf/support/warps.h"
#include "yarf/support/wavefront.h"

namespace yarf {
namespace {

// How many emitter samples estimate a light's power.
constexpr uint32_t kPowerSamples = 256;

// Point k of n in [0,1)³, well spread (a rank-1 lattice), for power
// estimates that are the same from run to run.
std::array<float, 3> SpreadPoint(uint32_t k, uint32_t n) {
  const float x = (float(k) + 0.5f) / float(n);
  const auto frac = [](double v) { return float(v - std::floor(v)); };
  return {x, frac(k * 0.6180339887498949), frac(k * 0.7548776662466927)};
}

// The frame whose axes are to_world's images of x, y, z, made orthonormal
// (z kept): a light's local frame.
Frame FrameOf(const Transform& to_world) {
  Frame frame(Normalize(to_world.Vector(Vec3(0, 0, 1))));
  const Vec3 x = to_world.Vector(Vec3(1, 0, 0));
  const Vec3 s = x - frame.n * Dot(frame.n, x);
  if (Length(s) > 1e-6f * Length(x)) {
    frame.s = Normalize(s);
    frame.t = Cross(frame.n, frame.s);
  }
  return frame;
}

}  // namespace

KernelScene::KernelScene(const EmbreeDevice& device, const Camera& camera, uint32_t width,
                         uint32_t height)
    : device_(device),
      wide_packets_(rtcGetDeviceProperty(device.get(), RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED) != 0),
      camera_(camera),
      width_(width),
      height_(height) {
  groups_.push_back({rtcNewScene(device.get()), {}});  // kWorld
}

KernelScene::~KernelScene() {
  for (Group& g : groups_) rtcReleaseScene(g.scene);
}

uint32_t KernelScene::AddMaterial(std::shared_ptr<const SurfaceModel> material) {
  materials_.push_back(std::move(material));
  return uint32_t(materials_.size() - 1);
}

uint32_t KernelScene::AddMedium(std::unique_ptr<Medium> medium) {
  media_.push_back(std::move(medium));
  return uint32_t(media_.size() - 1);
}

const Emitter* KernelScene::AddEmitter(std::unique_ptr<Emitter> emitter) {
  emitters_.push_back(std::move(emitter));
  return emitters_.back().get();
}

std::vector<const Emitter*> KernelScene::Emitters() const {
  std::vector<const Emitter*> emitters;
  for (const auto& emitter : emitters_) emitters.push_back(emitter.get());
  return emitters;
}

uint32_t KernelScene::NewGroup() {
  groups_.push_back({rtcNewScene(device_.get()), {}});
  return uint32_t(groups_.size() - 1);
}

void KernelScene::AttachMesh(RTCScene scene, uint32_t id, const TriangleMesh& mesh, const ShapeLook& look) {
  RTCGeometry geom = rtcNewGeometry(device_.get(), RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
      geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), mesh.positions.size()));
  auto* indices = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
      geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), mesh.TriangleCount()));
  if (!vertices || !indices) {
    rtcReleaseGeometry(geom);
    device_.Check("mesh '" + look.name + "'");
    throw Error("mesh '" + look.name + "': Embree could not allocate its buffers");
  }
  for (size_t i = 0; i < mesh.positions.size(); ++i) mesh.positions[i].Store(vertices + 3 * i);
  std::copy(mesh.indices.begin(), mesh.indices.end(), indices);
  if (look.alpha) {
    alpha_cuts_.push_back(std::make_unique<AlphaCut>(look.alpha, mesh.indices, mesh.uvs));
    alpha_cuts_.back()->Attach(geom);
  }
  rtcCommitGeometry(geom);
  rtcAttachGeometryByID(scene, geom, id);
  rtcReleaseGeometry(geom);
}

void KernelScene::SetAggregate(uint32_t group, std::shared_ptr<Aggregate> aggregate) {
  if (!groups_[group].shapes.empty()) throw Error("an aggregate is set before the shapes it holds");
  groups_[group].aggregate = std::move(aggregate);
}

uint32_t KernelScene::AddMesh(uint32_t group, TriangleMesh mesh, const ShapeLook& look) {
  // A mesh with vertex normals takes its side from them, even where they
  // are its faces' own and dropped as such.
  const bool winding_decides = mesh.normals.empty();
  DropFaceNormals(mesh);
  // Shapes are Embree geometries numbered as in their group, so that a hit
  // names its shape whichever aggregate found it.
  const uint32_t id = uint32_t(groups_[group].shapes.size());
  if (groups_[group].aggregate && !look.alpha)
    groups_[group].aggregated.push_back(id);
  else
    AttachMesh(groups_[group].scene, id, mesh, look);

  ShapeRecord record;
  record.kind = Kind::kTriangles;
  record.mesh = uint32_t(meshes_.size());
  record.look = look;
  std::vector<Vec3> normals(mesh.TriangleCount());
  for (size_t t = 0; t < normals.size(); ++t) {
    const uint32_t* v = &mesh.indices[3 * t];
    const Vec3 p0 = mesh.positions[v[0]], p1 = mesh.positions[v[1]], p2 = mesh.positions[v[2]];
    const Vec3 n = Cross(p1 - p0, p2 - p0);
    const float length = Length(n);
    normals[t] = length > 0 ? n / length : Vec3(0, 0, 1);
    if (look.flip_winding && winding_decides) normals[t] = -normals[t];
    // With vertex normals, the face's side is theirs (as pbrt-v4): the
    // winding of a smooth mesh's triangles need not agree with them.
    if (!mesh.normals.empty() && Dot(normals[t], mesh.normals[v[0]] + mesh.normals[v[1]] + mesh.normals[v[2]]) < 0)
      normals[t] = -normals[t];
    if (look.flip_normals) normals[t] = -normals[t];
  }
  face_normals_.push_back(std::move(normals));
  meshes_.push_back(std::move(mesh));
  groups_[group].shapes.push_back(record);
  return uint32_t(groups_[group].shapes.size() - 1);
}

uint32_t KernelScene::AddSphere(uint32_t group, Vec3 center, float radius, const ShapeLook& look,
                                const std::array<Vec3, 3>& axes) {
  RTCGeometry geom = rtcNewGeometry(device_.get(), RTC_GEOMETRY_TYPE_SPHERE_POINT);
  auto* point = static_cast<float*>(rtcSetNewGeometryBuffer(
      geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float), 1));
  point[0] = center.x;
  point[1] = center.y;
  point[2] = center.z;
  point[3] = radius;
  rtcCommitGeometry(geom);
  rtcAttachGeometryByID(groups_[group].scene, geom, uint32_t(groups_[group].shapes.size()));
  rtcReleaseGeometry(geom);

  ShapeRecord record;
  record.kind = Kind::kSphere;
  record.center = center;
  record.radius = radius;
  record.axes = axes;
  record.look = look;
  groups_[group].shapes.push_back(record);
  return uint32_t(groups_[group].shapes.size() - 1);
}

uint32_t KernelScene::AddCurves(uint32_t group, CurveGeometry curves, const ShapeLook& look) {
  // Embree reads the points each segment names: none may lie beyond them.
  if (const std::string defect = curves.Defect(); !defect.empty()) throw Error("shape '" + look.name + "': " + defect);
  AttachCurves(device_.get(), groups_[group].scene, uint32_t(groups_[group].shapes.size()), curves);
  ShapeRecord record;
  record.kind = Kind::kCurves;
  record.mesh = uint32_t(curves_.size());
  record.look = look;
  curves_.push_back(std::move(curves));
  groups_[group].shapes.push_back(record);
  return uint32_t(groups_[group].shapes.size() - 1);
}

void KernelScene::AddPlacement(uint32_t group, const Transform& to_world,
                               const std::optional<Transform>& to_world_end) {
  placements_.push_back({group, to_world, to_world_end});
}

void KernelScene::AddDirectionalLight(const Emitter* emitter, const Transform& to_world) {
  Light light;
  light.kind = LightKind::kDirectional;
  light.emitter = emitter;
  light.frame = FrameOf(to_world);
  lights_.push_back(light);
}

void KernelScene::AddEnvironment(const Emitter* emitter, const Transform& to_world) {
  if (environment_ != kNoLight) throw Error("a scene has at most one environment light");
  Light light;
  light.kind = LightKind::kEnvironment;
  light.emitter = emitter;
  light.frame = FrameOf(to_world);
  environment_ = uint32_t(lights_.size());
  lights_.push_back(light);
}

void KernelScene::Build(RTCScene scene) const {
  // Embree asks between steps of a build whether to go on: a stopped job
  // does not wait for the BVH of a huge mesh.
  rtcSetSceneProgressMonitorFunction(
      scene, [](void* self, double) { return !static_cast<const KernelScene*>(self)->Stopped(); },
      const_cast<KernelScene*>(this));
  rtcCommitScene(scene);
  ThrowIfStopped();
  device_.Check("scene build");
}

void KernelScene::AttachAggregate(Group& group, uint32_t id) {
  if (!group.aggregate || group.aggregated.empty()) return;
  for (uint32_t shape : group.aggregated) {
    const TriangleMesh& mesh = meshes_[group.shapes[shape].mesh];
    group.aggregate->Add(mesh.positions, mesh.indices);
  }
  group.aggregate->Commit();
  ThrowIfStopped();
  aggregate_geometries_.push_back(std::make_unique<AggregateGeometry>(group.aggregate, group.aggregated));
  aggregate_geometries_.back()->Attach(device_.get(), group.scene, id);
  device_.Check("aggregate");
}

void KernelScene::AddLight(const Emitter* emitter, const Transform& to_world) {
  Light light;
  light.emitter = emitter;
  light.kind = LightKind::kPoint;
  light.position = to_world.Point(Vec3(0, 0, 0));
  light.axis = Normalize(to_world.Vector(Vec3(0, 0, 1)));
  lights_.push_back(light);
}

void KernelScene::Commit() {
  // World geometries come first, one shape each; then each placement adds
  // an instance whose geometries are the shapes of its group.
  for (const ShapeRecord& s : groups_[kWorld].shapes) {
    geometry_base_.push_back(uint32_t(shapes_.size()));
    shapes_.push_back(s);
  }
  // Each group's aggregate follows its shapes; in the world its number
  // leads to no shape of its own, since its hits name theirs.
  for (Group& group : groups_) AttachAggregate(group, uint32_t(group.shapes.size()));
  if (groups_[kWorld].aggregate && !groups_[kWorld].aggregated.empty()) geometry_base_.push_back(0);
  if (camera_.IsIrradianceMeter()) {
    if (!meter_shape_ || *meter_shape_ >= shapes_.size())
      throw Error("camera: the irradiance meter's shape is not a shape of the world");
    camera_.MeasureOn(MakeSurface(*meter_shape_));
  }
  for (size_t g = 1; g < groups_.size(); ++g) {
    rtcSetSceneBuildQuality(groups_[g].scene, RTC_BUILD_QUALITY_HIGH);
    Build(groups_[g].scene);
  }
  for (const Placement& placement : placements_) {
    RTCGeometry geom = rtcNewGeometry(device_.get(), RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(geom, groups_[placement.group].scene);
    const auto set_transform = [&](uint32_t step, const Transform& t) {
      float m[12];
      for (int i = 0; i < 12; ++i) m[i] = float(t.m[i]);
      rtcSetGeometryTransform(geom, step, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, m);
    };
    if (placement.to_world_end) {
      // Embree interpolates the matrices linearly over time [0, 1].
      rtcSetGeometryTimeStepCount(geom, 2);
      set_transform(1, *placement.to_world_end);
    }
    set_transform(0, placement.to_world);
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(groups_[kWorld].scene, geom, uint32_t(geometry_base_.size()));
    rtcReleaseGeometry(geom);
    geometry_base_.push_back(uint32_t(shapes_.size()));
    for (ShapeRecord s : groups_[placement.group].shapes) {
      s.placed = true;
      s.to_world = placement.to_world;
      for (Vec3& axis : s.axes) axis = Normalize(placement.to_world.Vector(axis));
      s.moving = placement.to_world_end.has_value();
      if (s.moving) s.to_world_end = *placement.to_world_end;
      shapes_.push_back(s);
    }
  }
  rtcSetSceneBuildQuality(groups_[kWorld].scene, RTC_BUILD_QUALITY_HIGH);
  Build(groups_[kWorld].scene);
  // The sphere lights at infinity shoot through holds the scene and the eye.
  RTCBounds box;
  rtcGetSceneBounds(groups_[kWorld].scene, &box);
  Vec3 lower(box.lower_x, box.lower_y, box.lower_z), upper(box.upper_x, box.upper_y, box.upper_z);
  const Vec3 eye = camera_.origin();
  if (!(lower.x <= upper.x)) lower = upper = eye;  // an empty scene
  bounds_center_ = (lower + upper) * 0.5f;
  bounds_radius_ = std::max({Length(upper - bounds_center_), Length(eye - bounds_center_), 1e-3f});
  AddSurfaceLights();
  ChooseLightsByPower();
  if (light_choice_ == LightChoice::kBvh) BuildLightBvh();
}

void KernelScene::AddSurfaceLights() {
  // Surface lights follow the point and infinite lights already added,
  // one per emitting shape placement.
  shape_light_pdf_.assign(shapes_.size(), 0.0f);
  shape_light_.assign(shapes_.size(), kNoLight);
  for (uint32_t id = 0; id < shapes_.size(); ++id) {
    const ShapeRecord& s = shapes_[id];
    if (!s.look.emitter) continue;
    if (s.moving) throw Error("shape '" + s.look.name + "' moves and emits: moving lights are not supported");
    Light light;
    light.shape = id;
    light.emitter = s.look.emitter;
    light.surface = MakeSurface(id);
    if (!(light.surface->Area() > 0)) continue;
    shape_light_[id] = uint32_t(lights_.size());
    lights_.push_back(std::move(light));
  }
}

std::unique_ptr<ShapeSurface> KernelScene::MakeSurface(uint32_t shape) const {
  const ShapeRecord& s = shapes_.at(shape);
  if (s.kind == Kind::kCurves)
    throw Error("shape '" + s.look.name + "' is curves, which have no surface to sample points on");
  if (s.kind == Kind::kSphere) {
    SphereGeometry sphere;
    sphere.center = s.placed ? s.to_world.Point(s.center) : s.center;
    // Spheres are placed by similarity transforms: scale by the cube root
    // of the determinant.
    sphere.radius = s.radius * (s.placed ? float(std::cbrt(std::abs(s.to_world.Determinant3()))) : 1.0f);
    sphere.axes = s.axes;
    sphere.flip_normals = s.look.flip_normals;
    return std::make_unique<SphereSurface>(sphere, !spheres_by_area_);
  }
  const uint32_t count = uint32_t(meshes_[s.mesh].TriangleCount());
  std::vector<std::array<Vec3, 3>> corners(count);
  std::vector<Vec3> normals(count);
  for (uint32_t p = 0; p < count; ++p) {
    Triangle(s, p, corners[p].data());
    normals[p] = Normal(s, p, corners[p][0], 0);
  }
  return std::make_unique<MeshSurface>(std::move(corners), std::move(normals), meshes_[s.mesh],
                                       triangles_by_solid_angle_);
}

float KernelScene::EstimatePower(const Light& light) const {
  // Φ = ∫∫ L cos dω dA, by the emitter's own direction samples: surfaces
  // at points uniform in area; lights at infinity through the disk of the
  // scene's bounding sphere (as pbrt-v4 counts them).
  const uint32_t n = light.kind == LightKind::kDirectional ? 1 : kPowerSamples;
  std::vector<float> u(2 * n), w(3 * n), pdf(n), uv(2 * n), radiance(3 * n);
  for (uint32_t k = 0; k < n; ++k) {
    const auto p = SpreadPoint(k, n);
    u[2 * k] = p[1], u[2 * k + 1] = p[2];
    if (light.kind == LightKind::kSurface) {
      const LightSample s = PointOnSurfaceLight(light, p[0], p[1], p[2]);
      uv[2 * k] = s.u, uv[2 * k + 1] = s.v;
      // Fresh numbers for the direction, unrelated to the point's.
      u[2 * k] = SpreadPoint(k * 7 + 3, n * 7)[0], u[2 * k + 1] = SpreadPoint(k * 5 + 1, n * 5)[2];
    }
  }
  if (light.kind == LightKind::kDirectional) {
    w = {0, 0, 1};
    pdf = {1};
  } else {
    light.emitter->SampleDirection(u, w, pdf);
  }
  SurfacePoints points;
  points.uv = uv;
  light.emitter->Radiance(w, points, radiance);
  double sum = 0;
  for (uint32_t k = 0; k < n; ++k) {
    if (!(pdf[k] > 0)) continue;
    const float cos = light.kind == LightKind::kSurface ? std::abs(w[3 * k + 2]) : 1.0f;
    const double value = (double(radiance[3 * k]) + radiance[3 * k + 1] + radiance[3 * k + 2]) / 3 * cos / pdf[k];
    if (std::isfinite(value) && value > 0) sum += value;
  }
  double power = sum / n;
  if (light.kind == LightKind::kSurface) power *= light.surface->Area();
  if (light.kind == LightKind::kDirectional || light.kind == LightKind::kEnvironment)
    power *= kPi * double(bounds_radius_) * bounds_radius_;
  return std::isfinite(power) ? float(power) : 0.0f;
}

void KernelScene::ChooseLightsByPower() {
  // Every light keeps a share of a hundredth of the mean power, so that
  // one whose estimate missed its light (a small bright texel) is still
  // chosen sometimes.
  std::vector<double> weight(lights_.size(), 1.0);
  if (light_choice_ != LightChoice::kUniform && !lights_.empty()) {
    double total = 0;
    for (size_t l = 0; l < lights_.size(); ++l) total += weight[l] = lights_[l].power = EstimatePower(lights_[l]);
    const double floor = total > 0 ? 0.01 * total / double(lights_.size()) : 1.0;
    for (double& w : weight) w += floor;
  }
  double total = 0;
  for (double w : weight) total += w;
  double running = 0;
  light_cdf_.resize(lights_.size());
  for (size_t l = 0; l < lights_.size(); ++l) {
    lights_[l].probability = float(weight[l] / total);
    running += weight[l];
    light_cdf_[l] = l + 1 == lights_.size() ? 1.0f : float(running / total);
  }
  for (const Light& light : lights_)
    if (light.kind == LightKind::kSurface) shape_light_pdf_[light.shape] = light.probability / light.surface->Area();
}

void KernelScene::Triangle(const ShapeRecord& shape, uint32_t primitive, Vec3 v[3]) const {
  const TriangleMesh& mesh = meshes_[shape.mesh];
  for (int k = 0; k < 3; ++k) {
    v[k] = mesh.positions[mesh.indices[3 * primitive + k]];
    if (shape.placed) v[k] = shape.to_world.Point(v[k]);
  }
}

void KernelScene::SetSamplesPerPixel(uint32_t spp) {
  sample_spacing_ = 1 / std::sqrt(float(std::max(spp, 1u)));
}

void KernelScene::SampleSpacing(Vec3 p, Vec3 n, Vec3& dpdx, Vec3& dpdy) const {
  camera_.PixelSpacing(p, n, &dpdx, &dpdy);
  dpdx = dpdx * sample_spacing_;
  dpdy = dpdy * sample_spacing_;
}

void KernelScene::Attribute(std::string_view name, std::span<const SurfaceLocation> at,
                            std::span<float> rgb) const {
  std::fill(rgb.begin(), rgb.end(), 0.0f);
  // Points of a batch mostly share a shape: its attribute is looked up once.
  uint32_t shape_seen = kNoShape;
  const MeshAttribute* attribute = nullptr;
  const TriangleMesh* mesh = nullptr;
  for (size_t k = 0; k < at.size() && 3 * k + 2 < rgb.size(); ++k) {
    const SurfaceLocation& where = at[k];
    if (where.shape != shape_seen) {
      shape_seen = where.shape;
      attribute = nullptr;
      if (where.shape < shapes_.size() && shapes_[where.shape].kind == Kind::kTriangles) {
        mesh = &meshes_[shapes_[where.shape].mesh];
        for (const MeshAttribute& a : mesh->attributes)
          if (a.name == name) attribute = &a;
      }
    }
    if (!attribute || where.primitive >= mesh->TriangleCount()) continue;
    const uint32_t c = attribute->channels;
    float value[3] = {0, 0, 0};
    if (attribute->PerFace()) {
      for (uint32_t i = 0; i < c && i < 3; ++i) value[i] = attribute->values[c * size_t(where.primitive) + i];
    } else {
      const uint32_t* v = &mesh->indices[3 * size_t(where.primitive)];
      const float b[3] = {1 - where.b1 - where.b2, where.b1, where.b2};
      for (int corner = 0; corner < 3; ++corner)
        for (uint32_t i = 0; i < c && i < 3; ++i) value[i] += b[corner] * attribute->values[c * size_t(v[corner]) + i];
    }
    for (int i = 0; i < 3; ++i) rgb[3 * k + i] = c == 1 ? value[0] : value[i];
  }
}

uint32_t KernelScene::PrimitiveCount(uint32_t shape) const {
  const ShapeRecord& record = shapes_[shape];
  switch (record.kind) {
    case Kind::kSphere:
      return 1;
    case Kind::kCurves:
      return uint32_t(curves_[record.mesh].segments.size());
    case Kind::kTriangles:
      break;
  }
  return uint32_t(meshes_[record.mesh].TriangleCount());
}

bool KernelScene::Triangle(uint32_t shape, uint32_t primitive, Vec3 corners[3]) const {
  const ShapeRecord& record = shapes_[shape];
  if (record.kind != Kind::kTriangles) return false;
  Triangle(record, primitive, corners);
  return true;
}

Transform KernelScene::PlacementAt(const ShapeRecord& shape, float time) {
  Transform to_world = shape.to_world;
  if (shape.moving)
    for (int i = 0; i < 16; ++i) to_world.m[i] += time * (shape.to_world_end.m[i] - to_world.m[i]);
  return to_world;
}

Vec3 KernelScene::Normal(const ShapeRecord& shape, uint32_t primitive, Vec3 position,
                         float time) const {
  // The placement is made (16 numbers, interpolated if moving) only for
  // a placed shape: most hits are on shapes that have none.
  if (shape.kind == Kind::kTriangles) {
    const Vec3 n = face_normals_[shape.mesh][primitive];  // flipped already
    return shape.placed ? Normalize(PlacementAt(shape, time).Normal(n)) : n;
  }
  const Vec3 center = shape.placed ? PlacementAt(shape, time).Point(shape.center) : shape.center;
  const Vec3 n = Normalize(position - center);
  return shape.look.flip_normals ? -n : n;
}

void KernelScene::ShadeCurve(const ShapeRecord& shape, float time, Vec3 ng, Vec3 toward, Hit& hit) const {
  const CurveGeometry& curves = curves_[shape.mesh];
  // u along the segment, v across it (Embree's, from -1 to 1 on a
  // ribbon).
  hit.u = hit.b1;
  hit.v = std::clamp(0.5f * (hit.b2 + 1), 0.0f, 1.0f);
  hit.b1 = hit.b2 = 0;
  hit.parameterised = false;
  Vec3 tangent = curves.Tangent(hit.primitive, hit.u);
  std::optional<Transform> to_world;
  if (shape.placed) to_world = PlacementAt(shape, time);
  if (to_world) tangent = to_world->Vector(tangent);
  // A ribbon turns about its centre line to face the ray: its normal is
  // the ray's reverse less its part along the curve. A tube's is Embree's.
  toward = Normalize(toward);
  Vec3 n;
  if (curves.flat) {
    const float length = Length(tangent);
    n = length > 0 && std::isfinite(length) ? toward - tangent * (Dot(toward, tangent) / (length * length)) : toward;
  } else {
    n = to_world ? to_world->Normal(ng) : ng;
  }
  const float n_length = Length(n);
  // Zero only where the curve has no width, or runs along the ray: any
  // unit vector facing the ray then.
  n = n_length > 1e-12f && std::isfinite(n_length) ? n / n_length : toward;
  hit.normal = hit.shading_normal = shape.look.flip_normals && !curves.flat ? -n : n;
  // The tangent orients the shading frame, as hair needs.
  tangent = tangent - hit.normal * Dot(tangent, hit.normal);
  const float t_length = Length(tangent);
  hit.dpdu = t_length > 1e-12f && std::isfinite(t_length) ? tangent / t_length : Frame(hit.normal).s;
  hit.dpdv = Cross(hit.normal, hit.dpdu);
}

void KernelScene::Shade(const ShapeRecord& shape, Vec3 position, float time, Hit& hit) const {
  hit.shading_normal = hit.normal;
  hit.parameterised = shape.kind == Kind::kSphere;
  if (shape.kind == Kind::kSphere) {
    const Vec3 center = shape.placed ? shape.to_world.Point(shape.center) : shape.center;
    const float r = Length(position - center);
    SphereParameters(shape.axes, r > 0 ? (position - center) / r : shape.axes[2], r, hit);
    return;
  }
  const TriangleMesh& mesh = meshes_[shape.mesh];
  if (mesh.uvs.empty() && mesh.normals.empty()) {
    // Flat and unparameterised: its barycentrics are its uv, the shading
    // frame is the normal's own (dp/du left zero), and nothing is read.
    hit.u = hit.b1, hit.v = hit.b2;
    hit.dpdu = hit.dpdv = Vec3();
    return;
  }
  const uint32_t* v = &mesh.indices[3 * hit.primitive];
  const Transform to_world = PlacementAt(shape, time);
  Vec3 p[3];
  for (int k = 0; k < 3; ++k) p[k] = shape.placed ? to_world.Point(mesh.positions[v[k]]) : mesh.positions[v[k]];
  // uv of the corners: the mesh's, else the barycentric parameterisation.
  float uv[3][2] = {{0, 0}, {1, 0}, {0, 1}};
  if (!mesh.uvs.empty())
    for (int k = 0; k < 3; ++k) uv[k][0] = mesh.uvs[2 * v[k]], uv[k][1] = mesh.uvs[2 * v[k] + 1];
  const float b0 = 1 - hit.b1 - hit.b2;
  hit.u = b0 * uv[0][0] + hit.b1 * uv[1][0] + hit.b2 * uv[2][0];
  hit.v = b0 * uv[0][1] + hit.b1 * uv[1][1] + hit.b2 * uv[2][1];
  // ∂p/∂u, ∂p/∂v from p − p2 = (u − u2)·∂p/∂u + (v − v2)·∂p/∂v at the
  // other two corners.
  const float du02 = uv[0][0] - uv[2][0], dv02 = uv[0][1] - uv[2][1];
  const float du12 = uv[1][0] - uv[2][0], dv12 = uv[1][1] - uv[2][1];
  const Vec3 dp02 = p[0] - p[2], dp12 = p[1] - p[2];
  const float det = du02 * dv12 - dv02 * du12;
  const Vec3 dpdu = (dp02 * dv12 - dp12 * dv02) / det, dpdv = (dp12 * du02 - dp02 * du12) / det;
  if (std::abs(det) > 1e-12f && Length(Cross(dpdu, dpdv)) > 0 && std::isfinite(Dot(dpdu, dpdv))) {
    hit.dpdu = dpdu, hit.dpdv = dpdv;
    hit.parameterised = !mesh.uvs.empty();
  } else {
    // Degenerate uvs: any frame of the plane.
    const Frame frame(hit.normal);
    hit.dpdu = frame.s, hit.dpdv = frame.t;
  }
  if (mesh.normals.empty()) return;
  Vec3 ns = mesh.normals[v[0]] * b0 + mesh.normals[v[1]] * hit.b1 + mesh.normals[v[2]] * hit.b2;
  if (shape.placed) ns = to_world.Normal(ns);
  if (shape.look.flip_normals) ns = -ns;
  const float length = Length(ns);
  // Degenerate or opposing interpolated normals shade flat.
  if (length > 1e-6f && std::isfinite(length) && Dot(ns, hit.normal) > 0) hit.shading_normal = ns / length;
}

namespace {

// Embree asserts (and so aborts the server) on a ray outside its valid
// range: coordinates beyond ~1.8e18, NaNs, a NaN interval. The test is
// on the floats' bits, as integers, so that a packet's lanes take it in
// one vectorised pass: a float's magnitude orders as its bits do, NaNs
// above infinity, and a value in [0, most] has bits in [0, most's] or is
// -0.
constexpr float kLargestCoordinate = 1e18f;
inline uint32_t Above(float x, float most) {
  return (std::bit_cast<uint32_t>(x) & 0x7FFFFFFFu) > std::bit_cast<uint32_t>(most);
}
inline uint32_t Outside(float x, float most) {
  const uint32_t bits = std::bit_cast<uint32_t>(x);
  return (bits > std::bit_cast<uint32_t>(most)) & (bits != 0x80000000u);
}
inline uint32_t Untraceable(float ox, float oy, float oz, float dx, float dy, float dz, float tnear, float tfar,
                            float time) {
  return Above(ox, kLargestCoordinate) | Above(oy, kLargestCoordinate) | Above(oz, kLargestCoordinate) |
         Above(dx, kLargestCoordinate) | Above(dy, kLargestCoordinate) | Above(dz, kLargestCoordinate) |
         Outside(tnear, kInfinity) | Above(tfar, kInfinity) | Outside(time, 1.0f);
}

// Rays a component made are untrusted: one that Embree cannot trace fails
// the job, never the server.
void CheckTraceable(std::span<const Ray> rays, size_t first, size_t count) {
  for (size_t k = first; k < first + count; ++k)
    if (const Ray& r = rays[k]; Untraceable(r.origin.x, r.origin.y, r.origin.z, r.direction.x, r.direction.y,
                                            r.direction.z, r.tnear, r.tfar, r.time)) [[unlikely]] {
      throw Error("a ray Embree cannot trace (origin " + std::to_string(r.origin.x) + ", " +
                  std::to_string(r.origin.y) + ", " + std::to_string(r.origin.z) + "; direction " +
                  std::to_string(r.direction.x) + ", " + std::to_string(r.direction.y) + ", " +
                  std::to_string(r.direction.z) + "; interval [" + std::to_string(r.tnear) + ", " +
                  std::to_string(r.tfar) + "]; time " + std::to_string(r.time) +
                  "): a component computed a non-finite or out-of-range ray");
    }
}

// Embree's packet types and calls of one width: 16 rays where the CPU
// runs Embree's AVX-512 kernels, else 8 (bench/embree_ceiling measures
// every width).
template <size_t N>
struct Packets {
  static_assert(N == 8 || N == 16);
  static constexpr bool kWide = N == 16;
  using RayHit = std::conditional_t<kWide, RTCRayHit16, RTCRayHit8>;
  using Ray = std::conditional_t<kWide, RTCRay16, RTCRay8>;
  static void Intersect(const int* valid, RTCScene scene, RTCIntersectContext* context, RayHit* packet) {
    if constexpr (kWide)
      rtcIntersect16(valid, scene, context, packet);
    else
      rtcIntersect8(valid, scene, context, packet);
  }
  static void Occluded(const int* valid, RTCScene scene, RTCIntersectContext* context, Ray* packet) {
    if constexpr (kWide)
      rtcOccluded16(valid, scene, context, packet);
    else
      rtcOccluded8(valid, scene, context, packet);
  }
};

// Loads rays [first, first + count) into a packet of N lanes (the unused
// lanes repeat the last ray, masked off by `valid`) and checks them there,
// lane by lane in one vectorisable pass; only a packet with a ray Embree
// cannot trace goes back to the rays to say which.
template <size_t N, typename Packet>
void LoadPacket(std::span<const Ray> rays, size_t first, size_t count, Packet& ray, int* valid) {
  for (size_t k = 0; k < N; ++k) {
    const Ray& r = rays[first + std::min(k, count - 1)];
    valid[k] = k < count ? -1 : 0;
    ray.org_x[k] = r.origin.x;
    ray.org_y[k] = r.origin.y;
    ray.org_z[k] = r.origin.z;
    ray.dir_x[k] = r.direction.x;
    ray.dir_y[k] = r.direction.y;
    ray.dir_z[k] = r.direction.z;
    ray.tnear[k] = r.tnear;
    ray.tfar[k] = r.tfar;
    ray.time[k] = r.time;
    ray.mask[k] = 0xFFFFFFFFu;
    ray.id[k] = 0;
    ray.flags[k] = 0;
  }
  uint32_t untraceable = 0;
  for (size_t k = 0; k < N; ++k)
    untraceable |= Untraceable(ray.org_x[k], ray.org_y[k], ray.org_z[k], ray.dir_x[k], ray.dir_y[k], ray.dir_z[k],
                               ray.tnear[k], ray.tfar[k], ray.time[k]);
  if (untraceable) [[unlikely]]
    CheckTraceable(rays, first, count);
}

RTCIntersectContext IncoherentContext() {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
  return context;
}

}  // namespace

bool KernelScene::Stopped() const { return stop_ && stop_->load(std::memory_order_relaxed); }

void KernelScene::ThrowIfStopped() const {
  if (Stopped()) throw Error("the job was stopped");
}

void KernelScene::Intersect(std::span<const Ray> rays, std::span<Hit> hits) const {
  ThrowIfStopped();
  if (wide_packets_)
    IntersectPackets<16>(rays, hits);
  else
    IntersectPackets<8>(rays, hits);
  closest_hit_rays_.fetch_add(rays.size(), std::memory_order_relaxed);
}

void KernelScene::Occluded(std::span<const Ray> rays, std::span<uint8_t> occluded) const {
  ThrowIfStopped();
  if (wide_packets_)
    OccludedPackets<16>(rays, occluded);
  else
    OccludedPackets<8>(rays, occluded);
  shadow_rays_.fetch_add(rays.size(), std::memory_order_relaxed);
}

template <size_t N>
void KernelScene::IntersectPackets(std::span<const Ray> rays, std::span<Hit> hits) const {
  RTCIntersectContext context = IncoherentContext();
  const RTCScene world = groups_[kWorld].scene;
  for (size_t first = 0; first < rays.size(); first += N) {
    const size_t count = std::min(N, rays.size() - first);
    alignas(64) typename Packets<N>::RayHit packet;
    alignas(64) int valid[N];
    LoadPacket<N>(rays, first, count, packet.ray, valid);
    for (size_t k = 0; k < N; ++k) {
      packet.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
      packet.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
    }
    Packets<N>::Intersect(valid, world, &context, &packet);
    for (size_t k = 0; k < count; ++k) {
      Hit& hit = hits[first + k];
      if (packet.hit.geomID[k] == RTC_INVALID_GEOMETRY_ID) {
        hit = Hit{};
        continue;
      }
      const uint32_t instance = packet.hit.instID[0][k];
      const bool placed = instance != RTC_INVALID_GEOMETRY_ID;
      hit.shape = geometry_base_[placed ? instance : packet.hit.geomID[k]] + (placed ? packet.hit.geomID[k] : 0);
      hit.primitive = packet.hit.primID[k];
      hit.t = packet.ray.tfar[k];
      const ShapeRecord& shape = shapes_[hit.shape];
      const bool sphere = shape.kind == Kind::kSphere;
      hit.b1 = sphere ? 0 : packet.hit.u[k];
      hit.b2 = sphere ? 0 : packet.hit.v[k];
      const Ray& ray = rays[first + k];
      const Vec3 position = ray.origin + ray.direction * hit.t;
      if (shape.kind == Kind::kCurves) {
        const Vec3 ng(packet.hit.Ng_x[k], packet.hit.Ng_y[k], packet.hit.Ng_z[k]);
        ShadeCurve(shape, ray.time, ng, -ray.direction, hit);
        continue;
      }
      hit.normal = Normal(shape, hit.primitive, position, ray.time);
      Shade(shape, position, ray.time, hit);
    }
  }
}

template <size_t N>
void KernelScene::OccludedPackets(std::span<const Ray> rays, std::span<uint8_t> occluded) const {
  RTCIntersectContext context = IncoherentContext();
  const RTCScene world = groups_[kWorld].scene;
  for (size_t first = 0; first < rays.size(); first += N) {
    const size_t count = std::min(N, rays.size() - first);
    alignas(64) typename Packets<N>::Ray packet;
    alignas(64) int valid[N];
    LoadPacket<N>(rays, first, count, packet, valid);
    Packets<N>::Occluded(valid, world, &context, &packet);
    for (size_t k = 0; k < count; ++k) occluded[first + k] = packet.tfar[k] < 0 ? 1 : 0;
  }
}

uint32_t KernelScene::PickLight(float u_choice, float& u_rest) const {
  // The first light whose running sum exceeds u_choice (upper_bound's
  // answer, a NaN going past every light), by halving without branches:
  // which half is taken is a coin toss per sample, too random for the
  // branch predictor.
  const float* cdf = light_cdf_.data();
  size_t first = 0, count = light_cdf_.size();
  while (count > 1) {
    const size_t half = count / 2;
    first = !(u_choice < cdf[first + half - 1]) ? first + half : first;
    count -= half;
  }
  const uint32_t index = uint32_t(std::min(first + (!(u_choice < cdf[first]) ? 1 : 0), light_cdf_.size() - 1));
  const Light& light = lights_[index];
  const float below = light_cdf_[index] - light.probability;
  u_rest = light.probability > 0 ? std::clamp((u_choice - below) / light.probability, 0.0f, 0x1.fffffep-1f) : 0.0f;
  return index;
}

void KernelScene::BuildLightBvh() {
  // Bounds of every light with a place; each light's power keeps a
  // hundredth of the mean, as ChooseLightsByPower's shares do.
  double total = 0;
  for (const Light& light : lights_) total += light.power;
  const float floor = lights_.empty() ? 0.0f : float(0.01 * total / double(lights_.size()));
  std::vector<LightBounds> bounds(lights_.size());
  infinite_lights_.clear();
  for (uint32_t l = 0; l < lights_.size(); ++l) {
    const Light& light = lights_[l];
    LightBounds& b = bounds[l];
    b.phi = light.power + (floor > 0 ? floor : 1.0f);
    switch (light.kind) {
      case LightKind::kDirectional:
      case LightKind::kEnvironment:
        infinite_lights_.push_back(l);
        b.phi = 0;  // not in the BVH
        break;
      case LightKind::kPoint:
        // Its emitter may be a spot: every direction, conservatively.
        b.lower = b.upper = light.position;
        break;
      case LightKind::kSurface:
        light.surface->Bounds(b.lower, b.upper);
        // The cone of the surface's normals; an emitter may shine from
        // both sides (two_sided), so the bound is.
        if (!light.surface->NormalCone(b.w, b.cos_theta_o)) b.w = Vec3(0, 0, 1), b.cos_theta_o = -1;
        break;
    }
  }
  light_bvh_ = LightBvh(bounds);
  const float slots = float(infinite_lights_.size()) + (light_bvh_.Empty() ? 0.0f : 1.0f);
  infinite_probability_ = slots > 0 ? float(infinite_lights_.size()) / slots : 0.0f;
}

uint32_t KernelScene::PickLightFor(Vec3 p, float u_choice, float& u_rest, float& probability) const {
  if (light_choice_ != LightChoice::kBvh) {
    const uint32_t index = PickLight(u_choice, u_rest);
    probability = lights_[index].probability;
    return index;
  }
  // The lights at infinity, evenly, with the BVH as one more choice.
  if (u_choice < infinite_probability_) {
    const size_t count = infinite_lights_.size();
    const float scaled = u_choice / infinite_probability_ * float(count);
    const size_t pick = std::min(size_t(scaled), count - 1);
    u_rest = std::clamp(scaled - float(pick), 0.0f, 0x1.fffffep-1f);
    probability = infinite_probability_ / float(count);
    return infinite_lights_[pick];
  }
  const float u = std::clamp((u_choice - infinite_probability_) / (1 - infinite_probability_), 0.0f, 0x1.fffffep-1f);
  const auto picked = light_bvh_.Sample(p, u, u_rest);
  if (!picked) return kNoLight;
  probability = (1 - infinite_probability_) * picked->second;
  return picked->first;
}

float KernelScene::ProbabilityFrom(uint32_t light, Vec3 p) const {
  if (light_choice_ != LightChoice::kBvh) return lights_[light].probability;
  const LightKind kind = lights_[light].kind;
  if (kind == LightKind::kDirectional || kind == LightKind::kEnvironment)
    return infinite_probability_ / float(infinite_lights_.size());
  return (1 - infinite_probability_) * light_bvh_.Pmf(p, light);
}

LightSample KernelScene::PointOnSurfaceLight(const Light& light, float u_primitive, float u0, float u1) const {
  const float u[3] = {u_primitive, u0, u1};
  SurfaceSample at;
  light.surface->Sample(u, {&at, 1});
  LightSample s;
  s.emitter = light.emitter;
  s.shape = light.shape;
  s.pdf = shape_light_pdf_[light.shape];
  s.position = at.position;
  s.normal = at.normal;
  s.u = at.u, s.v = at.v;
  return s;
}

LightSample KernelScene::SampleLight(float u_choice, float u0, float u1) const {
  if (lights_.empty()) return {};
  float u_primitive = 0;
  const Light& light = lights_[PickLight(u_choice, u_primitive)];
  LightSample s;
  switch (light.kind) {
    case LightKind::kSurface:
      return PointOnSurfaceLight(light, u_primitive, u0, u1);
    case LightKind::kPoint:
      s.position = light.position;
      s.normal = light.axis;
      s.delta_position = true;
      break;
    case LightKind::kDirectional:
    case LightKind::kEnvironment:
      s.infinite = true;
      s.delta_direction = light.kind == LightKind::kDirectional;
      s.frame = light.frame;
      s.normal = light.frame.n;
      break;
  }
  s.emitter = light.emitter;
  s.pdf = light.probability;
  return s;
}

Vec3 KernelScene::InfiniteLightOrigin(Vec3 d, float u0, float u1, float& pdf_area) const {
  const auto [x, y] = SampleConcentricDisk(u0, u1);
  const Frame disk(d);
  pdf_area = 1 / (kPi * bounds_radius_ * bounds_radius_);
  return bounds_center_ + (disk.s * x + disk.t * y - d) * bounds_radius_;
}

namespace {

// A finite light's point seen from p: the direction, distance and local
// direction toward p; the density is the caller's. False when p is the
// point itself.
bool AimAt(LightDirection& s, Vec3 p) {
  const Vec3 d = s.position - p;
  s.distance = Length(d);
  if (!(s.distance > 0)) return false;
  s.direction = d / s.distance;
  s.w = Frame(s.normal).ToLocal(-s.direction);
  return true;
}

}  // namespace

void KernelScene::SampleLightsFrom(std::span<const Vec3> points, std::span<const float> uniform,
                                   std::span<LightDirection> out) const {
  const size_t n = points.size();
  std::fill_n(out.begin(), n, LightDirection{});
  if (lights_.empty()) return;
  // Each point's light. Surface lights are sampled afterwards, all of a
  // light's points in one call; the rest here.
  std::vector<uint32_t> from_environment, on_surface;
  std::vector<uint32_t> picked(n);
  std::vector<float> probability(n), u_primitive(n);
  for (size_t k = 0; k < n; ++k) {
    LightDirection& s = out[k];
    const Vec3 p = points[k];
    picked[k] = PickLightFor(p, uniform[3 * k], u_primitive[k], probability[k]);
    if (picked[k] == kNoLight) continue;
    const Light& light = lights_[picked[k]];
    s.emitter = light.emitter;
    switch (light.kind) {
      case LightKind::kEnvironment:
        from_environment.push_back(uint32_t(k));
        s.pdf = probability[k];  // times the direction's density below
        break;
      case LightKind::kDirectional:
        s.direction = -light.frame.n;
        s.distance = kInfinity;
        s.pdf = probability[k];
        s.delta = true;
        s.w = Vec3(0, 0, 1);
        break;
      case LightKind::kPoint:
        s.position = light.position;
        s.normal = light.axis;
        s.delta = true;
        if (!AimAt(s, p)) {
          s.emitter = nullptr;
          break;
        }
        s.pdf = probability[k] * s.distance * s.distance;
        break;
      case LightKind::kSurface:
        on_surface.push_back(uint32_t(k));
        break;
    }
  }
  SampleSurfaceLights(points, uniform, picked, probability, u_primitive, on_surface, out);
  if (!from_environment.empty()) SampleEnvironment(uniform, from_environment, out);
}

void KernelScene::SampleSurfaceLights(std::span<const Vec3> points, std::span<const float> uniform,
                                      std::span<const uint32_t> picked, std::span<const float> probability,
                                      std::span<const float> u_primitive, std::span<const uint32_t> on_surface,
                                      std::span<LightDirection> out) const {
  std::vector<uint32_t> light_of(on_surface.size());
  for (size_t j = 0; j < on_surface.size(); ++j) light_of[j] = picked[on_surface[j]];
  // Each light's points in one call to its surface's own sampler, by solid
  // angle where it can.
  for (const auto& [index, members] : GroupBy(light_of)) {
    const size_t m = members.size();
    std::vector<Vec3> from(m);
    std::vector<float> u(3 * m);
    std::vector<SurfaceSample> at(m);
    for (size_t j = 0; j < m; ++j) {
      const uint32_t k = on_surface[members[j]];
      from[j] = points[k];
      u[3 * j] = u_primitive[k];
      u[3 * j + 1] = uniform[3 * k + 1];
      u[3 * j + 2] = uniform[3 * k + 2];
    }
    lights_[index].surface->Sample(from, u, at);
    for (size_t j = 0; j < m; ++j) {
      const uint32_t k = on_surface[members[j]];
      LightDirection& s = out[k];
      s.position = at[j].position;
      s.normal = at[j].normal;
      s.shape = lights_[index].shape;
      s.u = at[j].u, s.v = at[j].v;
      // Density per solid angle.
      const float pdf = probability[k] * at[j].pdf;
      if (!(pdf > 0) || !AimAt(s, points[k])) {
        s.emitter = nullptr;
        continue;
      }
      s.pdf = pdf;
    }
  }
}

void KernelScene::SampleEnvironment(std::span<const float> uniform, std::span<const uint32_t> from_environment,
                                    std::span<LightDirection> out) const {
  const Light& environment = lights_[environment_];
  const size_t m = from_environment.size();
  std::vector<float> u(2 * m), w(3 * m), pdf(m);
  for (size_t j = 0; j < m; ++j) {
    u[2 * j] = uniform[3 * from_environment[j] + 1];
    u[2 * j + 1] = uniform[3 * from_environment[j] + 2];
  }
  environment.emitter->SampleDirection(u, w, pdf);
  for (size_t j = 0; j < m; ++j) {
    LightDirection& s = out[from_environment[j]];
    s.w = Vec3::Load(&w[3 * j]);
    s.direction = -Normalize(environment.frame.ToWorld(s.w));
    s.distance = kInfinity;
    s.pdf = std::isfinite(pdf[j]) ? s.pdf * pdf[j] : 0.0f;
  }
}

float KernelScene::LightPdfFrom(const Ray& ray, const Hit& hit) const {
  if (!hit.Found() || hit.shape >= shape_light_.size() || shape_light_[hit.shape] == kNoLight) return 0;
  const Light& light = lights_[shape_light_[hit.shape]];
  SurfaceSample at;
  at.position = ray.origin + ray.direction * hit.t;
  at.normal = hit.normal;
  at.primitive = hit.primitive;
  float pdf = 0;
  light.surface->Pdf({&ray.origin, 1}, {&at, 1}, {&pdf, 1});
  return ProbabilityFrom(shape_light_[hit.shape], ray.origin) * pdf;
}

void KernelScene::Escaped(std::span<const Vec3> directions, std::span<Vec3> radiance, std::span<float> pdf) const {
  const size_t n = directions.size();
  std::fill_n(radiance.begin(), n, Vec3());
  std::fill_n(pdf.begin(), n, 0.0f);
  if (environment_ == kNoLight || n == 0) return;
  const Light& environment = lights_[environment_];
  std::vector<float> w(3 * n), rgb(3 * n), uv(2 * n);
  for (size_t k = 0; k < n; ++k) environment.frame.ToLocal(-directions[k]).Store(&w[3 * k]);
  SurfacePoints points;
  points.uv = uv;
  environment.emitter->Radiance(w, points, rgb);
  environment.emitter->PdfDirection(w, pdf.first(n));
  for (size_t k = 0; k < n; ++k) {
    radiance[k] = Vec3::Load(&rgb[3 * k]);
    pdf[k] = std::isfinite(pdf[k]) ? pdf[k] * ProbabilityFrom(environment_, Vec3()) : 0.0f;
  }
}

LightDirection KernelScene::LightPoint(uint32_t index, Vec3 seen_from) const {
  const Light& light = lights_[index];
  LightDirection s;
  float gathered_area = 0;
  switch (light.kind) {
    case LightKind::kEnvironment:
      return s;
    case LightKind::kDirectional:
      s.emitter = light.emitter;
      s.direction = -light.frame.n;
      s.distance = kInfinity;
      s.pdf = 1;
      s.delta = true;
      s.w = Vec3(0, 0, 1);
      return s;
    case LightKind::kPoint:
      s.position = light.position;
      s.normal = light.axis;
      s.delta = true;
      break;
    case LightKind::kSurface: {
      const SurfaceSample at = light.surface->Gathered(seen_from, gathered_area);
      s.shape = light.shape;
      s.position = at.position;
      s.normal = at.normal;
      s.u = at.u, s.v = at.v;
      break;
    }
  }
  s.emitter = light.emitter;
  if (!AimAt(s, seen_from)) return LightDirection{};
  const float d2 = s.distance * s.distance;
  if (s.delta) {
    s.pdf = d2;
    return s;
  }
  // As if the light's whole area (a sphere: its cross-section) emitted here.
  const float cos_light = std::abs(s.w.z);
  s.pdf = cos_light > 0 ? d2 / (gathered_area * cos_light) : 0.0f;
  return s;
}

bool KernelScene::ConnectToCamera(Vec3 p, float lens_u, float lens_v, CameraConnection& out) const {
  float x = 0, y = 0;
  if (!camera_.Connect(p, lens_u, lens_v, &out.lens_point, &x, &y, &out.importance)) return false;
  out.axis = camera_.axis();
  out.raster_x = x * float(width_);
  out.raster_y = y * float(height_);
  return true;
}

}  // namespace yarf
