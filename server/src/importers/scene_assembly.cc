#include "importers/scene_assembly.h"

#include <cmath>
#include <functional>

#include "importers/properties_util.h"

namespace yarf::importers {
namespace {

void CheckTransform(const Matrix4& m, const SourceLocation& where, const std::string& what) {
  if (!m.IsFinite()) Fail(where, what + ": transform has non-finite values");
  if (!(std::abs(m.Determinant3()) > 1e-30)) Fail(where, what + ": transform is singular");
}

void SetTransform(const Matrix4& m, v1::Transform* out, std::function<void()> clear) {
  if (m.IsIdentity())
    clear();
  else
    *out = m.ToProto();
}

// yarf computes a mesh's normal from its winding after to_world (or from
// its vertex normals, when it has them); decide how to turn it so that it
// matches the source renderer's: the user's flip, and the winding's when
// the placement reverses it.
struct YarfSide {
  bool flip_normals, flip_winding;
};
YarfSide SideOf(bool flip, NormalRule rule, const Matrix4& to_world, bool mirrored_world) {
  switch (rule) {
    case NormalRule::kWorldWinding:
      return {flip, mirrored_world};
    case NormalRule::kTransformed:
      return {flip, to_world.Determinant3() < 0};
    case NormalRule::kSphere:
      break;
  }
  return {flip, false};
}
void SetSide(v1::SceneShape& shape, const YarfSide& side) {
  shape.set_flip_normals(side.flip_normals);
  shape.set_flip_winding(side.flip_winding);
}

// A rotation taking +z to the unit vector `z`.
Matrix4 FrameAlong(const Vec3d& z) {
  const Vec3d up = std::abs(z.y) < 0.9 ? Vec3d{0, 1, 0} : Vec3d{1, 0, 0};
  return *Matrix4::LookAt({0, 0, 0}, z, up);
}

}  // namespace

std::string SceneAssembly::UniqueName(std::set<std::string>& taken, const std::string& name) {
  std::string unique = name.empty() ? "unnamed" : name;
  for (int k = 2; taken.count(unique); ++k) unique = name + "-" + std::to_string(k);
  taken.insert(unique);
  return unique;
}

std::string SceneAssembly::DefaultMaterial() {
  if (default_material_.empty()) {
    v1::Properties p;
    auto& rgb = *(*p.mutable_values())["reflectance"].mutable_rgb_value();
    rgb.set_r(0.5), rgb.set_g(0.5), rgb.set_b(0.5);
    default_material_ = AddMaterial("default", "lambertian", std::move(p));
  }
  return default_material_;
}

std::string SceneAssembly::AddMaterial(const std::string& name, const std::string& class_name,
                                       v1::Properties properties) {
  v1::Material& m = *scene_.add_materials();
  m.set_name(UniqueName(material_names_, name));
  m.set_class_name(class_name);
  *m.mutable_properties() = std::move(properties);
  return m.name();
}

std::string SceneAssembly::AddTexture(const std::string& name, v1::ComponentSpec texture,
                                      const std::optional<Matrix4>& texture_to_world) {
  v1::SceneTexture& t = *scene_.add_textures();
  t.set_name(UniqueName(texture_names_, name));
  *t.mutable_texture() = std::move(texture);
  texture_transforms_.push_back(texture_to_world);
  return t.name();
}

std::string SceneAssembly::NullMaterial() {
  if (null_material_.empty()) null_material_ = AddMaterial("null", "null", {});
  return null_material_;
}

std::string SceneAssembly::AddMedium(const std::string& name, v1::ComponentSpec medium,
                                     const std::optional<Matrix4>& to_world, const SourceLocation& where) {
  if (to_world) CheckTransform(*to_world, where, "medium");
  v1::SceneMedium& m = *scene_.add_media();
  m.set_name(UniqueName(medium_names_, name.empty() ? "medium" : name));
  *m.mutable_medium() = std::move(medium);
  medium_transforms_.push_back(to_world);
  return m.name();
}

v1::Mesh SceneAssembly::Made(v1::Mesh mesh, const SourceLocation& where) {
  made_triangles_ += uint64_t(mesh.indices_size()) / 3;
  if (made_triangles_ > kMaxMadeTriangles)
    Fail(where, "the disks, cylinders and patches made into triangles pass " + std::to_string(kMaxMadeTriangles) +
                    " triangles in all");
  return mesh;
}

void SceneAssembly::AddShape(v1::SceneShape shape, const Matrix4& to_world, bool flip, NormalRule rule,
                             const SourceLocation& where, const std::string& group) {
  CheckTransform(to_world, where, "shape");
  if (group.empty()) {
    world_shapes_.push_back({to_world, flip, rule});
    *scene_.add_shapes() = std::move(shape);
    return;
  }
  // Groups are placed by instances, whose transforms carry normals as
  // normals: only the shape's own transform matters here.
  SetSide(shape, SideOf(flip, rule, to_world, false));
  if (!to_world.IsIdentity()) *shape.mutable_to_world() = to_world.ToProto();
  *Group(group).add_shapes() = std::move(shape);
}

v1::Group& SceneAssembly::Group(const std::string& name) {
  const auto it = group_index_.find(name);
  if (it != group_index_.end()) return *scene_.mutable_groups(it->second);
  group_index_[name] = scene_.groups_size();
  v1::Group& g = *scene_.add_groups();
  g.set_name(name);
  return g;
}

bool SceneAssembly::HasGroup(const std::string& name) const { return group_index_.count(name) > 0; }

void SceneAssembly::AddInstance(const std::string& group, const Matrix4& to_world, const SourceLocation& where) {
  CheckTransform(to_world, where, "instance");
  scene_.add_instances()->set_group(group);
  instance_transforms_.push_back(to_world);
}

void SceneAssembly::AddLight(v1::Light light, const Matrix4& to_world, const SourceLocation& where) {
  CheckTransform(to_world, where, "light");
  *scene_.add_lights() = std::move(light);
  light_transforms_.push_back(to_world);
}

void SceneAssembly::AddDirectionalLight(const std::string& name, const Rgb& irradiance, const Vec3d& direction,
                                        const SourceLocation& where) {
  const auto travel = Normalized(direction);
  if (!travel) Fail(where, "directional light: its direction is zero or not finite");
  v1::Light light;
  light.set_name(name);
  light.set_kind(v1::Light::DIRECTIONAL);
  v1::Properties props;
  SetRgb(props, "irradiance", irradiance);
  *light.mutable_emitter() = Spec("directional", std::move(props));
  *scene_.add_lights() = std::move(light);
  light_transforms_.push_back(FrameAlong(*travel));
}

SceneAssembly::EnvironmentAdded SceneAssembly::AddUniformEnvironment(const std::string& name, const Rgb& radiance) {
  if (environment_ >= 0 && !environment_radiance_) return EnvironmentAdded::kIgnored;
  if (environment_ < 0) {
    environment_ = scene_.lights_size();
    v1::Light& light = *scene_.add_lights();
    light.set_name(name);
    light.set_kind(v1::Light::ENVIRONMENT);
    light_transforms_.push_back(Matrix4());
    environment_radiance_ = Rgb{0, 0, 0};
  }
  Rgb& sum = *environment_radiance_;
  sum = {sum.r + radiance.r, sum.g + radiance.g, sum.b + radiance.b};
  v1::Properties props;
  SetRgb(props, "radiance", sum);
  *scene_.mutable_lights(environment_)->mutable_emitter() = Spec("constant", std::move(props));
  return EnvironmentAdded::kAdded;
}

SceneAssembly::EnvironmentAdded SceneAssembly::AddEnvironmentMap(const std::string& name, v1::Properties props,
                                                                 const Matrix4& to_world,
                                                                 const SourceLocation& where) {
  if (environment_ >= 0 && !environment_radiance_) return EnvironmentAdded::kIgnored;
  CheckTransform(to_world, where, "environment map");
  const bool replaces = environment_ >= 0;
  if (!replaces) {
    environment_ = scene_.lights_size();
    scene_.add_lights();
    light_transforms_.emplace_back();
  }
  v1::Light& light = *scene_.mutable_lights(environment_);
  light.set_name(name);
  light.set_kind(v1::Light::ENVIRONMENT);
  *light.mutable_emitter() = Spec("envmap", std::move(props));
  light_transforms_[environment_] = to_world;
  environment_radiance_.reset();
  return replaces ? EnvironmentAdded::kReplacedUniform : EnvironmentAdded::kAdded;
}

void SceneAssembly::SetCamera(v1::Camera camera, const Matrix4& camera_to_world, const Vec3d& source_right,
                              const SourceLocation& where) {
  if (!camera_to_world.IsFinite()) Fail(where, "camera: transform has non-finite values");
  const Vec3d origin = camera_to_world.Point({0, 0, 0});
  const auto forward = Normalized(camera_to_world.Vector({0, 0, 1}));
  const Vec3d up = camera_to_world.Vector({0, 1, 0});
  if (!forward) Fail(where, "camera: transform has no view direction");
  const auto right = Normalized(Cross(*forward, up));
  if (!right) Fail(where, "camera: transform's up is parallel to its view direction");
  const Vec3d target = origin + *forward;
  auto set = [](v1::Vec3* v, const Vec3d& p) { v->set_x(p.x), v->set_y(p.y), v->set_z(p.z); };
  set(camera.mutable_origin(), origin);
  set(camera.mutable_target(), target);
  set(camera.mutable_up(), up);
  *scene_.mutable_camera() = std::move(camera);

  // yarf draws cross(forward, up) to the right; where the source draws the
  // opposite, reflect the world about the plane through the camera that
  // holds forward and up: p' = p - 2 ((p - o)·r) r.
  mirrored_ = Dot(camera_to_world.Vector(source_right), *right) < 0;
  if (mirrored_) {
    const Vec3d r = *right;
    const double d = 2 * Dot(origin, r);
    mirror_ = Matrix4({1 - 2 * r.x * r.x, -2 * r.x * r.y, -2 * r.x * r.z, d * r.x,  //
                       -2 * r.y * r.x, 1 - 2 * r.y * r.y, -2 * r.y * r.z, d * r.y,  //
                       -2 * r.z * r.x, -2 * r.z * r.y, 1 - 2 * r.z * r.z, d * r.z,  //
                       0, 0, 0, 1});
  } else {
    mirror_ = Matrix4();
  }
}

void SceneAssembly::SetMeter(v1::Camera camera) {
  *scene_.mutable_camera() = std::move(camera);
  mirrored_ = false;
  mirror_ = Matrix4();
}

std::string SceneAssembly::UnusedShapeName(const std::string& wanted) const {
  const auto taken = [&](const std::string& name) {
    for (const v1::SceneShape& shape : scene_.shapes())
      if (shape.name() == name) return true;
    return false;
  };
  std::string name = wanted;
  for (int k = 2; taken(name); ++k) name = wanted + " " + std::to_string(k);
  return name;
}

v1::Scene SceneAssembly::Finish() {
  for (int i = 0; i < scene_.shapes_size(); ++i) {
    v1::SceneShape& shape = *scene_.mutable_shapes(i);
    const WorldShape& w = world_shapes_[i];
    const Matrix4 to_world = mirror_ * w.to_world;
    SetSide(shape, SideOf(w.flip, w.rule, to_world, mirrored_));
    SetTransform(to_world, shape.mutable_to_world(), [&] { shape.clear_to_world(); });
  }
  for (int i = 0; i < scene_.lights_size(); ++i) {
    v1::Light& light = *scene_.mutable_lights(i);
    Matrix4 to_world = mirror_ * light_transforms_[i];
    // The mirror turns a light's direction with the world; a directional
    // light's frame is made a rotation again.
    if (light.kind() == v1::Light::DIRECTIONAL) to_world = FrameAlong(*Normalized(to_world.Vector({0, 0, 1})));
    SetTransform(to_world, light.mutable_to_world(), [&] { light.clear_to_world(); });
  }
  for (int i = 0; i < scene_.media_size(); ++i)
    if (const std::optional<Matrix4>& to_world = medium_transforms_[i]; to_world && !(mirror_ * *to_world).IsIdentity())
      SetTransform(*scene_.mutable_media(i)->mutable_medium()->mutable_properties(), "to_world", mirror_ * *to_world);
  for (int i = 0; i < scene_.textures_size(); ++i) {
    const std::optional<Matrix4>& placed = texture_transforms_[i];
    // Texture space to yarf's world is the placement, then the mirror.
    const std::optional<Matrix4> to_texture = placed ? (mirror_ * *placed).Inverse() : std::nullopt;
    if (to_texture && !to_texture->IsIdentity())
      SetTransform(*scene_.mutable_textures(i)->mutable_texture()->mutable_properties(), "to_texture", *to_texture);
  }
  for (int i = 0; i < scene_.instances_size(); ++i) {
    v1::Instance& instance = *scene_.mutable_instances(i);
    SetTransform(mirror_ * instance_transforms_[i], instance.mutable_to_world(),
                 [&] { instance.clear_to_world(); });
  }
  return std::move(scene_);
}

}  // namespace yarf::importers
