#include "kernel/scene.h"

#include <algorithm>
#include <cmath>

#include "yarf/error.h"
#include "yarf/warps.h"

namespace yarf {
namespace {

// What the environment's sphere is made of: it absorbs everything.
class Absorber final : public SurfaceModel {
 public:
  void Evaluate(TransportMode, std::span<const float> wi, std::span<const float>, const SurfacePoints&,
                std::span<float> value) const override {
    std::fill(value.begin(), value.begin() + wi.size(), 0.0f);
  }
  void Sample(TransportMode, std::span<const float> wi, const SurfacePoints&, std::span<const float>, uint32_t,
              std::span<float> wo, std::span<float> weight, std::span<float> pdf,
              std::span<uint32_t> flags) const override {
    const size_t n = wi.size() / 3;
    std::fill(wo.begin(), wo.begin() + 3 * n, 0.0f);
    std::fill(weight.begin(), weight.begin() + 3 * n, 0.0f);
    std::fill(pdf.begin(), pdf.begin() + n, 0.0f);
    std::fill(flags.begin(), flags.begin() + n, kScatterNone);
  }
  void Pdf(std::span<const float> wi, std::span<const float>, const SurfacePoints&,
           std::span<float> pdf) const override {
    std::fill(pdf.begin(), pdf.begin() + wi.size() / 3, 0.0f);
  }
  uint32_t Lobes() const override { return kScatterReflect | kScatterDiffuse; }
};

// A directional light as a spot light at `distance`, aimed at the scene:
// intensity E·distance² inside the cone that holds the scene, nothing out.
class FarSpotLight final : public Emitter {
 public:
  FarSpotLight(const Emitter& irradiance, float distance, float cos_cone)
      : irradiance_(irradiance), scale_(distance * distance), cos_cone_(cos_cone) {}

  void Radiance(std::span<const float> w, const SurfacePoints& at, std::span<float> radiance) const override {
    irradiance_.Radiance(w, at, radiance);
    for (size_t k = 0; k < w.size() / 3; ++k)
      for (int c = 0; c < 3; ++c) radiance[3 * k + c] *= w[3 * k + 2] >= cos_cone_ ? scale_ : 0.0f;
  }
  void SampleDirection(std::span<const float> uniform, std::span<float> w, std::span<float> pdf) const override {
    for (size_t k = 0; k < uniform.size() / 2; ++k) {
      SampleUniformCone(uniform[2 * k], uniform[2 * k + 1], cos_cone_).Store(&w[3 * k]);
      pdf[k] = UniformConePdf(1.0f, cos_cone_);
    }
  }
  void PdfDirection(std::span<const float> w, std::span<float> pdf) const override {
    for (size_t k = 0; k < w.size() / 3; ++k) pdf[k] = UniformConePdf(w[3 * k + 2], cos_cone_);
  }

 private:
  const Emitter& irradiance_;
  float scale_, cos_cone_;
};

// How far a directional light stands, in scene radii.
constexpr float kDirectionalDistance = 1000;

}  // namespace

KernelScene::KernelScene(const EmbreeDevice& device, const Camera& camera, uint32_t width,
                         uint32_t height)
    : device_(device), camera_(camera), width_(width), height_(height) {
  groups_.push_back({rtcNewScene(device.get()), {}});  // kWorld
}

KernelScene::~KernelScene() {
  for (Group& g : groups_) rtcReleaseScene(g.scene);
}

uint32_t KernelScene::AddMaterial(std::shared_ptr<const SurfaceModel> material) {
  materials_.push_back(std::move(material));
  return uint32_t(materials_.size() - 1);
}

const Emitter* KernelScene::AddEmitter(std::unique_ptr<Emitter> emitter) {
  emitters_.push_back(std::move(emitter));
  return emitters_.back().get();
}

uint32_t KernelScene::NewGroup() {
  groups_.push_back({rtcNewScene(device_.get()), {}});
  return uint32_t(groups_.size() - 1);
}

void KernelScene::AddMesh(uint32_t group, TriangleMesh mesh, const ShapeLook& look) {
  DropFaceNormals(mesh);
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
  rtcAttachGeometry(groups_[group].scene, geom);
  rtcReleaseGeometry(geom);

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
    // With vertex normals, the face's side is theirs (as pbrt-v4): the
    // winding of a smooth mesh's triangles need not agree with them.
    if (!mesh.normals.empty() && Dot(normals[t], mesh.normals[v[0]] + mesh.normals[v[1]] + mesh.normals[v[2]]) < 0)
      normals[t] = -normals[t];
    if (look.flip_normals) normals[t] = -normals[t];
  }
  face_normals_.push_back(std::move(normals));
  meshes_.push_back(std::move(mesh));
  groups_[group].shapes.push_back(record);
}

