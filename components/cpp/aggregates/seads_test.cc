// The SEADS grid against Embree's BVH: the same closest hits and the same
// shadow-ray answers on random rays, through worlds, instances, motion and
// the shapes the grid does not hold.
#include <google/protobuf/util/json_util.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <random>
#include <sstream>

#include "components/registry.h"
#include "kernel/scene.h"
#include "components/scene_builder.h"
#include "yarf/error.h"

namespace yarf {
namespace {

constexpr double kPi = 3.14159265358979323846;

v1::Scene LoadJson(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  v1::Scene scene;
  if (!google::protobuf::util::JsonStringToMessage(text.str(), &scene).ok())
    throw Error("cannot parse " + path.string());
  return scene;
}

v1::ComponentSpec Seads(double density = 2.0) {
  v1::ComponentSpec spec;
  spec.set_class_name("seads");
  (*spec.mutable_properties()->mutable_values())["density"].set_float_value(density);
  return spec;
}

v1::Transform Matrix(std::initializer_list<double> rows) {
  v1::Transform t;
  for (double v : rows) t.add_m(v);
  for (double v : {0.0, 0.0, 0.0, 1.0}) t.add_m(v);
  return t;
}

v1::Camera SmallCamera() {
  v1::Camera camera;
  camera.mutable_target()->set_z(1);
  camera.mutable_up()->set_y(1);
  camera.set_fov(45);
  return camera;
}

// A camera, a small film and one lambertian material named "m".
v1::Scene SmallScene() {
  v1::Scene scene;
  scene.mutable_film()->set_width(4);
  scene.mutable_film()->set_height(4);
  *scene.mutable_camera() = SmallCamera();
  v1::Material* m = scene.add_materials();
  m->set_name("m");
  m->set_class_name("lambertian");
  return scene;
}

// A bumpy sphere of about 2·rings·segments triangles, and a soup of random
// triangles around it: an even part and an uneven one for the grid.
void AddBumpySphere(v1::Mesh* mesh, int rings, int segments, std::mt19937& random) {
  std::uniform_real_distribution<float> bump(0.9f, 1.1f);
  for (int r = 0; r <= rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const double theta = kPi * r / rings, phi = 2 * kPi * s / segments;
      const float radius = (r == 0 || r == rings) ? 1.0f : bump(random);
      mesh->add_positions(float(radius * std::sin(theta) * std::cos(phi)));
      mesh->add_positions(float(radius * std::cos(theta)));
      mesh->add_positions(float(radius * std::sin(theta) * std::sin(phi)));
    }
  for (int r = 0; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const uint32_t a = r * segments + s, b = r * segments + (s + 1) % segments;
      const uint32_t c = a + segments, d = b + segments;
      for (uint32_t i : {a, c, b, b, c, d}) mesh->add_indices(i);
    }
}

void AddSoup(v1::Mesh* mesh, int triangles, float size, std::mt19937& random) {
  std::uniform_real_distribution<float> corner(-2, 2), offset(-size, size);
  for (int t = 0; t < triangles; ++t) {
    const float x = corner(random), y = corner(random), z = corner(random);
    for (int k = 0; k < 3; ++k) {
      mesh->add_positions(x + offset(random));
      mesh->add_positions(y + offset(random));
      mesh->add_positions(z + offset(random));
      mesh->add_indices(uint32_t(3 * t + k));
    }
  }
}

class SeadsTest : public ::testing::Test {
 protected:
  SeadsTest() { registry_.LoadDirectory(YARF_PLUGIN_DIR); }

  std::unique_ptr<KernelScene> Build(const v1::Scene& scene, const std::filesystem::path& root = {}) {
    return BuildScene(scene, SceneSources{{registry_}, device_, root});
  }

  // Rays from points in the box [-extent, extent]³ around `center` in
  // uniform directions; every third ends at a random distance.
  static std::vector<Ray> RandomRays(size_t count, Vec3 center, float extent, uint32_t seed) {
    std::mt19937 random(seed);
    std::uniform_real_distribution<float> unit(0, 1), cube(-extent, extent);
    std::vector<Ray> rays(count);
    for (size_t i = 0; i < count; ++i) {
      const float z = 1 - 2 * unit(random), phi = float(2 * kPi) * unit(random);
      const float r = std::sqrt(std::max(0.0f, 1 - z * z));
      rays[i].origin = center + Vec3(cube(random), cube(random), cube(random));
      rays[i].direction = Vec3(r * std::cos(phi), r * std::sin(phi), z);
      rays[i].tfar = i % 3 == 0 ? 2 * extent * unit(random) : kInfinity;
      rays[i].time = unit(random);
    }
    return rays;
  }

