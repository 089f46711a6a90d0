#include "kernel/scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <random>
#include <array>
#include <atomic>

#include "components/registry.h"
#include "components/scene_builder.h"
#include "yarf/error.h"
#include "yarf/support/shading.h"

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

// Curves of `basis` along x at z = 5 whose centre line runs straight from
// x = -1 to x = 1, radius `radius` all along: a tube (or ribbon) there.
v1::SceneShape* AddStraightCurve(google::protobuf::RepeatedPtrField<v1::SceneShape>* shapes,
                                 v1::Curves::Basis basis, float radius) {
  v1::SceneShape* s = shapes->Add();
  s->set_material("m");
  v1::Curves* curves = s->mutable_curves();
  curves->set_basis(basis);
  // A B-spline passes near, not through, its points: (-3, -1, 1, 3) give
  // the segment from -1 to 1; Bézier and straight ones end on them.
  const std::vector<float> xs = basis == v1::Curves::BASIS_BSPLINE   ? std::vector<float>{-3, -1, 1, 3}
                                : basis == v1::Curves::BASIS_BEZIER ? std::vector<float>{-1, -1.0f / 3, 1.0f / 3, 1}
                                                                     : std::vector<float>{-1, 1};
  for (const float x : xs)
    for (const float v : {x, 0.0f, 5.0f, radius}) curves->add_points(v);
  curves->add_segments(0);
  return s;
}

TEST_F(SceneTest, RoundCurvesAreTubesOfTheirRadiusWhateverTheirBasis) {
  for (const auto basis : {v1::Curves::BASIS_BEZIER, v1::Curves::BASIS_BSPLINE, v1::Curves::BASIS_LINEAR}) {
    SCOPED_TRACE(v1::Curves::Basis_Name(basis));
    v1::Scene scene = BaseScene();
    AddStraightCurve(scene.mutable_shapes(), basis, 0.25f);
    auto kernel = Build(scene);
    const Hit top = Trace(*kernel, {0.3f, 0, 0}, {0, 0, 1});
    ASSERT_TRUE(top.Found());
    EXPECT_NEAR(top.t, 4.75f, 1e-3f);
    EXPECT_NEAR(top.normal.z, -1.0f, 1e-3f);
    EXPECT_EQ(top.shading_normal.z, top.normal.z);
    // Off the axis by 0.2: the circle of radius 0.25 is met 0.15 before it,
    // where its normal leans (0.2, -0.15) / 0.25.
    const Hit side = Trace(*kernel, {0.3f, 0.2f, 0}, {0, 0, 1});
    ASSERT_TRUE(side.Found());
    EXPECT_NEAR(side.t, 4.85f, 2e-3f);
    EXPECT_NEAR(side.normal.y, 0.8f, 5e-3f);
    EXPECT_NEAR(side.normal.z, -0.6f, 5e-3f);
    // Its tangent runs along the curve, its uv along (u) and across it.
    EXPECT_NEAR(std::abs(side.dpdu.x), 1.0f, 1e-3f);
    EXPECT_NEAR(Dot(side.dpdv, side.normal), 0.0f, 1e-5f);
    EXPECT_GT(side.u, 0.5f);
    EXPECT_LT(side.u, 0.8f);
    EXPECT_FALSE(Trace(*kernel, {0.3f, 0.3f, 0}, {0, 0, 1}).Found());  // beside it
    // A tube is a fibre: from inside it, its wall is not met.
    EXPECT_FALSE(Trace(*kernel, {0.3f, 0, 5}, {0, 0, 1}).Found());
    EXPECT_FALSE(Trace(*kernel, {0.3f, 0.1f, 5}, {0, 1, 0}).Found());
    EXPECT_FALSE(Trace(*kernel, {-3, 0, 5}, {1, 0, 0}).Found());  // in at its end
    // A shadow ray across it is blocked.
    Ray across{{0.3f, 0, 0}, 0, {0, 0, 1}, 10};
    uint8_t blocked = 0;
    kernel->Occluded(std::span(&across, 1), std::span(&blocked, 1));
    EXPECT_EQ(blocked, 1);
  }
}