void KernelScene::AddSphere(uint32_t group, Vec3 center, float radius, const ShapeLook& look,
                            const std::array<Vec3, 3>& axes) {
  RTCGeometry geom = rtcNewGeometry(device_.get(), RTC_GEOMETRY_TYPE_SPHERE_POINT);
  auto* point = static_cast<float*>(rtcSetNewGeometryBuffer(
      geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float), 1));
  point[0] = center.x;
  point[1] = center.y;
  point[2] = center.z;
  point[3] = radius;
  rtcCommitGeometry(geom);
  rtcAttachGeometry(groups_[group].scene, geom);
  rtcReleaseGeometry(geom);

  ShapeRecord record;
  record.kind = Kind::kSphere;
  record.center = center;
  record.radius = radius;
  record.axes = axes;
  record.look = look;
  groups_[group].shapes.push_back(record);
}

void KernelScene::AddPlacement(uint32_t group, const Transform& to_world,
                               const std::optional<Transform>& to_world_end) {
  placements_.push_back({group, to_world, to_world_end});
}

void KernelScene::AddDirectionalLight(const Emitter* emitter, Vec3 direction) {
  directional_.emplace_back(emitter, Normalize(direction));
}

void KernelScene::AddEnvironment(const Emitter* emitter) { environments_.push_back(emitter); }

void KernelScene::AddInfiniteLights() {
  if (directional_.empty() && environments_.empty()) return;
  RTCBounds box;
  rtcGetSceneBounds(groups_[kWorld].scene, &box);
  Vec3 lower(box.lower_x, box.lower_y, box.lower_z), upper(box.upper_x, box.upper_y, box.upper_z);
  const Vec3 eye = camera_.origin();
  if (!(lower.x <= upper.x)) lower = upper = eye;  // an empty scene
  const Vec3 center = (lower + upper) * 0.5f;
  const float radius = std::max({Length(upper - center), Length(eye - center), 1e-3f});
  for (const auto& [emitter, direction] : directional_) {
    const float distance = kDirectionalDistance * radius;
    emitters_.push_back(std::make_unique<FarSpotLight>(
        *emitter, distance, std::sqrt(1 - 1 / (kDirectionalDistance * kDirectionalDistance))));
    Light light;
    light.first = light.end = uint32_t(emitting_.size());
    light.emitter = emitters_.back().get();
    light.position = center - direction * distance;
    light.axis = direction;
    lights_.push_back(light);
  }
  for (const Emitter* emitter : environments_) {
    // Twice the radius: rays leaving the scene's surfaces never start
    // outside it.
    const float sphere_radius = 2 * radius;
    RTCGeometry geom = rtcNewGeometry(device_.get(), RTC_GEOMETRY_TYPE_SPHERE_POINT);
    auto* point = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4,
                                                              4 * sizeof(float), 1));
    center.Store(point);
    point[3] = sphere_radius;
    rtcCommitGeometry(geom);
    const uint32_t id = rtcAttachGeometry(groups_[kWorld].scene, geom);
    rtcReleaseGeometry(geom);
    if (id != geometry_base_.size()) throw Error("environment light: unexpected Embree geometry id");
    ShapeRecord record;
    record.kind = Kind::kSphere;
    record.center = center;
    record.radius = sphere_radius;
    record.look.name = "environment";
    record.look.material = AddMaterial(std::make_unique<Absorber>());
    record.look.emitter = emitter;
    record.look.flip_normals = true;  // emitting inward
    geometry_base_.push_back(uint32_t(shapes_.size()));
    shapes_.push_back(record);
  }
  Build(groups_[kWorld].scene);
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

