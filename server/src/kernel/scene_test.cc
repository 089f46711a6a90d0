#include "kernel/scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <array>
#include <atomic>

#include "components/registry.h"
#include "kernel/scene_builder.h"
#include "yarf/error.h"

namespace yarf {
namespace {

v1::Transform Translation(double x, double y, double z) {
  v1::Transform t;
  for (double v : {1.0, 0.0, 0.0, x, 0.0, 1.0, 0.0, y, 0.0, 0.0, 1.0, z, 0.0, 0.0, 0.0, 1.0}) t.add_m(v);
  return t;
}

// A scene with a camera, a film and one lambertian material named "m".
v1::Scene BaseScene() {
  v1::Scene scene;
  scene.mutable_film()->set_width(8);
  scene.mutable_film()->set_height(8);
  v1::Camera* camera = scene.mutable_camera();
  camera->mutable_target()->set_z(1);
  camera->mutable_up()->set_y(1);
  camera->set_fov(45);
  v1::Material* m = scene.add_materials();
  m->set_name("m");
  m->set_class_name("lambertian");
  return scene;
}

v1::SceneShape* AddTriangle(google::protobuf::RepeatedPtrField<v1::SceneShape>* shapes) {
  v1::SceneShape* s = shapes->Add();
  s->set_material("m");
  v1::Mesh* mesh = s->mutable_mesh();
  for (float v : {-1.f, -1.f, 0.f, 1.f, -1.f, 0.f, 0.f, 1.f, 0.f}) mesh->add_positions(v);
  for (uint32_t i : {0u, 1u, 2u}) mesh->add_indices(i);
  return s;
}

class SceneTest : public ::testing::Test {
 protected:
  void SetUp() override { registry_.LoadDirectory(YARF_PLUGIN_DIR); }
  std::unique_ptr<KernelScene> Build(const v1::Scene& scene) {
    return BuildScene(scene, SceneSources{{registry_}, device_, {}});
  }
  Hit Trace(const KernelScene& scene, Vec3 origin, Vec3 direction) {
    Ray ray{origin, 0, Normalize(direction), kInfinity};
    Hit hit;
    scene.Intersect(std::span(&ray, 1), std::span(&hit, 1));
    return hit;
  }
  Registry registry_;
  EmbreeDevice device_;
};

TEST_F(SceneTest, RayHitsTriangleAtItsDistanceWithItsNormal) {
  v1::Scene scene = BaseScene();
  *AddTriangle(scene.mutable_shapes())->mutable_to_world() = Translation(0, 0, 5);
  auto kernel = Build(scene);
  const Hit hit = Trace(*kernel, {0, 0, 0}, {0, 0, 1});
  ASSERT_TRUE(hit.Found());
  EXPECT_NEAR(hit.t, 5.0f, 1e-5f);
  EXPECT_NEAR(hit.normal.z, 1.0f, 1e-6f);  // counter-clockwise winding seen from +z
  EXPECT_FALSE(Trace(*kernel, {0, 0, 0}, {0, 0, -1}).Found());
  EXPECT_FALSE(Trace(*kernel, {3, 0, 0}, {0, 0, 1}).Found());  // beside the triangle
}

TEST_F(SceneTest, SphereIsHitFromOutsideAndFromInside) {
  v1::Scene scene = BaseScene();
  v1::SceneShape* s = scene.add_shapes();
  s->set_material("m");
  s->mutable_sphere()->mutable_center()->set_z(10);
  s->mutable_sphere()->set_radius(2);
  auto kernel = Build(scene);
  const Hit outside = Trace(*kernel, {0, 0, 0}, {0, 0, 1});
  ASSERT_TRUE(outside.Found());
  EXPECT_NEAR(outside.t, 8.0f, 1e-4f);
  EXPECT_NEAR(outside.normal.z, -1.0f, 1e-5f);
  const Hit inside = Trace(*kernel, {0, 0, 10}, {1, 0, 0});
  ASSERT_TRUE(inside.Found());
  EXPECT_NEAR(inside.t, 2.0f, 1e-4f);
  EXPECT_NEAR(inside.normal.x, 1.0f, 1e-5f);
}

TEST_F(SceneTest, NestedInstancesComposeTheirTransforms) {
  v1::Scene scene = BaseScene();
  v1::Group* leaf = scene.add_groups();
  leaf->set_name("leaf");
  AddTriangle(leaf->mutable_shapes());
  v1::Group* outer = scene.add_groups();
  outer->set_name("outer");
  v1::Instance* nested = outer->add_instances();
  nested->set_group("leaf");
  *nested->mutable_to_world() = Translation(0, 0, 3);
  v1::Instance* top = scene.add_instances();
  top->set_group("outer");
  *top->mutable_to_world() = Translation(10, 0, 4);
  v1::Instance* direct = scene.add_instances();
  direct->set_group("leaf");
  *direct->mutable_to_world() = Translation(-10, 0, 2);
  auto kernel = Build(scene);
  const Hit nested_hit = Trace(*kernel, {10, 0, 0}, {0, 0, 1});
  ASSERT_TRUE(nested_hit.Found());
  EXPECT_NEAR(nested_hit.t, 7.0f, 1e-4f);
  const Hit direct_hit = Trace(*kernel, {-10, 0, 0}, {0, 0, 1});
  ASSERT_TRUE(direct_hit.Found());
  EXPECT_NEAR(direct_hit.t, 2.0f, 1e-4f);
  EXPECT_NE(nested_hit.shape, direct_hit.shape);
  EXPECT_NEAR(direct_hit.normal.z, 1.0f, 1e-5f);
  EXPECT_FALSE(Trace(*kernel, {0, 0, 0}, {0, 0, 1}).Found());
}

TEST_F(SceneTest, RejectsBadScenesWithClearErrors) {
  v1::Scene cycle = BaseScene();
  v1::Group* g = cycle.add_groups();
  g->set_name("g");
  g->add_instances()->set_group("g");
  cycle.add_instances()->set_group("g");
  EXPECT_THROW(ValidateScene(cycle), Error);

  v1::Scene huge = BaseScene();
  huge.mutable_film()->set_width(100000);
  EXPECT_THROW(ValidateScene(huge), Error);

  v1::Scene bad_index = BaseScene();
  AddTriangle(bad_index.mutable_shapes())->mutable_mesh()->set_indices(2, 7);
  EXPECT_THROW(ValidateScene(bad_index), Error);

  v1::Scene outside = BaseScene();
  AddTriangle(outside.mutable_shapes())->mutable_mesh()->set_file("../../etc/passwd");
  try {
    BuildScene(outside, SceneSources{{registry_}, device_, std::filesystem::temp_directory_path()});
    FAIL() << "a path outside the scene folder was read";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("outside"), std::string::npos) << e.what();
  }
}

TEST_F(SceneTest, ParsesPlyMeshes) {
  v1::Scene scene = BaseScene();
  v1::SceneShape* s = AddTriangle(scene.mutable_shapes());
  s->mutable_mesh()->set_data(
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "-1 -1 6\n1 -1 6\n1 1 6\n-1 1 6\n4 0 1 2 3\n");
  s->mutable_mesh()->set_format("ply");
  auto kernel = Build(scene);
  const Hit hit = Trace(*kernel, {0.5f, 0.5f, 0}, {0, 0, 1});
  ASSERT_TRUE(hit.Found());
  EXPECT_NEAR(hit.t, 6.0f, 1e-4f);
}

TEST_F(SceneTest, ParsesBinaryPlyMeshesOfEitherByteOrder) {
  for (const bool big_endian : {false, true}) {
    std::string ply = std::string("ply\nformat ") + (big_endian ? "binary_big_endian" : "binary_little_endian") +
                      " 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                      "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    auto put = [&](auto value) {
      char bytes[sizeof value];
      std::memcpy(bytes, &value, sizeof value);
      if (big_endian) std::reverse(bytes, bytes + sizeof value);
      ply.append(bytes, sizeof value);
    };
    for (float v : {-1.f, -1.f, 2.f, 1.f, -1.f, 2.f, 0.f, 1.f, 2.f}) put(v);
    put(uint8_t(3));
    for (int32_t i : {0, 1, 2}) put(i);
    v1::Scene scene = BaseScene();
    v1::SceneShape* s = AddTriangle(scene.mutable_shapes());
    s->mutable_mesh()->set_data(ply);
    s->mutable_mesh()->set_format("ply");
    auto kernel = Build(scene);
    const Hit hit = Trace(*kernel, {0, 0, 0}, {0, 0, 1});
    ASSERT_TRUE(hit.Found()) << (big_endian ? "big" : "little") << " endian";
    EXPECT_NEAR(hit.t, 2.0f, 1e-5f);
  }
}

TEST_F(SceneTest, MalformedMeshFilesAreNamedInTheError) {
  v1::Scene scene = BaseScene();
  v1::SceneShape* s = AddTriangle(scene.mutable_shapes());
  s->set_name("broken");
  s->mutable_mesh()->set_data("ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nend_header\n");
  s->mutable_mesh()->set_format("ply");
  try {
    Build(scene);
    FAIL() << "a truncated PLY file was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("broken"), std::string::npos) << e.what();
  }
}

TEST_F(SceneTest, RaysEmbreeCannotTraceFailWithAnErrorInsteadOfAborting) {
  v1::Scene scene = BaseScene();
  AddTriangle(scene.mutable_shapes())->mutable_to_world()->CopyFrom(Translation(0, 0, 5));
  const auto kernel = Build(scene);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (const Ray& bad : {Ray{{nan, 0, 0}, 0, {0, 0, 1}, kInfinity}, Ray{{0, 0, 0}, 0, {0, 0, 1e30f}, kInfinity},
                         Ray{{0, 0, 0}, nan, {0, 0, 1}, kInfinity}, Ray{{0, 0, 0}, -1, {0, 0, 1}, kInfinity},
                         Ray{{0, 0, 0}, 0, {0, 0, 1}, nan}}) {
    std::vector<Ray> rays(9, Ray{{0, 0, 0}, 0, {0, 0, 1}, kInfinity});
    rays[5] = bad;  // in the second packet of eight
    std::vector<Hit> hits(rays.size());
    std::vector<uint8_t> occluded(rays.size());
    EXPECT_THROW(kernel->Intersect(rays, hits), Error);
    EXPECT_THROW(kernel->Occluded(rays, occluded), Error);
  }
  EXPECT_NEAR(Trace(*kernel, {0, 0, 0}, {0, 0, 1}).t, 5.0f, 1e-5f);  // rounded differently by Embree on some CPUs
}

TEST_F(SceneTest, AStoppedJobStopsBuildingAndTracing) {
  v1::Scene scene = BaseScene();
  for (int i = 0; i < 4; ++i) AddTriangle(scene.mutable_shapes())->mutable_to_world()->CopyFrom(Translation(0, 0, 5 + i));
  std::atomic<bool> stop{true};
  SceneSources stopped{{registry_}, device_, {}};
  stopped.stop = &stop;
  EXPECT_THROW(BuildScene(scene, stopped), Error);
  stop = false;
  const auto kernel = BuildScene(scene, stopped);
  EXPECT_NEAR(Trace(*kernel, {0, 0, 0}, {0, 0, 1}).t, 5.0f, 1e-5f);  // rounded differently by Embree on some CPUs
  stop = true;
  EXPECT_THROW(Trace(*kernel, {0, 0, 0}, {0, 0, 1}), Error);
}

TEST_F(SceneTest, PlacementsThatCannotBeInvertedInFloatAreRefused) {
  for (const std::array<double, 3> scale : {std::array{0.0, 1.0, 1.0}, std::array{1e-30, 1e-30, 1e-30},
                                            std::array{1e5, 1.0, 1e-5}, std::array{1e13, 1e13, 1e13}}) {
    v1::Scene scene = BaseScene();
    v1::Transform* t = AddTriangle(scene.mutable_shapes())->mutable_to_world();
    for (double v : {scale[0], 0.0, 0.0, 0.0, 0.0, scale[1], 0.0, 0.0, 0.0, 0.0, scale[2], 5.0, 0.0, 0.0, 0.0, 1.0})
      t->add_m(v);
    EXPECT_THROW(ValidateScene(scene), Error) << scale[0] << " " << scale[1] << " " << scale[2];
  }
  v1::Scene thin = BaseScene();
  v1::Transform* t = AddTriangle(thin.mutable_shapes())->mutable_to_world();
  for (double v : {1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1e-4, 5.0, 0.0, 0.0, 0.0, 1.0}) t->add_m(v);
  EXPECT_NO_THROW(ValidateScene(thin));
}

}  // namespace
}  // namespace yarf