TEST_F(SceneTest, FlatCurvesAreRibbonsFacingTheRay) {
  v1::Scene scene = BaseScene();
  AddStraightCurve(scene.mutable_shapes(), v1::Curves::BASIS_BEZIER, 0.25f)->mutable_curves()->set_form(
      v1::Curves::FORM_FLAT);
  auto kernel = Build(scene);
  for (const float y : {0.0f, 0.2f}) {
    const Hit hit = Trace(*kernel, {0.3f, y, 0}, {0, 0, 1});
    ASSERT_TRUE(hit.Found()) << y;
    EXPECT_NEAR(hit.t, 5.0f, 1e-3f) << y;  // the plane of the centre line
    EXPECT_NEAR(hit.normal.z, -1.0f, 1e-3f) << y;
  }
  // From the other side it faces that way.
  const Hit below = Trace(*kernel, {0.3f, 0.1f, 10}, {0, 0, -1});
  ASSERT_TRUE(below.Found());
  EXPECT_NEAR(below.t, 5.0f, 1e-3f);
  EXPECT_NEAR(below.normal.z, 1.0f, 1e-3f);
  EXPECT_FALSE(Trace(*kernel, {0.3f, 0.3f, 0}, {0, 0, 1}).Found());
}

TEST_F(SceneTest, PlacedCurvesScaleTheirRadiusAndTurnTheirNormals) {
  v1::Scene scene = BaseScene();
  v1::Group* group = scene.add_groups();
  group->set_name("g");
  AddStraightCurve(group->mutable_shapes(), v1::Curves::BASIS_BSPLINE, 0.25f);
  v1::Instance* instance = scene.add_instances();
  instance->set_group("g");
  // Scaled 2× about the origin: the tube's axis at z = 10, radius 0.5.
  v1::Transform* t = instance->mutable_to_world();
  for (double v : {2.0, 0.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 0.0, 1.0}) t->add_m(v);
  auto kernel = Build(scene);
  const Hit side = Trace(*kernel, {0.5f, 0.4f, 0}, {0, 0, 1});
  ASSERT_TRUE(side.Found());
  EXPECT_NEAR(side.t, 9.7f, 5e-3f);
  EXPECT_NEAR(side.normal.y, 0.8f, 5e-3f);
  EXPECT_NEAR(side.normal.z, -0.6f, 5e-3f);
  // The same curves in the world, scaled by their shape's own to_world.
  v1::Scene world = BaseScene();
  *AddStraightCurve(world.mutable_shapes(), v1::Curves::BASIS_BSPLINE, 0.25f)->mutable_to_world() = *t;
  const Hit same = Trace(*Build(world), {0.5f, 0.4f, 0}, {0, 0, 1});
  ASSERT_TRUE(same.Found());
  EXPECT_NEAR(same.t, side.t, 1e-3f);
}

// Shadow rays and closest hits see the same curves: a ray is blocked
// exactly when it finds a hit, for every basis and form.
TEST_F(SceneTest, ShadowRaysAreBlockedByCurvesExactlyWhereRaysHitThem) {
  for (const auto basis : {v1::Curves::BASIS_BEZIER, v1::Curves::BASIS_BSPLINE, v1::Curves::BASIS_LINEAR})
    for (const auto form : {v1::Curves::FORM_ROUND, v1::Curves::FORM_FLAT}) {
      SCOPED_TRACE(v1::Curves::Basis_Name(basis) + " " + v1::Curves::Form_Name(form));
      v1::Scene scene = BaseScene();
      v1::Curves* curves = scene.add_shapes()->mutable_curves();
      scene.mutable_shapes(0)->set_material("m");
      curves->set_basis(basis);
      curves->set_form(form);
      // A wavy strand rising along y and thinning, of six control points.
      for (int i = 0; i < 6; ++i)
        for (const float v : {0.3f * std::sin(3.0f * i / 5), -1 + 0.4f * i, 0.4f * std::cos(2.0f * i / 5),
                              0.14f - 0.016f * i})
          curves->add_points(v);
      const uint32_t span = basis == v1::Curves::BASIS_LINEAR ? 2 : 4;
      for (uint32_t first = 0; first + span <= 6; first += basis == v1::Curves::BASIS_BEZIER ? 3 : 1)
        curves->add_segments(first);
      auto kernel = Build(scene);
      std::mt19937 random(11);
      std::uniform_real_distribution<float> spread(-1, 1);
      constexpr int kRays = 4000;
      std::vector<Ray> rays(kRays);
      for (Ray& ray : rays) {
        const Vec3 origin(3 * spread(random), 2 * spread(random), 3 * spread(random));
        const Vec3 target(0.3f * spread(random), 1.2f * spread(random), 0.4f * spread(random));
        ray = Ray{origin, 0, Normalize(target - origin), 2 * Length(target - origin)};
      }
      std::vector<Hit> hits(kRays);
      std::vector<uint8_t> blocked(kRays);
      kernel->Intersect(rays, hits);
      kernel->Occluded(rays, blocked);
      int found = 0;
      for (int i = 0; i < kRays; ++i) {
        EXPECT_EQ(bool(blocked[i]), hits[i].Found()) << "ray " << i;
        found += hits[i].Found();
      }
      EXPECT_GT(found, kRays / 20);
      EXPECT_LT(found, kRays);
    }
}