void KernelScene::AddLight(const Emitter* emitter, const Transform& to_world) {
  Light light;
  light.first = light.end = uint32_t(emitting_.size());
  light.emitter = emitter;
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
    rtcAttachGeometry(groups_[kWorld].scene, geom);
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
  AddInfiniteLights();

  // Surface lights follow the point lights already added, one per
  // emitting shape placement.
  shape_light_pdf_.assign(shapes_.size(), 0.0f);
  const size_t point_lights = lights_.size();
  for (uint32_t id = 0; id < shapes_.size(); ++id) {
    const ShapeRecord& s = shapes_[id];
    if (!s.look.emitter) continue;
    if (s.moving) throw Error("shape '" + s.look.name + "' moves and emits: moving lights are not supported");
    Light light;
    light.first = uint32_t(emitting_.size());
    light.emitter = s.look.emitter;
    const uint32_t count = s.kind == Kind::kSphere ? 1 : uint32_t(meshes_[s.mesh].TriangleCount());
    for (uint32_t p = 0; p < count; ++p) {
      EmittingPrimitive e{id, p, s.kind == Kind::kSphere, {}, {}, {}, 0, {}, 0};
      if (e.sphere) {
        e.p0 = s.placed ? s.to_world.Point(s.center) : s.center;
        e.radius = s.radius * (s.placed ? float(std::cbrt(std::abs(s.to_world.Determinant3()))) : 1.0f);
      } else {
        Vec3 v[3];
        Triangle(s, p, v);
        e.p0 = v[0], e.p1 = v[1], e.p2 = v[2];
        e.normal = Normal(s, p, v[0], 0);
      }
      const float area = PrimitiveArea(s, p);
      light.area += area;
      light.position += (e.sphere ? e.p0 : (e.p0 + e.p1 + e.p2) / 3.0f) * area;
      light.axis += e.normal * area;
      e.cdf = light.area;
      emitting_.push_back(e);
    }
    light.end = uint32_t(emitting_.size());
    if (!(light.area > 0)) continue;
    light.position = light.position / light.area;
    light.axis = Length(light.axis) > 0 ? Normalize(light.axis) : emitting_[light.first].normal;
    lights_.push_back(light);
  }
  for (size_t l = point_lights; l < lights_.size(); ++l)
    shape_light_pdf_[emitting_[lights_[l].first].shape] = 1.0f / (float(lights_.size()) * lights_[l].area);
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
  return record.kind == Kind::kSphere ? 1 : uint32_t(meshes_[record.mesh].TriangleCount());
}

bool KernelScene::Triangle(uint32_t shape, uint32_t primitive, Vec3 corners[3]) const {
  const ShapeRecord& record = shapes_[shape];
  if (record.kind == Kind::kSphere) return false;
  Triangle(record, primitive, corners);
  return true;
}

float KernelScene::PrimitiveArea(const ShapeRecord& shape, uint32_t primitive) const {
  if (shape.kind == Kind::kSphere) {
    // Spheres are placed by similarity transforms: scale by the cube root
    // of the determinant.
    const float scale = shape.placed ? float(std::cbrt(std::abs(shape.to_world.Determinant3()))) : 1;
    const float r = shape.radius * scale;
    return 4 * kPi * r * r;
  }
  Vec3 v[3];
  Triangle(shape, primitive, v);
  return 0.5f * Length(Cross(v[1] - v[0], v[2] - v[0]));
}

Transform KernelScene::PlacementAt(const ShapeRecord& shape, float time) {
  Transform to_world = shape.to_world;
  if (shape.moving)
    for (int i = 0; i < 16; ++i) to_world.m[i] += time * (shape.to_world_end.m[i] - to_world.m[i]);
  return to_world;
}

Vec3 KernelScene::Normal(const ShapeRecord& shape, uint32_t primitive, Vec3 position,
                         float time) const {
  const Transform to_world = PlacementAt(shape, time);
  if (shape.kind == Kind::kTriangles) {
    const Vec3 n = face_normals_[shape.mesh][primitive];  // flipped already
    return shape.placed ? Normalize(to_world.Normal(n)) : n;
  }
  const Vec3 center = shape.placed ? to_world.Point(shape.center) : shape.center;
  const Vec3 n = Normalize(position - center);
  return shape.look.flip_normals ? -n : n;
}