  // Both scenes' closest hits and shadow answers for every ray: the same
  // shape and triangle at the same distance, but where two triangles tie
  // (a ray through a shared edge, or onto coplanar faces, may take
  // either), on at most `tie_fraction` of the hits.
  static void ExpectSameHits(const KernelScene& bvh, const KernelScene& grid, std::span<const Ray> rays,
                             double tie_fraction = 1e-3) {
    std::vector<Hit> expected(rays.size()), got(rays.size());
    bvh.Intersect(rays, expected);
    grid.Intersect(rays, got);
    size_t hits = 0, ties = 0, differ = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
      const Hit &a = expected[i], &b = got[i];
      if (a.Found() != b.Found()) {
        ++differ;
        ADD_FAILURE() << "ray " << i << ": " << (a.Found() ? "BVH" : "grid") << " hit at "
                      << (a.Found() ? a.t : b.t) << ", the other missed";
        continue;
      }
      if (!a.Found()) continue;
      ++hits;
      const float scale = std::max(1.0f, a.t);
      if (a.shape != b.shape || a.primitive != b.primitive) {
        // Two triangles at one distance: a shared edge, or coplanar faces.
        if (std::abs(a.t - b.t) <= 1e-5f * scale) {
          ++ties;
          continue;
        }
        ++differ;
        ADD_FAILURE() << "ray " << i << ": BVH hit shape " << a.shape << " triangle " << a.primitive << " at "
                      << a.t << ", grid shape " << b.shape << " triangle " << b.primitive << " at " << b.t;
        continue;
      }
      EXPECT_NEAR(a.t, b.t, 1e-4f * scale) << "ray " << i;
      EXPECT_NEAR(a.b1, b.b1, 1e-3f) << "ray " << i;
      EXPECT_NEAR(a.b2, b.b2, 1e-3f) << "ray " << i;
    }
    EXPECT_EQ(differ, 0u);
    EXPECT_GT(hits, rays.size() / 10) << "too few rays hit anything to tell";
    EXPECT_LE(ties, size_t(double(hits) * tie_fraction)) << "more ties than shared edges and coplanar faces make";
    std::vector<uint8_t> blocked_bvh(rays.size()), blocked_grid(rays.size());
    bvh.Occluded(rays, blocked_bvh);
    grid.Occluded(rays, blocked_grid);
    size_t disagree = 0;
    for (size_t i = 0; i < rays.size(); ++i) disagree += blocked_bvh[i] != blocked_grid[i];
    EXPECT_LE(disagree, rays.size() / 10000) << "shadow rays differ";
  }

