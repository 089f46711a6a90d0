// Builds a yarf Scene from what an importer finds, and reconciles the
// conventions that differ between renderers: the camera's handedness and
// which side of a surface its normal points to.
#pragma once

#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "importers/diagnostics.h"
#include "importers/matrix.h"
#include "importers/spectrum.h"
#include "yarf/v1/scene.pb.h"

namespace yarf::importers {

// What decides a shape's normal in the renderer the scene comes from.
enum class NormalRule {
  // The winding of its triangles in world space (Mitsuba's meshes, like
  // yarf's world meshes).
  kWorldWinding,
  // Its object-space normal carried by the transform (pbrt's shapes,
  // Mitsuba's rectangle and disk): a mirroring transform keeps it.
  kTransformed,
  // Outward from the centre (spheres, in every renderer and in yarf).
  kSphere,
};

class SceneAssembly {
 public:
  v1::Scene& scene() { return scene_; }

  // A lambertian of reflectance 0.5, the default of Mitsuba and pbrt.
  std::string DefaultMaterial();
  // Adds a material; returns its name: `name`, made unique if taken.
  std::string AddMaterial(const std::string& name, const std::string& class_name, v1::Properties properties);
  // Adds a texture (Scene.textures) after those it may refer to; returns
  // its name: `name`, made unique if taken. A solid texture gives the
  // placement of its space (invertible), which Finish turns into its
  // property "to_texture", world to texture space, after the world's mirror.
  std::string AddTexture(const std::string& name, v1::ComponentSpec texture,
                         const std::optional<Matrix4>& texture_to_world = std::nullopt);
  // The material of class "null": a medium boundary that does not scatter.
  std::string NullMaterial();

  // Adds a participating medium (Scene.media); returns its name: `name`,
  // made unique if taken. A medium placed in space (a grid's unit cube)
  // gives its `to_world`, which Finish sets as its property "to_world"
  // after the world's mirror. Fails at `where` when it is singular.
  std::string AddMedium(const std::string& name, v1::ComponentSpec medium, const std::optional<Matrix4>& to_world,
                        const SourceLocation& where);
  bool HasMedia() const { return scene_.media_size() > 0; }
  // Names the medium the camera sits in ("" is vacuum).
  void SetCameraMedium(const std::string& name) { scene_.set_camera_medium(name); }

  // Adds a shape to the world (empty `group`) or to a group. `flip` is the
  // source's own "flip normals" / "reverse orientation" state. Fails at
  // `where` when to_world is singular or not finite.
  // A mesh made for a shape yarf has no primitive for (a disk, a cylinder,
  // a bilinear patch), counted against kMaxMadeTriangles in all: a few
  // bytes of a cylinder become 256 triangles, and a file that included
  // another of 200 cylinders ten thousand times asked for half a billion.
  static constexpr uint64_t kMaxMadeTriangles = uint64_t(1) << 24;
  v1::Mesh Made(v1::Mesh mesh, const SourceLocation& where);
  void AddShape(v1::SceneShape shape, const Matrix4& to_world, bool flip, NormalRule rule,
                const SourceLocation& where, const std::string& group = "");
  // Creates the group on first use.
  v1::Group& Group(const std::string& name);
  bool HasGroup(const std::string& name) const;
  void AddInstance(const std::string& group, const Matrix4& to_world, const SourceLocation& where);
  // A light of kind POSITIONED, placed by to_world.
  void AddLight(v1::Light light, const Matrix4& to_world, const SourceLocation& where);
  // A "directional" light (kind DIRECTIONAL) of this irradiance, travelling
  // along `direction` (any length): its to_world is a rotation taking +z
  // there. Fails at `where` when the direction is zero or not finite.
  void AddDirectionalLight(const std::string& name, const Rgb& irradiance, const Vec3d& direction,
                           const SourceLocation& where);
  // yarf renders one environment: uniform ones add up, and a map takes
  // the place of a uniform one.
  enum class EnvironmentAdded { kAdded, kReplacedUniform, kIgnored };
  // A uniform environment of this radiance ("constant", kind ENVIRONMENT);
  // ignored after an environment map.
  EnvironmentAdded AddUniformEnvironment(const std::string& name, const Rgb& radiance);
  // An environment map ("envmap" with these properties, kind ENVIRONMENT)
  // turned by to_world; ignored after another map.
  EnvironmentAdded AddEnvironmentMap(const std::string& name, v1::Properties props, const Matrix4& to_world,
                                     const SourceLocation& where);
  bool HasEnvironment() const { return environment_ >= 0; }

  // Places the camera. `camera` carries the projection (fov, lens, clip
  // planes); camera_to_world maps the camera frame (+z forward, +y up) to
  // the world, and `source_right` is the camera-space direction the source
  // renderer draws to the right of the image (+x for pbrt, -x for Mitsuba).
  // When yarf's look-at frame would draw the image mirrored, the whole
  // world is mirrored about the camera's vertical plane instead.
  void SetCamera(v1::Camera camera, const Matrix4& camera_to_world, const Vec3d& source_right,
                 const SourceLocation& where);
  bool HasCamera() const { return scene_.has_camera(); }
  // A meter (radiance or irradiance) as the camera: placed by its own
  // fields, with no image whose sides could be mirrored.
  void SetMeter(v1::Camera camera);
  // `wanted`, or a variant of it, that no world shape is named yet.
  std::string UnusedShapeName(const std::string& wanted) const;

  // The scene, with the mirror applied to world shapes, lights and instances.
  v1::Scene Finish();

 private:
  struct WorldShape {
    Matrix4 to_world;
    bool flip;
    NormalRule rule;
  };
  std::string UniqueName(std::set<std::string>& taken, const std::string& name);

  v1::Scene scene_;
  std::set<std::string> material_names_;
  std::set<std::string> texture_names_;
  std::set<std::string> medium_names_;
  std::string null_material_;
  std::vector<std::optional<Matrix4>> medium_transforms_;   // parallel to scene_.media()
  std::vector<std::optional<Matrix4>> texture_transforms_;  // parallel to scene_.textures()
  std::map<std::string, int> group_index_;
  std::string default_material_;
  std::vector<WorldShape> world_shapes_;   // parallel to scene_.shapes()
  std::vector<Matrix4> light_transforms_;  // parallel to scene_.lights()
  int environment_ = -1;                   // its index in scene_.lights()
  // The radiance of a uniform environment; none for a map.
  std::optional<Rgb> environment_radiance_;
  std::vector<Matrix4> instance_transforms_;
  Matrix4 mirror_;
  bool mirrored_ = false;
  // Triangles of the meshes Made so far.
  uint64_t made_triangles_ = 0;
};

}  // namespace yarf::importers