void KernelScene::SphereParameters(const ShapeRecord& shape, Vec3 d, float r, Hit& hit) {
  // Mitsuba's parameterisation in the sphere's own frame: u = φ/2π from
  // its x axis, v = θ/π from its z axis.
  const Vec3 local(Dot(d, shape.axes[0]), Dot(d, shape.axes[1]), Dot(d, shape.axes[2]));
  float phi = std::atan2(local.y, local.x);
  if (phi < 0) phi += 2 * kPi;
  const float cos_theta = std::clamp(local.z, -1.0f, 1.0f), sin_theta = std::sqrt(1 - cos_theta * cos_theta);
  hit.u = phi * (0.5f * kInvPi);
  hit.v = std::acos(cos_theta) * kInvPi;
  const Vec3 along_phi = shape.axes[0] * (-local.y) + shape.axes[1] * local.x;
  const Vec3 along_theta = shape.axes[0] * (cos_theta * std::cos(phi)) + shape.axes[1] * (cos_theta * std::sin(phi)) -
                           shape.axes[2] * sin_theta;
  hit.dpdu = along_phi * (2 * kPi * r);
  hit.dpdv = along_theta * (kPi * r);
}

void KernelScene::Shade(const ShapeRecord& shape, Vec3 position, float time, Hit& hit) const {
  hit.shading_normal = hit.normal;
  hit.parameterised = shape.kind == Kind::kSphere;
  if (shape.kind == Kind::kSphere) {
    const Vec3 center = shape.placed ? shape.to_world.Point(shape.center) : shape.center;
    const float r = Length(position - center);
    SphereParameters(shape, r > 0 ? (position - center) / r : shape.axes[2], r, hit);
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

// Rays go to Embree eight at a time: its 8-wide packet kernels are the
// fastest on incoherent rays here (bench/embree_ceiling measures them all).
constexpr size_t kPacket = 8;

// Embree asserts (and so aborts the server) on a ray outside its valid
// range: coordinates beyond ~1.8e18, NaNs, a NaN interval.
bool Traceable(const Ray& r) {
  constexpr float kLargest = 1e18f;
  const auto in_range = [](Vec3 v) {
    return std::abs(v.x) <= kLargest && std::abs(v.y) <= kLargest && std::abs(v.z) <= kLargest;
  };
  return in_range(r.origin) && in_range(r.direction) && r.tnear >= 0 && r.tnear <= kInfinity &&
         !std::isnan(r.tfar) && r.time >= 0 && r.time <= 1;
}

// Rays a component made are untrusted: one that Embree cannot trace fails
// the job, never the server.
void CheckTraceable(std::span<const Ray> rays, size_t first, size_t count) {
  for (size_t k = first; k < first + count; ++k)
    if (!Traceable(rays[k])) [[unlikely]] {
      const Ray& r = rays[k];
      throw Error("a ray Embree cannot trace (origin " + std::to_string(r.origin.x) + ", " +
                  std::to_string(r.origin.y) + ", " + std::to_string(r.origin.z) + "; direction " +
                  std::to_string(r.direction.x) + ", " + std::to_string(r.direction.y) + ", " +
                  std::to_string(r.direction.z) + "; interval [" + std::to_string(r.tnear) + ", " +
                  std::to_string(r.tfar) + "]; time " + std::to_string(r.time) +
                  "): a component computed a non-finite or out-of-range ray");
    }
}

template <typename Packet>
void LoadPacket(std::span<const Ray> rays, size_t first, size_t count, Packet& ray, int* valid) {
  CheckTraceable(rays, first, count);
  for (size_t k = 0; k < kPacket; ++k) {
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
  RTCIntersectContext context = IncoherentContext();
  const RTCScene world = groups_[kWorld].scene;
  for (size_t first = 0; first < rays.size(); first += kPacket) {
    const size_t count = std::min(kPacket, rays.size() - first);
    alignas(32) RTCRayHit8 packet;
    alignas(32) int valid[kPacket];
    LoadPacket(rays, first, count, packet.ray, valid);
    for (size_t k = 0; k < kPacket; ++k) {
      packet.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
      packet.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
    }
    rtcIntersect8(valid, world, &context, &packet);
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
      hit.normal = Normal(shape, hit.primitive, position, ray.time);
      Shade(shape, position, ray.time, hit);
    }
  }
  closest_hit_rays_.fetch_add(rays.size(), std::memory_order_relaxed);
}

void KernelScene::Occluded(std::span<const Ray> rays, std::span<uint8_t> occluded) const {
  ThrowIfStopped();
  RTCIntersectContext context = IncoherentContext();
  const RTCScene world = groups_[kWorld].scene;
  for (size_t first = 0; first < rays.size(); first += kPacket) {
    const size_t count = std::min(kPacket, rays.size() - first);
    alignas(32) RTCRay8 packet;
    alignas(32) int valid[kPacket];
    LoadPacket(rays, first, count, packet, valid);
    rtcOccluded8(valid, world, &context, &packet);
    for (size_t k = 0; k < count; ++k) occluded[first + k] = packet.tfar[k] < 0 ? 1 : 0;
  }
  shadow_rays_.fetch_add(rays.size(), std::memory_order_relaxed);
}

LightSample KernelScene::SampleLight(float u_choice, float u0, float u1) const {
  LightSample s;
  if (lights_.empty()) return s;
  // One number chooses the light and, rescaled, the primitive within it.
  const float scaled = u_choice * float(lights_.size());
  const size_t index = std::min(size_t(scaled), lights_.size() - 1);
  const float u_primitive = std::min(scaled - float(index), 0x1.fffffep-1f);
  const Light& light = lights_[index];
  s.emitter = light.emitter;
  if (light.first == light.end) {
    s.position = light.position;
    s.normal = light.axis;
    s.pdf = 1.0f / float(lights_.size());
    s.delta_position = true;
    return s;
  }
  const auto begin = emitting_.begin() + light.first, end = emitting_.begin() + light.end;
  const auto it = std::upper_bound(begin, end, u_primitive * light.area,
                                   [](float target, const EmittingPrimitive& e) { return target < e.cdf; });
  const EmittingPrimitive& e = it == end ? *(end - 1) : *it;
  s.shape = e.shape;
  s.pdf = shape_light_pdf_[e.shape];
  if (e.sphere) {
    const Vec3 d = SampleUniformSphere(u0, u1);
    s.position = e.p0 + d * e.radius;
    s.normal = shapes_[e.shape].look.flip_normals ? -d : d;
    Hit at;
    SphereParameters(shapes_[e.shape], d, e.radius, at);
    s.u = at.u, s.v = at.v;
    return s;
  }
  const auto b = SampleUniformTriangle(u0, u1);
  s.position = e.p0 * b[0] + e.p1 * b[1] + e.p2 * (1 - b[0] - b[1]);
  float uv[2];
  const TriangleMesh& mesh = meshes_[shapes_[e.shape].mesh];
  TriangleUvAt(mesh.indices, mesh.uvs, e.primitive, b[1], 1 - b[0] - b[1], uv);
  s.u = uv[0], s.v = uv[1];
  s.normal = e.normal;
  return s;
}

LightSample KernelScene::LightPoint(uint32_t index, Vec3 seen_from) const {
  const Light& light = lights_[index];
  LightSample s;
  s.emitter = light.emitter;
  if (light.first == light.end) {
    s.position = light.position;
    s.normal = light.axis;
    s.pdf = 1;
    s.delta_position = true;
    return s;
  }
  const EmittingPrimitive& first = emitting_[light.first];
  s.shape = first.shape;
  if (first.sphere) {
    const Vec3 to = seen_from - first.p0;
    const Vec3 d = Length(to) > 0 ? Normalize(to) : Vec3(0, 0, 1);
    s.position = first.p0 + d * first.radius;
    s.normal = shapes_[first.shape].look.flip_normals ? -d : d;
    s.pdf = 1 / (kPi * first.radius * first.radius);
    return s;
  }
  s.position = light.position;
  s.normal = light.axis;
  s.pdf = 1 / light.area;
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