  Registry registry_;
  EmbreeDevice device_;
};

TEST_F(SeadsTest, CornellBoxHitsAreEmbreesOnRandomRays) {
  const std::filesystem::path folder = std::filesystem::path(YARF_SCENES_DIR) / "cornell-box";
  v1::Scene scene = LoadJson(folder / "scene.json");
  const auto bvh = Build(scene, folder);
  *scene.mutable_aggregate() = Seads();
  const auto grid = Build(scene, folder);
  // The boxes stand on the floor: their bottoms and the floor are coplanar.
  ExpectSameHits(*bvh, *grid, RandomRays(100000, Vec3(278, 274, 280), 300, 1), 0.02);
}

// Instances (one moving), a sphere and a cut-out mesh the grid does not
// hold, a group with its own density, and a dense uneven soup.
TEST_F(SeadsTest, InstancedMovingAndMixedScenesHitAsEmbree) {
  std::mt19937 random(7);
  v1::Scene scene = SmallScene();
  v1::Group* group = scene.add_groups();
  group->set_name("bumpy");
  v1::SceneShape* bumpy = group->add_shapes();
  bumpy->set_material("m");
  AddBumpySphere(bumpy->mutable_mesh(), 60, 120, random);
  v1::SceneShape* soup = scene.add_shapes();
  soup->set_material("m");
  AddSoup(soup->mutable_mesh(), 20000, 0.05f, random);
  v1::SceneShape* sphere = scene.add_shapes();
  sphere->set_material("m");
  sphere->mutable_sphere()->mutable_center()->set_x(2.5);
  sphere->mutable_sphere()->set_radius(0.7);
  const std::vector<v1::Transform> placements = {
      Matrix({1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0}),
      Matrix({0, -2, 0, -2.5, 2, 0, 0, 0, 0, 0, 2, 1}),
      Matrix({0.5, 0, 0, 0, 0, 0.5, 0, 2.5, 0, 0, 0.5, -1}),
  };
  for (const v1::Transform& t : placements) {
    v1::Instance* instance = scene.add_instances();
    instance->set_group("bumpy");
    *instance->mutable_to_world() = t;
  }
  v1::SceneShape* moving = scene.add_shapes();
  moving->set_material("m");
  AddBumpySphere(moving->mutable_mesh(), 20, 40, random);
  *moving->mutable_to_world() = Matrix({1, 0, 0, 0, 0, 1, 0, -2.5, 0, 0, 1, 0});
  *moving->mutable_to_world_end() = Matrix({1, 0, 0, 1, 0, 1, 0, -2.5, 0, 0, 1, 0});

  const auto bvh = Build(scene);
  *scene.mutable_aggregate() = Seads();
  *scene.mutable_groups(0)->mutable_aggregate() = Seads(0.5);
  const auto grid = Build(scene);
  ExpectSameHits(*bvh, *grid, RandomRays(100000, Vec3(0, 0, 0), 4, 2));
}

// A single flat quad (a box of no thickness), and grids of one cell and of
// many: the same hits.
TEST_F(SeadsTest, FlatScenesAndExtremeDensitiesHitAsEmbree) {
  for (double density : {0.01, 2.0, 64.0}) {
    SCOPED_TRACE("density " + std::to_string(density));
    v1::Scene scene = SmallScene();
    v1::SceneShape* quad = scene.add_shapes();
    quad->set_material("m");
    for (float v : {-1.f, 0.f, -1.f, 1.f, 0.f, -1.f, 1.f, 0.f, 1.f, -1.f, 0.f, 1.f}) quad->mutable_mesh()->add_positions(v);
    for (uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) quad->mutable_mesh()->add_indices(i);
    const auto bvh = Build(scene);
    *scene.mutable_aggregate() = Seads(density);
    const auto grid = Build(scene);
    ExpectSameHits(*bvh, *grid, RandomRays(20000, Vec3(0, 0, 0), 1.5f, 3));
  }
}

// Triangles as large as the scene, many of them: binning each over every
// cell of its box was quadratic in the triangles (20 000 took 15 s, 40 000
// a minute, none of it cancellable). The grid is made coarser instead, and
// still hits as Embree does.
TEST_F(SeadsTest, ManyTrianglesAsLargeAsTheSceneBuildACoarserGridThatHitsAsEmbree) {
  v1::Scene scene = SmallScene();
  std::mt19937 random(5);
  std::uniform_real_distribution<float> jitter(-0.05f, 0.05f);
  v1::Mesh* mesh = scene.add_shapes()->mutable_mesh();
  scene.mutable_shapes(scene.shapes_size() - 1)->set_material("m");
  // Slanted planes through the whole box, each crossing most of its cells.
  for (uint32_t t = 0; t < 20000; ++t)
    for (const Vec3 corner : {Vec3(-2, -2, -2), Vec3(2, 2, -2), Vec3(2, -2, 2)}) {
      const Vec3 p = corner + Vec3(jitter(random), jitter(random), jitter(random));
      for (const float c : {p.x, p.y, p.z}) mesh->add_positions(c);
      mesh->add_indices(uint32_t(mesh->indices_size()));
    }
  const auto bvh = Build(scene);
  *scene.mutable_aggregate() = Seads(64.0);
  const auto grid = Build(scene);
  ExpectSameHits(*bvh, *grid, RandomRays(2000, Vec3(0, 0, 0), 3, 4));
}

// Rays along the axes (directions with zero components), from the grid's
// sides and corners, from far away and with empty intervals: the cases of
// the walk's set-up, against Embree.
TEST_F(SeadsTest, AxisRaysFromTheGridsSidesHitAsEmbree) {
  v1::Scene scene = SmallScene();
  std::mt19937 random(3);
  v1::SceneShape* soup = scene.add_shapes();
  soup->set_material("m");
  AddSoup(soup->mutable_mesh(), 4000, 0.3f, random);
  const auto bvh = Build(scene);
  *scene.mutable_aggregate() = Seads();
  const auto grid = Build(scene);
  std::vector<Ray> rays;
  const std::array<Vec3, 6> axes = {Vec3(1, 0, 0), Vec3(-1, 0, 0), Vec3(0, 1, 0),
                                    Vec3(0, -1, 0), Vec3(0, 0, 1), Vec3(0, 0, -1)};
  std::uniform_real_distribution<float> inside(-2.3f, 2.3f);
  for (int i = 0; i < 3000; ++i)
    for (const Vec3& axis : axes) {
      // From inside, from the far side of the box, and from far away.
      const Vec3 point(inside(random), inside(random), inside(random));
      rays.push_back({point, 0, axis, kInfinity});
      rays.push_back({point - axis * 2.5f * std::abs(Dot(point, axis) + 2.5f), 0, axis, kInfinity});
      rays.push_back({point - axis * 100.0f, 0, axis, kInfinity});
      rays.push_back({point, 1, axis, 0.5f});  // tnear > tfar: nothing
    }
  ExpectSameHits(*bvh, *grid, rays, 0.01);
}

// Rays the kernel would refuse before Embree sees them (NaNs, no
// direction), given to the grid itself: no hit, and no endless walk.
TEST_F(SeadsTest, TheGridFindsNothingOnRaysWithoutADirection) {
  std::shared_ptr<Aggregate> grid = registry_.CreateAs<Aggregate>("seads", Properties{});
  const std::vector<Vec3> positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  const std::vector<uint32_t> indices = {0, 1, 2};
  grid->Add(positions, indices);
  grid->Commit();
  const float nan = std::nanf("");
  for (const Ray& ray : {Ray{Vec3(0.2f, 0.2f, -1), 0, Vec3(0, 0, 0), kInfinity},
                         Ray{Vec3(nan, 0.2f, -1), 0, Vec3(0, 0, 1), kInfinity},
                         Ray{Vec3(0.2f, 0.2f, -1), 0, Vec3(nan, nan, nan), kInfinity},
                         Ray{Vec3(0.2f, 0.2f, -1), 0, Vec3(0, 0, 1), nan}}) {
    AggregateHit hit;
    EXPECT_FALSE(grid->Intersect(ray, hit));
    EXPECT_FALSE(grid->Occluded(ray));
  }
  AggregateHit hit;
  ASSERT_TRUE(grid->Intersect(Ray{Vec3(0.2f, 0.3f, -1), 0, Vec3(0, 0, 1), kInfinity}, hit));
  EXPECT_NEAR(hit.t, 1.0f, 1e-6f);
  EXPECT_NEAR(hit.u, 0.2f, 1e-6f);
  EXPECT_NEAR(hit.v, 0.3f, 1e-6f);
}

// A mesh index past its vertices is refused, not read.
TEST_F(SeadsTest, AMeshWithAnIndexPastItsVerticesIsRefused) {
  std::shared_ptr<Aggregate> grid = registry_.CreateAs<Aggregate>("seads", Properties{});
  const std::vector<Vec3> positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  const std::vector<uint32_t> indices = {0, 1, 3};
  EXPECT_THROW(grid->Add(positions, indices), Error);
}

TEST_F(SeadsTest, AnAggregateIsSetBeforeItsShapes) {
  KernelScene scene(device_, Camera(SmallCamera(), 4, 4), 4, 4);
  TriangleMesh mesh;
  mesh.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  mesh.indices = {0, 1, 2};
  scene.AddMesh(KernelScene::kWorld, mesh, ShapeLook{});
  EXPECT_THROW(scene.SetAggregate(KernelScene::kWorld, registry_.CreateAs<Aggregate>("seads", Properties{})),
               Error);
}

}  // namespace
}  // namespace yarf