TEST_F(SceneTest, MalformedCurvesAreRefusedWithTheirReason) {
  const auto refusal = [&](const std::function<void(v1::SceneShape&)>& spoil) {
    v1::Scene scene = BaseScene();
    spoil(*AddStraightCurve(scene.mutable_shapes(), v1::Curves::BASIS_BEZIER, 0.25f));
    try {
      Build(scene);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("built");
  };
  const auto contains = [](const std::string& text, const std::string& part) {
    return text.find(part) != std::string::npos;
  };
  EXPECT_PRED2(contains, refusal([](v1::SceneShape&) {}), "built");
  EXPECT_PRED2(contains, refusal([](v1::SceneShape& s) { s.mutable_curves()->add_segments(1); }),
               "segment from control point 1 needs 4 control points, and there are 4");
  EXPECT_PRED2(contains, refusal([](v1::SceneShape& s) { s.mutable_curves()->set_segments(0, 4000000000u); }),
               "needs 4 control points");
  EXPECT_PRED2(contains, refusal([](v1::SceneShape& s) { s.mutable_curves()->clear_segments(); }),
               "at least one segment");
  EXPECT_PRED2(contains, refusal([](v1::SceneShape& s) { s.mutable_curves()->add_points(1); }),
               "4 numbers) per control point");
  EXPECT_PRED2(contains, refusal([](v1::SceneShape& s) { s.mutable_curves()->set_points(5, NAN); }),
               "not a finite number");
  EXPECT_PRED2(contains, refusal([](v1::SceneShape& s) { s.mutable_curves()->set_points(7, -1); }),
               "radius is negative");
  EXPECT_PRED2(contains, refusal([](v1::SceneShape& s) { s.mutable_curves()->set_basis(v1::Curves::Basis(9)); }),
               "unknown curve basis");
  EXPECT_PRED2(contains, refusal([](v1::SceneShape& s) { s.mutable_emitter()->set_class_name("diffuse_area"); }),
               "cannot emit light");
}

// --- surface parameters ----------------------------------------------------

// A triangle with uvs and vertex normals leaning outward (a smooth patch).
v1::SceneShape* AddSmoothTriangle(google::protobuf::RepeatedPtrField<v1::SceneShape>* shapes) {
  v1::SceneShape* s = AddTriangle(shapes);
  v1::Mesh* mesh = s->mutable_mesh();
  for (float v : {0.f, 0.f, 1.f, 0.f, 0.5f, 1.f}) mesh->add_uvs(v);
  const float lean = 0.6f;
  for (float v : {-lean, 0.f, 1.f, lean, 0.f, 1.f, 0.f, lean, 1.f}) mesh->add_normals(v);
  return s;
}

TEST_F(SceneTest, TriangleHitsCarryUvBarycentricsShadingNormalAndDerivatives) {
  v1::Scene scene = BaseScene();
  *AddSmoothTriangle(scene.mutable_shapes())->mutable_to_world() = Translation(0, 0, 5);
  auto kernel = Build(scene);
  // Hit at (0.25, -0.5): b1 = 0.5 (corner 1), b2 = 0.25 (corner 2).
  const Hit hit = Trace(*kernel, {0.25f, -0.5f, 0}, {0, 0, 1});
  ASSERT_TRUE(hit.Found());
  EXPECT_NEAR(hit.b1, 0.5f, 1e-5f);
  EXPECT_NEAR(hit.b2, 0.25f, 1e-5f);
  // uv = 0.5·(1, 0) + 0.25·(0.5, 1).
  EXPECT_NEAR(hit.u, 0.625f, 1e-5f);
  EXPECT_NEAR(hit.v, 0.25f, 1e-5f);
  // u runs along x over 2 units, v from the bottom edge to the apex.
  EXPECT_NEAR(hit.dpdu.x, 2.0f, 1e-4f);
  EXPECT_NEAR(hit.dpdu.y, 0.0f, 1e-4f);
  EXPECT_NEAR(hit.dpdv.y, 2.0f, 1e-4f);
  EXPECT_NEAR(hit.dpdv.x, 0.0f, 1e-4f);
  // The interpolated normal, unit, leaning where the corners lean.
  const Vec3 expected = Normalize(Vec3(-0.6f, 0, 1) * 0.25f + Vec3(0.6f, 0, 1) * 0.5f + Vec3(0, 0.6f, 1) * 0.25f);
  EXPECT_NEAR(hit.shading_normal.x, expected.x, 1e-5f);
  EXPECT_NEAR(hit.shading_normal.y, expected.y, 1e-5f);
  EXPECT_NEAR(hit.shading_normal.z, expected.z, 1e-5f);
  EXPECT_NEAR(hit.normal.z, 1.0f, 1e-6f);
}

TEST_F(SceneTest, VertexNormalsDecideTheSideOfAMeshWoundTheOtherWay) {
  v1::Scene scene = BaseScene();
  v1::SceneShape* s = AddTriangle(scene.mutable_shapes());
  *s->mutable_to_world() = Translation(0, 0, 5);
  for (int k = 0; k < 3; ++k)
    for (float v : {0.f, 0.f, -1.f}) s->mutable_mesh()->add_normals(v);
  auto kernel = Build(scene);
  const Hit hit = Trace(*kernel, {0, 0, 0}, {0, 0, 1});
  ASSERT_TRUE(hit.Found());
  EXPECT_NEAR(hit.normal.z, -1.0f, 1e-6f);
  EXPECT_NEAR(hit.shading_normal.z, -1.0f, 1e-6f);
  // Without uvs, uv are the barycentrics.
  EXPECT_EQ(hit.u, hit.b1);
  EXPECT_EQ(hit.v, hit.b2);
}

// flip_winding turns the winding's normal around, unless vertex normals
// decide (even normals that are the faces' own, which the kernel drops as
// such); flip_normals turns whatever decided.
TEST_F(SceneTest, FlipWindingTurnsTheWindingsSideAndFlipNormalsTheFinalOne) {
  struct Case {
    bool vertex_normals, flip_winding, flip_normals;
    float normal_z;
  };
  for (const Case c : {Case{false, false, false, 1}, Case{false, true, false, -1}, Case{false, true, true, 1},
                       Case{false, false, true, -1}, Case{true, true, false, 1}, Case{true, true, true, -1},
                       Case{true, false, true, -1}}) {
    v1::Scene scene = BaseScene();
    v1::SceneShape* s = AddTriangle(scene.mutable_shapes());
    *s->mutable_to_world() = Translation(0, 0, 5);
    if (c.vertex_normals)
      for (int k = 0; k < 3; ++k)
        for (float v : {0.f, 0.f, 1.f}) s->mutable_mesh()->add_normals(v);
    s->set_flip_winding(c.flip_winding);
    s->set_flip_normals(c.flip_normals);
    auto kernel = Build(scene);
    const Hit hit = Trace(*kernel, {0, 0, 0}, {0, 0, 1});
    ASSERT_TRUE(hit.Found());
    const std::string what = std::string(c.vertex_normals ? "normals" : "no normals") +
                             (c.flip_winding ? ", winding flipped" : "") + (c.flip_normals ? ", normals flipped" : "");
    EXPECT_NEAR(hit.normal.z, c.normal_z, 1e-6f) << what;
    EXPECT_NEAR(hit.shading_normal.z, c.normal_z, 1e-6f) << what;
  }
}

TEST_F(SceneTest, PlacedMeshesTransformTheirShadingNormals) {
  v1::Scene scene = BaseScene();
  v1::Group* group = scene.add_groups();
  group->set_name("g");
  AddSmoothTriangle(group->mutable_shapes());
  v1::Instance* instance = scene.add_instances();
  instance->set_group("g");
  // Stretched 3× along x: normals lean less (inverse transpose).
  v1::Transform* t = instance->mutable_to_world();
  for (double v : {3.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 5.0, 0.0, 0.0, 0.0, 1.0}) t->add_m(v);
  auto kernel = Build(scene);
  const Hit hit = Trace(*kernel, {-2.9f, -0.99f, 0}, {0, 0, 1});  // near corner 0
  ASSERT_TRUE(hit.Found());
  const Vec3 local = Vec3(-0.6f, 0, 1) * (1 - hit.b1 - hit.b2) + Vec3(0.6f, 0, 1) * hit.b1 + Vec3(0, 0.6f, 1) * hit.b2;
  const Vec3 expected = Normalize(Vec3(local.x, 3 * local.y, 3 * local.z));
  EXPECT_NEAR(hit.shading_normal.x, expected.x, 1e-5f);
  EXPECT_NEAR(hit.shading_normal.y, expected.y, 1e-5f);
  EXPECT_NEAR(hit.shading_normal.z, expected.z, 1e-5f);
  EXPECT_NEAR(hit.dpdu.x, 6.0f, 1e-3f);
}

TEST_F(SceneTest, SphereUvFollowsItsOwnAxes) {
  v1::Scene scene = BaseScene();
  v1::SceneShape* s = scene.add_shapes();
  s->set_material("m");
  s->mutable_sphere()->set_radius(2);
  // Rotated 90° about x (its z axis becomes world −y) and moved to z = 10.
  v1::Transform* t = s->mutable_to_world();
  for (double v : {1.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 1.0, 0.0, 10.0, 0.0, 0.0, 0.0, 1.0}) t->add_m(v);
  auto kernel = Build(scene);
  // Seen from the origin, the hit point lies along −z from the centre: the
  // sphere's own −y axis, so φ = 3π/2 (u = 0.75) and θ = π/2 (v = 0.5).
  const Hit hit = Trace(*kernel, {0, 0, 0}, {0, 0, 1});
  ASSERT_TRUE(hit.Found());
  EXPECT_NEAR(hit.u, 0.75f, 1e-4f);
  EXPECT_NEAR(hit.v, 0.5f, 1e-4f);
  // ∂p/∂u = 2π·r along increasing φ; ∂p/∂v = π·r toward the sphere's −z.
  EXPECT_NEAR(Length(hit.dpdu), 4 * kPi, 1e-3f);
  EXPECT_NEAR(Length(hit.dpdv), 2 * kPi, 1e-3f);
  EXPECT_NEAR(hit.dpdv.y, 2 * kPi, 1e-3f);  // the sphere's −z is world +y
  // Its north pole, the sphere's +z = world −y: v = 0.
  const Hit pole = Trace(*kernel, {0, -5, 10}, {0, 1, 0});
  ASSERT_TRUE(pole.Found());
  EXPECT_NEAR(pole.v, 0.0f, 1e-3f);
}

TEST_F(SceneTest, InlineMeshAttributesAreChecked) {
  v1::Scene scene = BaseScene();
  v1::SceneShape* s = AddTriangle(scene.mutable_shapes());
  s->mutable_mesh()->add_uvs(0.5f);
  EXPECT_THROW(
      {
        try {
          Build(scene);
        } catch (const Error& e) {
          EXPECT_NE(std::string(e.what()).find("texture coordinates for 3 vertices"), std::string::npos) << e.what();
          throw;
        }
      },
      Error);
  s->mutable_mesh()->clear_uvs();
  v1::MeshAttribute* colour = s->mutable_mesh()->add_attributes();
  colour->set_name("vertex_color");
  colour->set_channels(3);
  for (int k = 0; k < 8; ++k) colour->add_values(0.5f);
  EXPECT_THROW(Build(scene), Error);  // 8 values, not 9
  colour->add_values(0.5f);
  EXPECT_NO_THROW(Build(scene));
}

TEST_F(SceneTest, MeshAttributesAreInterpolatedPerVertexAndConstantPerFace) {
  v1::Scene scene = BaseScene();
  v1::SceneShape* s = AddTriangle(scene.mutable_shapes());
  v1::MeshAttribute* colour = s->mutable_mesh()->add_attributes();
  colour->set_name("vertex_color");
  colour->set_channels(3);
  for (float v : {1.f, 0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f}) colour->add_values(v);
  v1::MeshAttribute* weight = s->mutable_mesh()->add_attributes();
  weight->set_name("face_weight");
  weight->set_channels(1);
  weight->add_values(0.25f);
  const auto kernel = Build(scene);
  const Hit hit = Trace(*kernel, Vec3(0.2f, -0.3f, -1), Vec3(0, 0, 1));
  ASSERT_TRUE(hit.Found());
  const SurfaceLocation at[] = {{hit.shape, hit.primitive, hit.b1, hit.b2}, {kNoShape, 0, 0, 0}};
  float rgb[6];
  kernel->Attribute("vertex_color", at, rgb);
  EXPECT_NEAR(rgb[0], 1 - hit.b1 - hit.b2, 1e-6f);
  EXPECT_NEAR(rgb[1], hit.b1, 1e-6f);
  EXPECT_NEAR(rgb[2], hit.b2, 1e-6f);
  EXPECT_EQ(rgb[3] + rgb[4] + rgb[5], 0.0f);  // no shape: 0
  kernel->Attribute("face_weight", at, rgb);
  EXPECT_EQ(rgb[0], 0.25f);
  EXPECT_EQ(rgb[2], 0.25f);  // one channel in all three
  kernel->Attribute("vertex_missing", at, rgb);
  EXPECT_EQ(rgb[0], 0.0f);
}

// A plane facing the camera at distance d: one pixel's step there is
// d·(2·tan(fov/2)/width), shrunk by √spp, and its uv footprint follows
// from the plane's ∂p/∂u.
TEST_F(SceneTest, SampleSpacingIsAPixelStepAtTheHitOverRootSpp) {
  v1::Scene scene = BaseScene();  // 8×8, fov 45, looking along +z from the origin
  const auto kernel = Build(scene);
  kernel->SetSamplesPerPixel(16);
  Vec3 dpdx, dpdy;
  kernel->SampleSpacing(Vec3(0, 0, 3), Vec3(0, 0, -1), dpdx, dpdy);
  const float step = 3 * 2 * std::tan(22.5f * kPi / 180) / 8 / 4;
  EXPECT_NEAR(Length(dpdx), step, 1e-5f);
  EXPECT_NEAR(Length(dpdy), step, 1e-5f);
  EXPECT_NEAR(std::abs(dpdx.z) + std::abs(dpdy.z), 0, 1e-6f);  // on the plane
  float footprint[4];
  UvFootprint(Vec3(2, 0, 0), Vec3(0, 4, 0), dpdx, dpdy, footprint);
  EXPECT_NEAR(std::hypot(footprint[0], footprint[1]), step / (std::abs(dpdx.x) > std::abs(dpdx.y) ? 2 : 4), 1e-5f);
  // Seen edge-on, the plane gives no footprint rather than an infinite one.
  kernel->SampleSpacing(Vec3(0, 0, 3), Vec3(1, 0, 0), dpdx, dpdy);
  EXPECT_EQ(Length(dpdx) + Length(dpdy), 0.0f);
}

TEST_F(SceneTest, FootprintsAreReadOnlyWhereATextureCanReadThem) {
  v1::Scene scene = BaseScene();
  AddTriangle(scene.mutable_shapes());
  EXPECT_FALSE(Build(scene)->FootprintsRead());
  // A constant never filters; a checkerboard box-filters its cells.
  v1::SceneTexture* t = scene.add_textures();
  t->set_name("grey");
  t->mutable_texture()->set_class_name("constant_texture");
  EXPECT_FALSE(Build(scene)->FootprintsRead());
  t = scene.add_textures();
  t->set_name("cells");
  t->mutable_texture()->set_class_name("checkerboard");
  EXPECT_TRUE(Build(scene)->FootprintsRead());
}

// A ridge of two faces without normals, 90° apart: smooth_normals gives
// the ridge's vertices the mean of the faces' normals; without it, none.
TEST_F(SceneTest, MeshesWithoutNormalsGetSmoothOnesWhenAsked) {
  v1::Scene scene = BaseScene();
  v1::SceneShape* s = AddTriangle(scene.mutable_shapes());
  v1::Mesh* mesh = s->mutable_mesh();
  mesh->clear_positions();
  mesh->clear_indices();
  // Faces y = 0 (x ≥ 0) and x = 0 (y ≥ 0) sharing the edge x = y = 0, at z 4 to 6.
  for (float v : {0.f, 0.f, 4.f, 0.f, 0.f, 6.f, 1.f, 0.f, 5.f, 0.f, 1.f, 5.f}) mesh->add_positions(v);
  for (uint32_t i : {0u, 2u, 1u, 0u, 1u, 3u}) mesh->add_indices(i);
  // Just beside the ridge, on the face y = 0, seen from below-right.
  const auto hit_near_ridge = [&](const KernelScene& kernel) {
    return Trace(kernel, {0.02f, -1, 5}, {0, 1, 0});
  };
  const Hit flat = hit_near_ridge(*Build(scene));
  ASSERT_TRUE(flat.Found());
  EXPECT_NEAR(flat.shading_normal.y, -1, 1e-5f);
  mesh->set_smooth_normals(true);
  const Hit smooth = hit_near_ridge(*Build(scene));
  ASSERT_TRUE(smooth.Found());
  // Near the ridge the normal leans toward the ridge's (−1, −1, 0)/√2.
  EXPECT_LT(smooth.shading_normal.x, -0.5f);
  EXPECT_NEAR(smooth.shading_normal.x, smooth.shading_normal.y, 0.05f);
  mesh->set_face_normals(true);  // Mitsuba's face_normals wins
  EXPECT_NEAR(hit_near_ridge(*Build(scene)).shading_normal.y, -1, 1e-5f);
}

TEST_F(SceneTest, TexturesNeedUniqueNamesAndTheirAssetsAHash) {
  v1::Scene scene = BaseScene();
  AddTriangle(scene.mutable_shapes());
  for (int k = 0; k < 2; ++k) {
    v1::SceneTexture* t = scene.add_textures();
    t->set_name("wood");
    t->mutable_texture()->set_class_name("bitmap");
  }
  EXPECT_THROW(ValidateScene(scene, nullptr), Error);
  scene.mutable_textures()->RemoveLast();
  (*scene.mutable_textures(0)->mutable_texture()->mutable_properties()->mutable_values())["asset"].set_string_value(
      "../../etc/passwd");
  EXPECT_THROW(ValidateScene(scene, nullptr), Error);
}

// A triangle at z = 5 whose alpha is a constant_texture of `opacity`: the
// fraction of many rays through it (each a different ray) that hit it.
TEST_F(SceneTest, AlphaCutsLetRaysThroughWithTheProbabilityOfTheirOpacity) {
  for (const double opacity : {0.0, 0.3, 1.0}) {
    v1::Scene scene = BaseScene();
    v1::SceneTexture* t = scene.add_textures();
    t->set_name("cut");
    t->mutable_texture()->set_class_name("constant_texture");
    (*t->mutable_texture()->mutable_properties()->mutable_values())["value"].set_float_value(opacity);
    v1::SceneShape* triangle = AddTriangle(scene.mutable_shapes());
    *triangle->mutable_to_world() = Translation(0, 0, 5);
    triangle->set_alpha("cut");
    auto kernel = Build(scene);
    constexpr int kRays = 4000;
    std::vector<Ray> rays(kRays);
    for (int i = 0; i < kRays; ++i)
      rays[i] = Ray{{0.001f * float(i % 100) - 0.05f, 0.001f * float(i / 100) - 0.3f, 0}, 0, {0, 0, 1}, kInfinity};
    std::vector<Hit> hits(kRays);
    kernel->Intersect(rays, hits);
    std::vector<uint8_t> occluded(kRays);
    kernel->Occluded(rays, occluded);
    int hit = 0, blocked = 0;
    for (int i = 0; i < kRays; ++i) hit += hits[i].Found(), blocked += occluded[i];
    // Binomial: within 5σ of opacity·N.
    const double sigma = std::sqrt(kRays * opacity * (1 - opacity)) + 1e-9;
    EXPECT_NEAR(hit, opacity * kRays, 5 * sigma + 0.5) << "opacity " << opacity;
    EXPECT_NEAR(blocked, opacity * kRays, 5 * sigma + 0.5) << "opacity " << opacity;
  }
}

// The kernel traces rays in packets as wide as the CPU's (16 with
// AVX-512, else 8): a device capped at AVX2 takes the 8-wide path on any
// machine, and must find every hit and every blocker the native one does.
TEST_F(SceneTest, EightAndSixteenWidePacketsFindTheSameHits) {
  v1::Scene scene = BaseScene();
  *AddSmoothTriangle(scene.mutable_shapes())->mutable_to_world() = Translation(0.3, 0.2, 4);
  *AddTriangle(scene.mutable_shapes())->mutable_to_world() = Translation(-0.8, -0.4, 6);
  v1::SceneShape* sphere = scene.add_shapes();
  sphere->set_material("m");
  sphere->mutable_sphere()->mutable_center()->set_z(9);
  sphere->mutable_sphere()->set_radius(1.5);
  const EmbreeDevice narrow_device("isa=avx2");
  ASSERT_EQ(rtcGetDeviceProperty(narrow_device.get(), RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED), 0);
  const auto native = Build(scene);
  const auto narrow = BuildScene(scene, SceneSources{{registry_}, narrow_device, {}});

  // A count no packet width divides: both tails are traced too.
  constexpr size_t kRays = 1003;
  std::mt19937 random(7);
  std::uniform_real_distribution<float> spread(-0.35f, 0.35f);
  std::vector<Ray> rays(kRays);
  for (Ray& ray : rays) {
    const Vec3 origin(spread(random), spread(random), 0);
    ray = Ray{origin, 0, Normalize(Vec3(spread(random), spread(random), 1)), kInfinity};
  }
  std::vector<Hit> wide_hits(kRays), narrow_hits(kRays);
  native->Intersect(rays, wide_hits);
  narrow->Intersect(rays, narrow_hits);
  std::vector<uint8_t> wide_blocked(kRays), narrow_blocked(kRays);
  native->Occluded(rays, wide_blocked);
  narrow->Occluded(rays, narrow_blocked);

  size_t found = 0;
  std::array<bool, 3> shapes_met{};
  const auto near = [](Vec3 a, Vec3 b) { return Length(a - b) <= 1e-4f * (1 + Length(a)); };
  for (size_t i = 0; i < kRays; ++i) {
    const Hit& a = wide_hits[i];
    const Hit& b = narrow_hits[i];
    ASSERT_EQ(a.Found(), b.Found()) << "ray " << i;
    EXPECT_EQ(wide_blocked[i], narrow_blocked[i]) << "ray " << i;
    EXPECT_EQ(bool(wide_blocked[i]), a.Found()) << "ray " << i;
    if (!a.Found()) continue;
    ++found;
    if (a.shape < shapes_met.size()) shapes_met[a.shape] = true;
    EXPECT_EQ(a.shape, b.shape) << "ray " << i;
    EXPECT_EQ(a.primitive, b.primitive) << "ray " << i;
    EXPECT_NEAR(a.t, b.t, 1e-4f * a.t) << "ray " << i;
    EXPECT_NEAR(a.u, b.u, 1e-4f) << "ray " << i;
    EXPECT_NEAR(a.v, b.v, 1e-4f) << "ray " << i;
    EXPECT_NEAR(a.b1, b.b1, 1e-4f) << "ray " << i;
    EXPECT_NEAR(a.b2, b.b2, 1e-4f) << "ray " << i;
    EXPECT_TRUE(near(a.normal, b.normal)) << "ray " << i;
    EXPECT_TRUE(near(a.shading_normal, b.shading_normal)) << "ray " << i;
    EXPECT_TRUE(near(a.dpdu, b.dpdu)) << "ray " << i;
    EXPECT_TRUE(near(a.dpdv, b.dpdv)) << "ray " << i;
    EXPECT_EQ(a.parameterised, b.parameterised) << "ray " << i;
  }
  // The rays meet all three shapes and miss some: neither answer is trivial.
  EXPECT_EQ(shapes_met, (std::array<bool, 3>{true, true, true}));
  EXPECT_LT(found, kRays);
}

TEST_F(SceneTest, AlphaMustNameATextureOfTheScene) {
  v1::Scene scene = BaseScene();
  AddTriangle(scene.mutable_shapes())->set_alpha("nowhere");
  EXPECT_THROW(ValidateScene(scene, nullptr), Error);
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
  const auto at_time = [](float time) {
    Ray ray{{0, 0, 0}, 0, {0, 0, 1}, kInfinity};
    ray.time = time;
    return ray;
  };
  const Ray good{{0, 0, 0}, 0, {0, 0, 1}, kInfinity};
  for (const Ray& bad : {Ray{{nan, 0, 0}, 0, {0, 0, 1}, kInfinity}, Ray{{0, 0, 0}, 0, {0, 0, 1e30f}, kInfinity},
                         Ray{{0, -kInfinity, 0}, 0, {0, 0, 1}, kInfinity}, Ray{{0, 0, 0}, nan, {0, 0, 1}, kInfinity},
                         Ray{{0, 0, 0}, -1, {0, 0, 1}, kInfinity}, Ray{{0, 0, 0}, 0, {0, 0, 1}, nan}, at_time(nan),
                         at_time(-0.5f), at_time(1.5f)})
    // In the first packet, in the last lane of a packet of eight, and in
    // a later packet whatever the width (8 or 16).
    for (const size_t place : {0, 7, 17}) {
      std::vector<Ray> rays(20, good);
      rays[place] = bad;
      std::vector<Hit> hits(rays.size());
      std::vector<uint8_t> occluded(rays.size());
      EXPECT_THROW(kernel->Intersect(rays, hits), Error) << place;
      EXPECT_THROW(kernel->Occluded(rays, occluded), Error) << place;
    }
  // The edges of the valid ranges pass: -0 and +inf where 0 and +inf may be.
  std::vector<Ray> edges{Ray{{0, 0, 0}, -0.0f, {0, 0, 1}, kInfinity}, Ray{{0, 0, 0}, kInfinity, {0, 0, 1}, kInfinity},
                         Ray{{0, 0, 0}, 0, {0, 0, 1}, -1}, at_time(-0.0f), at_time(1), Ray{{1e18f, 0, 0}, 0, {-1, 0, 0}, 1}};
  std::vector<Hit> hits(edges.size());
  std::vector<uint8_t> occluded(edges.size());
  EXPECT_NO_THROW(kernel->Intersect(edges, hits));
  EXPECT_NO_THROW(kernel->Occluded(edges, occluded));
  EXPECT_NEAR(hits[0].t, 5.0f, 1e-5f);
  EXPECT_FALSE(hits[1].Found());
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
