// The pbrt-v4 importer, one feature at a time, on the scenes of
// tests/scenes/import/pbrt_*.pbrt and malformed/*.pbrt.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>

#include "importers/importer_test_support.h"
#include "importers/loop_subdivision.h"
#include "importers/mesh_shapes.h"

namespace yarf::importers {
namespace {

using namespace testing;

void ExpectNear(const Vec3d& a, const Vec3d& b, double tolerance = 1e-9) {
  EXPECT_NEAR(a.x, b.x, tolerance);
  EXPECT_NEAR(a.y, b.y, tolerance);
  EXPECT_NEAR(a.z, b.z, tolerance);
}

Vec3d ToVec(const v1::Vec3& v) { return {v.x(), v.y(), v.z()}; }
double Luminance(const Vec3d& c) { return 0.212671 * c.x + 0.715160 * c.y + 0.072169 * c.z; }

// pbrt_basic.pbrt, imported once for the suite.
class PbrtBasic : public ::testing::Test {
 protected:
  static const ImportResult& result() {
    static const ImportResult imported = Import("pbrt_basic.pbrt");
    return imported;
  }
  static const v1::Scene& scene() { return result().scene; }
  static const v1::SceneShape& shape(int i) { return scene().shapes(i); }
  static const v1::Material& material(int i) { return MaterialOf(scene(), shape(i)); }
};

TEST_F(PbrtBasic, CameraFilmSamplerAndIntegrator) {
  ExpectNear(ToVec(scene().camera().origin()), {0, 0, -5});
  ExpectNear(ToVec(scene().camera().target()), {0, 0, -4});
  EXPECT_DOUBLE_EQ(scene().camera().fov(), 30);
  EXPECT_EQ(scene().camera().fov_axis(), v1::Camera::SMALLER);  // pbrt's fov spans the shorter side
  EXPECT_EQ(scene().film().width(), 32u);
  EXPECT_EQ(scene().film().height(), 24u);
  EXPECT_EQ(scene().film().filter().kind(), v1::ReconstructionFilter::BOX);
  EXPECT_EQ(scene().sampler().class_name(), "halton");
  EXPECT_EQ(result().sample_count, 8u);
  // pbrt's maxdepth counts bounces, yarf's path segments.
  EXPECT_EQ(IntProperty(scene().transport().properties(), "max_depth"), 4);
}

TEST_F(PbrtBasic, NamedMaterialIsTheOneUsed) {
  EXPECT_EQ(material(0).name(), "red");
  ExpectNear(RgbProperty(material(0).properties(), "reflectance"), {0.8, 0.1, 0.1});
  EXPECT_EQ(shape(0).mesh().indices_size(), 3);
}

TEST_F(PbrtBasic, TransformsInAttributeBlocksPlaceTheShape) {
  const Matrix4 to_world = ToMatrix(shape(1).to_world());
  ExpectNear(to_world.Point({0, 0, 0}), {1, 2, 3});
  // Scale 2, and the sphere mirrored in z for pbrt's uv (v = 1 − θ/π).
  ExpectNear(to_world.Point({0, 0, -1}), {1, 2, 5});
  EXPECT_DOUBLE_EQ(shape(1).sphere().radius(), 0.5);
  // AttributeEnd restored the identity for the next shapes.
  ExpectNear(ToMatrix(shape(3).to_world()).Point({0, 0, 0}), {0, 0, 0});
}

TEST_F(PbrtBasic, ConductorWithNamedMetalSpectraAndRemappedRoughness) {
  EXPECT_EQ(material(1).class_name(), "roughconductor");
  EXPECT_EQ(StringProperty(material(1).properties(), "material"), "Au");
  EXPECT_NEAR(FloatProperty(material(1).properties(), "alpha"), 0.3, 1e-12);  // sqrt(0.09)
}

TEST_F(PbrtBasic, TexturesBecomeSceneTexturesTheMaterialsReferTo) {
  const auto texture_of = [&](const v1::Material& material) -> const v1::ComponentSpec& {
    const v1::Property& value = material.properties().values().at("reflectance");
    EXPECT_EQ(value.value_case(), v1::Property::kReference);
    for (const v1::SceneTexture& t : scene().textures())
      if (t.name() == value.reference()) return t.texture();
    ADD_FAILURE() << "no texture named " << value.reference();
    return scene().textures(0).texture();
  };
  const v1::ComponentSpec& checks = texture_of(material(2));
  EXPECT_EQ(checks.class_name(), "checkerboard");
  ExpectNear(RgbProperty(checks.properties(), "tex1"), {0.2, 0.2, 0.2});
  ExpectNear(RgbProperty(checks.properties(), "tex2"), {0.6, 0.6, 0.6});
  const v1::ComponentSpec& image = texture_of(material(3));
  EXPECT_EQ(image.class_name(), "bitmap");
  EXPECT_EQ(StringProperty(image.properties(), "filename"), "assets/checker.png");
  // pbrt's images have v = 0 at their bottom row, yarf's at the top.
  const Matrix4 to_uv = ToMatrix(image.properties().values().at("to_uv").transform_value());
  ExpectNear(to_uv.Point({0.25, 0.1, 0}), {0.25, 0.9, 0});
}

TEST_F(PbrtBasic, DiskIsAScaledFanAtItsHeight) {
  ExpectNear(ToMatrix(shape(2).to_world()).Point({1, 0, 0}), {2, 0, 1});
  EXPECT_EQ(shape(2).mesh().indices_size(), 3 * 128);
}

TEST_F(PbrtBasic, ReverseOrientationFlipsNormalsAndPlymeshStaysAFile) {
  EXPECT_EQ(shape(3).mesh().file(), "assets/quad.ply");
  EXPECT_EQ(shape(3).mesh().format(), "ply");
  EXPECT_TRUE(shape(3).flip_normals());
  EXPECT_FALSE(shape(0).flip_normals());
}

// pbrt-v4 faces a mesh with normals as they face, ReverseOrientation or
// not: a plymesh whose header gives its vertices normals is not flipped.
TEST(PbrtImport, ReverseOrientationLeavesAPlymeshWithNormalsFacingThem) {
  char pattern[] = "/tmp/yarf-plymesh-XXXXXX";
  ASSERT_NE(mkdtemp(pattern), nullptr);
  const std::filesystem::path folder = pattern;
  const std::string vertices = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
  const std::string faces = "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  std::ofstream(folder / "plain.ply") << "ply\nformat ascii 1.0\n" << vertices << faces << "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  std::ofstream(folder / "smooth.ply") << "ply\r\nformat ascii 1.0\r\n" << vertices
                                       << "property float nx\nproperty float ny\nproperty float nz\n" << faces
                                       << "0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n";
  std::ofstream(folder / "scene.pbrt") << "WorldBegin\nReverseOrientation\n"
                                          "Shape \"plymesh\" \"string filename\" \"plain.ply\"\n"
                                          "Shape \"plymesh\" \"string filename\" \"smooth.ply\"\n";
  const v1::Scene scene = ImportSceneFile(folder / "scene.pbrt").scene;
  std::filesystem::remove_all(folder);
  ASSERT_EQ(scene.shapes_size(), 2);
  EXPECT_TRUE(scene.shapes(0).flip_normals());
  EXPECT_FALSE(scene.shapes(1).flip_normals());
}

TEST_F(PbrtBasic, AreaLightBlackbodyScaledAndOrientedByN) {
  const v1::SceneShape& light = shape(4);
  EXPECT_EQ(light.emitter().class_name(), "diffuse_area");
  // pbrt-v4 normalises the blackbody to unit luminance, then scales it.
  EXPECT_NEAR(Luminance(RgbProperty(light.emitter().properties(), "radiance")), 3.0, 1e-2);
  // N points to -z, against the winding of P: the triangle is turned over.
  EXPECT_EQ(light.mesh().indices(1), 2u);
  EXPECT_EQ(light.mesh().indices(2), 1u);
  EXPECT_FALSE(light.flip_normals());
  EXPECT_TRUE(Warns(result(), "blackbody spectra converted to RGB"));
  // coateddiffuse is yarf's coateddiffuse, with pbrt's roughness (α = √0.04 inside the model).
  EXPECT_EQ(MaterialOf(scene(), light).class_name(), "coateddiffuse");
  EXPECT_NEAR(FloatProperty(MaterialOf(scene(), light).properties(), "roughness"), 0.04, 1e-12);
}

TEST_F(PbrtBasic, PointAndSpotLights) {
  ASSERT_EQ(scene().lights_size(), 4);  // then the distant and the infinite light
  const v1::Light& point = scene().lights(0);
  EXPECT_EQ(point.kind(), v1::Light::POSITIONED);
  EXPECT_EQ(point.emitter().class_name(), "point");
  ExpectNear(RgbProperty(point.emitter().properties(), "intensity"), {2, 4, 6});  // I × scale
  ExpectNear(ToMatrix(point.to_world()).Point({0, 0, 0}), {0, 4, 0});
  const v1::Light& spot = scene().lights(1);
  EXPECT_EQ(spot.emitter().class_name(), "spot");
  EXPECT_DOUBLE_EQ(FloatProperty(spot.emitter().properties(), "cutoff_angle"), 40);
  EXPECT_DOUBLE_EQ(FloatProperty(spot.emitter().properties(), "beam_width"), 30);
  EXPECT_EQ(StringProperty(spot.emitter().properties(), "falloff"), "smoothstep");
  // "power" 100 over 2π((1 − cos 30°) + (cos 30° − cos 40°) / 2) sr.
  const double cos_start = std::cos(30 * M_PI / 180), cos_end = std::cos(40 * M_PI / 180);
  const double per_sr = 100 / (2 * M_PI * ((1 - cos_start) + (cos_start - cos_end) / 2));
  ExpectNear(RgbProperty(spot.emitter().properties(), "intensity"), {5 * per_sr, 5 * per_sr, 5 * per_sr});
  ExpectNear(ToMatrix(spot.to_world()).Point({0, 0, 0}), {0, 5, 0});
  ExpectNear(ToMatrix(spot.to_world()).Vector({0, 0, 1}), {0, -1, 0});
}

TEST_F(PbrtBasic, DistantAndInfiniteLightsBecomeDirectionalAndEnvironment) {
  ASSERT_EQ(scene().lights_size(), 4);
  const v1::Light& distant = scene().lights(2);
  EXPECT_EQ(distant.kind(), v1::Light::DIRECTIONAL);
  EXPECT_EQ(distant.emitter().class_name(), "directional");
  ExpectNear(RgbProperty(distant.emitter().properties(), "irradiance"), {1, 1, 1});
  // From (0, 0, 0) to (0, -1, 0): the light travels down.
  EXPECT_TRUE(IsRotation(ToMatrix(distant.to_world())));
  ExpectNear(ToMatrix(distant.to_world()).Vector({0, 0, 1}), {0, -1, 0});
  const v1::Light& infinite = scene().lights(3);
  EXPECT_EQ(infinite.kind(), v1::Light::ENVIRONMENT);
  EXPECT_EQ(infinite.emitter().class_name(), "constant");
  ExpectNear(RgbProperty(infinite.emitter().properties(), "radiance"), {0.1, 0.1, 0.1});
  EXPECT_FALSE(infinite.has_to_world());
  EXPECT_FALSE(Warns(result(), "pbrt_basic.pbrt:55"));
  EXPECT_FALSE(Warns(result(), "pbrt_basic.pbrt:56"));
}

TEST(PbrtImport, DistantLightsTurnWithTheTransformAndScaleByIlluminance) {
  const v1::Scene scene = Import("pbrt_lights.pbrt").scene;
  ASSERT_EQ(scene.lights_size(), 3);
  const v1::Light& plain = scene.lights(0);
  EXPECT_EQ(plain.kind(), v1::Light::DIRECTIONAL);
  EXPECT_EQ(plain.emitter().class_name(), "directional");
  ExpectNear(RgbProperty(plain.emitter().properties(), "irradiance"), {2, 4, 6});  // L × scale
  ExpectNear(ToMatrix(plain.to_world()).Vector({0, 0, 1}), {0, 0, 1});  // pbrt's default from and to
  const v1::Light& turned = scene.lights(1);
  EXPECT_EQ(turned.kind(), v1::Light::DIRECTIONAL);
  // pbrt-v4: the unit-luminance spectrum (here the default white) times
  // the illuminance.
  ExpectNear(RgbProperty(turned.emitter().properties(), "irradiance"), {4, 4, 4});
  // (0, 1, 1) turned 90° about x.
  EXPECT_TRUE(IsRotation(ToMatrix(turned.to_world())));
  ExpectNear(ToMatrix(turned.to_world()).Vector({0, 0, 1}), Vec3d{0, -1, 1} * (1 / std::sqrt(2)));
}

TEST(PbrtImport, UniformInfiniteLightsAddUpAndAMapTakesTheirPlace) {
  const ImportResult result = Import("pbrt_lights.pbrt");
  ASSERT_EQ(result.scene.lights_size(), 3);
  const v1::Light& sky = result.scene.lights(2);
  EXPECT_EQ(sky.kind(), v1::Light::ENVIRONMENT);
  // L × scale, (0.2, 0.4, 0.6), plus the default white times illuminance
  // / π, 2π / π: one uniform environment...
  const v1::Scene uniform_scene = Import("pbrt_uniform_lights.pbrt").scene;
  ASSERT_EQ(uniform_scene.lights_size(), 1);
  const v1::Light& uniform = uniform_scene.lights(0);
  EXPECT_EQ(uniform.emitter().class_name(), "constant");
  ExpectNear(RgbProperty(uniform.emitter().properties(), "radiance"), {2.2, 2.4, 2.6}, 1e-6);
  // ...which a map replaces, in pbrt-v4's equal-area mapping, turned by
  // the transform in force.
  EXPECT_EQ(sky.emitter().class_name(), "envmap");
  EXPECT_EQ(StringProperty(sky.emitter().properties(), "filename"), "assets/checker.png");
  EXPECT_EQ(StringProperty(sky.emitter().properties(), "mapping"), "equal_area");
  EXPECT_DOUBLE_EQ(FloatProperty(sky.emitter().properties(), "scale"), 3);
  EXPECT_TRUE(Warns(result, "pbrt_lights.pbrt:20: infinite light: yarf renders one environment per scene: this map "
                            "replaces the uniform one before it"));
  EXPECT_TRUE(Warns(result, "pbrt_lights.pbrt:21: infinite light: yarf renders one environment map per scene"));
  EXPECT_FALSE(Warns(result, "parameter"));
}

TEST(PbrtImport, MaterialsMapToSurfaceModels) {
  const ImportResult result = Import("pbrt_materials.pbrt");
  const v1::Scene& scene = result.scene;
  auto material = [&](int i) -> const v1::Material& { return MaterialOf(scene, scene.shapes(i)); };
  EXPECT_EQ(material(0).class_name(), "diffusetransmission");
  ExpectNear(RgbProperty(material(0).properties(), "reflectance"), {0.3, 0.4, 0.5});
  ExpectNear(RgbProperty(material(0).properties(), "transmittance"), {0.2, 0.2, 0.2});
  EXPECT_EQ(material(1).class_name(), "conductor");
  ExpectNear(RgbProperty(material(1).properties(), "eta"), {0.2, 0.9, 1.1});
  ExpectNear(RgbProperty(material(1).properties(), "k"), {3.9, 2.4, 2.1});
  // Given by reflectance: pbrt-v4's conductor of η = 1 and the k that
  // reflects that much at normal incidence, k = 2√r / √(1 − r); rough.
  EXPECT_EQ(material(2).class_name(), "roughconductor");
  ExpectNear(RgbProperty(material(2).properties(), "eta"), {1, 1, 1});
  const Vec3d k = RgbProperty(material(2).properties(), "k");
  for (const auto& [kc, r] : {std::pair{k.x, 0.9}, {k.y, 0.8}, {k.z, 0.7}}) {
    EXPECT_NEAR(kc * kc / (4 + kc * kc), r, 1e-9);  // Fresnel at normal incidence with η = 1
  }
  EXPECT_NEAR(FloatProperty(material(2).properties(), "alpha"), 0.1, 1e-12);
  // Brass is not among yarf's tabulated metals.
  EXPECT_EQ(StringProperty(material(3).properties(), "material"), "none");
  EXPECT_TRUE(Warns(result, "metal 'CuZn' is not among"));
  EXPECT_EQ(material(4).class_name(), "roughdielectric");
  EXPECT_NEAR(FloatProperty(material(4).properties(), "alpha_u"), 0.2, 1e-12);
  EXPECT_NEAR(FloatProperty(material(4).properties(), "alpha_v"), 0.4, 1e-12);
  EXPECT_DOUBLE_EQ(FloatProperty(material(4).properties(), "int_ior"), 1.33);
  EXPECT_EQ(material(5).class_name(), "thindielectric");
  EXPECT_EQ(material(6).class_name(), "coateddiffuse");  // a smooth one
  ExpectNear(RgbProperty(material(6).properties(), "reflectance"), {0.2, 0.3, 0.4});
  // mix: materials[1] with probability `amount`, on average a blend.
  EXPECT_EQ(material(7).class_name(), "blend");
  EXPECT_EQ(material(7).properties().values().at("bsdf_0").reference(), "a");
  EXPECT_EQ(material(7).properties().values().at("bsdf_1").reference(), "b");
  EXPECT_NEAR(FloatProperty(material(7).properties(), "weight"), 0.8, 1e-12);
  // subsurface: a dielectric around its medium (PbrtImport.ASubsurfaceMaterial...).
  EXPECT_EQ(material(8).class_name(), "dielectric");
  EXPECT_FALSE(scene.shapes(8).interior().empty());
  EXPECT_FALSE(Warns(result, "pbrt_materials.pbrt:24"));
  // A shape of the interface material that bounds no medium: left out, as
  // pbrt-v4 skips it.
  EXPECT_EQ(scene.shapes_size(), 10);
  EXPECT_FALSE(Warns(result, "pbrt_materials.pbrt:26"));
  // pbrt-v3's matte with a slope deviation σ = 20°: Oren and Nayar's
  // qualitative model, σ² = α²/2.
  EXPECT_EQ(material(9).class_name(), "roughdiffuse");
  EXPECT_NEAR(FloatProperty(material(9).properties(), "alpha"), std::sqrt(2.0) * 20 * M_PI / 180, 1e-9);
  EXPECT_TRUE(material(9).properties().values().at("use_fast_approx").bool_value());
  ExpectNear(RgbProperty(material(9).properties(), "reflectance"), {0.6, 0.5, 0.4});
}

// pbrt-v4's layered materials keep their parameters' names; what is not
// given keeps the plugins' defaults, which are pbrt's.
TEST(PbrtImport, CoatedMaterialsMapToTheLayeredModels) {
  const ImportResult result = ImportPbrt(
      "WorldBegin\n"
      "Material \"coateddiffuse\" \"float roughness\" 0.1 \"float thickness\" 0.2 \"rgb albedo\" [0.5 0.6 0.7]\n"
      "  \"float g\" 0.3 \"integer maxdepth\" 20 \"integer nsamples\" 2 \"float eta\" 1.4\n"
      "Shape \"sphere\"\n"
      "Material \"coatedconductor\" \"float interface.roughness\" 0.05 \"float conductor.roughness\" 0.2\n"
      "  \"spectrum conductor.eta\" \"metal-Au-eta\" \"spectrum conductor.k\" \"metal-Au-k\"\n"
      "  \"float interface.eta\" 1.6 \"bool remaproughness\" false\n"
      "Shape \"sphere\"\n"
      "Material \"coatedconductor\" \"rgb reflectance\" [0.9 0.8 0.7]\n"
      "Shape \"sphere\"\n",
      "coated.pbrt");
  const v1::Scene& scene = result.scene;
  const v1::Material& diffuse = MaterialOf(scene, scene.shapes(0));
  EXPECT_EQ(diffuse.class_name(), "coateddiffuse");
  EXPECT_NEAR(FloatProperty(diffuse.properties(), "roughness"), 0.1, 1e-12);
  EXPECT_NEAR(FloatProperty(diffuse.properties(), "thickness"), 0.2, 1e-12);
  EXPECT_NEAR(FloatProperty(diffuse.properties(), "g"), 0.3, 1e-12);
  EXPECT_NEAR(FloatProperty(diffuse.properties(), "eta"), 1.4, 1e-12);
  ExpectNear(RgbProperty(diffuse.properties(), "albedo"), {0.5, 0.6, 0.7});
  ExpectNear(RgbProperty(diffuse.properties(), "reflectance"), {0.5, 0.5, 0.5});  // pbrt's default
  EXPECT_EQ(IntProperty(diffuse.properties(), "maxdepth"), 20);
  EXPECT_EQ(IntProperty(diffuse.properties(), "nsamples"), 2);
  const v1::Material& gold = MaterialOf(scene, scene.shapes(1));
  EXPECT_EQ(gold.class_name(), "coatedconductor");
  EXPECT_NEAR(FloatProperty(gold.properties(), "interface.roughness"), 0.05, 1e-12);
  EXPECT_NEAR(FloatProperty(gold.properties(), "conductor.roughness"), 0.2, 1e-12);
  EXPECT_NEAR(FloatProperty(gold.properties(), "interface.eta"), 1.6, 1e-12);
  EXPECT_FALSE(gold.properties().values().at("remaproughness").bool_value());
  EXPECT_GT(RgbProperty(gold.properties(), "conductor.k").x, 1.0);  // gold's RGB, from yarf's metals
  const v1::Material& tinted = MaterialOf(scene, scene.shapes(2));
  EXPECT_EQ(tinted.class_name(), "coatedconductor");
  ExpectNear(RgbProperty(tinted.properties(), "reflectance"), {0.9, 0.8, 0.7});
  EXPECT_FALSE(Warns(result, "parameter"));
  EXPECT_FALSE(Warns(result, "coatedconductor"));
}

TEST(PbrtImport, ObjectInstancesMapToGroupsAndInstances) {
  const ImportResult result = Import("pbrt_instances.pbrt");
  const v1::Scene& scene = result.scene;
  ASSERT_EQ(scene.groups_size(), 1);
  ASSERT_EQ(scene.groups(0).shapes_size(), 1);
  const v1::SceneShape& ball = scene.groups(0).shapes(0);
  EXPECT_EQ(MaterialOf(scene, ball).class_name(), "dielectric");
  EXPECT_DOUBLE_EQ(FloatProperty(MaterialOf(scene, ball).properties(), "int_ior"), 1.5168);  // glass-BK7
  const Vec3d centre = ToMatrix(ball.to_world()).Point({0, 0, 0});
  ExpectNear(centre, {0, 1, 0});
  ASSERT_EQ(scene.instances_size(), 2);
  ExpectNear(ToMatrix(scene.instances(0).to_world()).Point(centre), {-2, 1, 0});
  ExpectNear(ToMatrix(scene.instances(1).to_world()).Point(centre), {1, 0, 0});  // rotated 90° about z
  EXPECT_TRUE(scene.shapes().empty());
}

TEST(PbrtImport, IncludeAndImportResolveRelativeToTheIncludingFile) {
  const v1::Scene scene = Import("pbrt_include.pbrt").scene;
  ASSERT_EQ(scene.shapes_size(), 1);
  EXPECT_EQ(scene.shapes(0).material(), "green");
  EXPECT_DOUBLE_EQ(FloatProperty(MaterialNamed(scene, "glass").properties(), "int_ior"), 1.33);
}

TEST(PbrtImport, ALeftHandedLookAtMirrorsTheWorldAndKeepsTheLitSide) {
  const v1::Scene scene = Import("pbrt_mirror.pbrt").scene;
  ASSERT_EQ(scene.shapes_size(), 1);
  const v1::SceneShape& light = scene.shapes(0);
  const Matrix4 to_world = ToMatrix(light.to_world());
  // Reflected about x = 0, the camera's vertical plane.
  ExpectNear(to_world.Point({1, 2, 3}), {-1, 2, 3});
  // The triangle faces the camera (-z) in pbrt; after the reflection its
  // winding faces +z, so yarf turns its winding's normal back (a user's
  // flip it is not: vertex normals would decide).
  EXPECT_TRUE(light.flip_winding());
  EXPECT_FALSE(light.flip_normals());
  ExpectNear(ToVec(scene.camera().origin()), {0, 0, -5});
  // The distant light travels along (1, 0, 1), mirrored: still by a rotation.
  ASSERT_EQ(scene.lights_size(), 1);
  const Matrix4 distant = ToMatrix(scene.lights(0).to_world());
  EXPECT_TRUE(IsRotation(distant));
  ExpectNear(distant.Vector({0, 0, 1}), Vec3d{-1, 0, 1} * (1 / std::sqrt(2)));
}

TEST(PbrtImport, NamesFilesOutsideTheSceneFolderRelativeToIt) {
  EXPECT_EQ(Import("beside/outside.pbrt").scene.shapes(0).mesh().file(), "../assets/quad.ply");
}

// Confined, a file outside the folder is not found, and whether it exists
// cannot be told from the message: a scene from someone else learns
// nothing of the importing user's files.
TEST(PbrtImport, ConfinedFindsNoFileOutsideTheSceneFolder) {
  ImportOptions confined;
  confined.confine_to_folder = true;
  const auto message = [&](const std::filesystem::path& file) -> std::string {
    try {
      ImportSceneFile(file, confined);
    } catch (const ImportError& error) {
      return error.what();
    }
    return "";
  };
  EXPECT_NE(message(TestScene("beside/outside.pbrt")).find("not found inside the scene's folder"), std::string::npos);
  EXPECT_GT(ImportSceneFile(TestScene("pbrt_include.pbrt"), confined).scene.shapes_size(), 0);

  const std::filesystem::path folder = std::filesystem::temp_directory_path() / ("yarf-confined-" + std::to_string(::getpid()));
  std::filesystem::create_directories(folder / "inner");
  const auto write = [&](const char* name, const std::string& text) {
    std::ofstream(folder / name) << text;
    return folder / name;
  };
  // An existing file outside (through an absolute path and through a
  // symbolic link inside the folder) and a missing one: the same answer.
  std::filesystem::create_symlink("/etc/passwd", folder / "inner" / "link.pbrt");
  const std::string existing = message(write("a.pbrt", "Include \"/etc/passwd\"\n"));
  const std::string linked = message(write("b.pbrt", "Include \"inner/link.pbrt\"\n"));
  const std::string missing = message(write("c.pbrt", "Include \"/etc/no_such_file_here\"\n"));
  std::filesystem::remove_all(folder);
  for (const std::string& text : {existing, linked, missing})
    EXPECT_NE(text.find("not found inside the scene's folder"), std::string::npos) << text;
  EXPECT_EQ(existing.substr(existing.find("not found")), missing.substr(missing.find("not found")));
}

TEST(PbrtImport, MalformedFilesFailWithFileAndLine) {
  const std::pair<const char*, const char*> cases[] = {
      {"malformed/truncated.pbrt", "truncated.pbrt:1: unclosed '[' of parameter 'fov'"},
      {"malformed/unterminated.pbrt", "unterminated.pbrt:3: unterminated string"},
      {"malformed/unknown_directive.pbrt", "unknown_directive.pbrt:2: unknown directive 'Shpae'"},
      {"malformed/wrong_type.pbrt", "wrong_type.pbrt:1: integer parameter 'xresolution' needs numbers"},
      {"malformed/undefined_material.pbrt", "undefined_material.pbrt:2: named material 'nowhere' is not defined"},
      {"malformed/absurd.pbrt", "absurd.pbrt:1: film resolution 1000000000x1000000000 is out of range"},
      {"malformed/cycle.pbrt", "cycle.pbrt:1: include cycle"},
      {"malformed/bad_indices.pbrt", "bad_indices.pbrt:2: shape 'trianglemesh': index 7 is not a vertex"},
      {"malformed/bad_patches.pbrt", "bad_patches.pbrt:2: shape 'bilinearmesh': indices needs four per patch"},
      {"malformed/unbalanced.pbrt", "unbalanced.pbrt:2: AttributeEnd without AttributeBegin"},
      {"malformed/huge_integer.pbrt", "huge_integer.pbrt:1: parameter 'xresolution' needs an integer"},
      {"malformed/bad_curve.pbrt", "bad_curve.pbrt:2: curve: a degree-3 bezier curve needs degree × segments + 1"},
  };
  for (const auto& [file, message] : cases)
    EXPECT_NE(ImportErrorOf(file).find(message), std::string::npos) << file << ": " << ImportErrorOf(file);
}

TEST(PbrtImport, CurvesBecomeBezierSegmentsOfTheirTypeAndWidth) {
  const ImportResult result = Import("pbrt_curves.pbrt");
  const v1::Scene& scene = result.scene;
  ASSERT_EQ(scene.shapes_size(), 3);
  const v1::Curves& cylinder = scene.shapes(0).curves();
  EXPECT_EQ(cylinder.basis(), v1::Curves::BASIS_BEZIER);
  EXPECT_EQ(cylinder.form(), v1::Curves::FORM_ROUND);
  EXPECT_EQ(cylinder.segments_size(), 2);  // five B-spline points
  EXPECT_FLOAT_EQ(cylinder.points(3), 0.05f);
  const v1::Material& hair = MaterialOf(scene, scene.shapes(0));
  EXPECT_EQ(hair.class_name(), "hair");
  EXPECT_DOUBLE_EQ(FloatProperty(hair.properties(), "eumelanin"), 0.8);
  EXPECT_DOUBLE_EQ(FloatProperty(hair.properties(), "beta_m"), 0.25);
  // Flat by default, tapering from width 0.2 to 0.
  const v1::Curves& flat = scene.shapes(1).curves();
  EXPECT_EQ(flat.form(), v1::Curves::FORM_FLAT);
  ASSERT_EQ(flat.points_size(), 16);
  EXPECT_FLOAT_EQ(flat.points(3), 0.1f);
  EXPECT_FLOAT_EQ(flat.points(15), 0.0f);
  EXPECT_EQ(scene.shapes(2).curves().form(), v1::Curves::FORM_FLAT);
  EXPECT_TRUE(Warns(result, "pbrt_curves.pbrt:14: ribbon curves face each ray"));
  EXPECT_FALSE(scene.shapes(2).has_emitter());
  EXPECT_TRUE(Warns(result, "area lights on curves are not supported"));
  EXPECT_FALSE(Warns(result, "splitdepth"));
}

TEST(PbrtImport, NormalMapsCutOutsCylindersAndMeshAttributes) {
  const ImportResult result = Import("pbrt_surfaces.pbrt");
  const v1::Scene& scene = result.scene;
  ASSERT_EQ(scene.shapes_size(), 3);
  EXPECT_EQ(scene.shapes(2).mesh().indices_size(), 3 * 8 * 16);  // the octahedron refined twice
  // The normal-mapped diffuse: a normalmap wrapper of the diffuse, its
  // map a linear bitmap with v flipped.
  const v1::Material& wrapped = MaterialOf(scene, scene.shapes(0));
  EXPECT_EQ(wrapped.class_name(), "normalmap");
  const std::string nested = wrapped.properties().values().at("bsdf").reference();
  EXPECT_EQ(MaterialNamed(scene, nested).class_name(), "lambertian");
  const std::string map = wrapped.properties().values().at("normalmap").reference();
  const v1::SceneTexture* image = nullptr;
  for (const v1::SceneTexture& t : scene.textures())
    if (t.name() == map) image = &t;
  ASSERT_NE(image, nullptr);
  EXPECT_EQ(image->texture().class_name(), "bitmap");
  EXPECT_EQ(StringProperty(image->texture().properties(), "encoding"), "linear");
  // The half cylinder: 64 quads with smooth normals, and a constant cut-out.
  const v1::SceneShape& cylinder = scene.shapes(0);
  EXPECT_EQ(cylinder.mesh().indices_size(), 6 * 64);
  EXPECT_FALSE(cylinder.alpha().empty());
  // The triangle keeps its normals and uv.
  const v1::Mesh& triangle = scene.shapes(1).mesh();
  EXPECT_EQ(triangle.normals_size(), 9);
  EXPECT_EQ(triangle.uvs_size(), 6);
  EXPECT_FLOAT_EQ(triangle.uvs(5), 1.0f);
  // A misspelt parameter is told the nearest one pbrt's material has.
  EXPECT_TRUE(Warns(result, "parameter 'reflectanse' ignored (did you mean 'reflectance'?)"));
}

TEST(PbrtImport, SolidNoiseTexturesLiveInTheSpaceOfTheTransformAtTheirDirective) {
  const ImportResult result = ImportPbrt(
      "WorldBegin\nAttributeBegin\nTranslate 1 2 3\nScale 2 2 2\n"
      "Texture \"n\" \"float\" \"fbm\" \"integer octaves\" 4 \"float roughness\" 0.7\nAttributeEnd\n"
      "Texture \"m\" \"spectrum\" \"marble\" \"float variation\" 0.3\n"
      "Material \"diffuse\" \"texture reflectance\" \"m\"\n"
      "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]\n",
      "noise.pbrt");
  const v1::Scene& scene = result.scene;
  std::map<std::string, const v1::ComponentSpec*> textures;
  for (const v1::SceneTexture& t : scene.textures()) textures[t.texture().class_name()] = &t.texture();
  ASSERT_TRUE(textures.count("fbm") && textures.count("marble"));
  const v1::Properties& fbm = textures["fbm"]->properties();
  EXPECT_EQ(IntProperty(fbm, "octaves"), 4);
  EXPECT_DOUBLE_EQ(FloatProperty(fbm, "roughness"), 0.7);
  EXPECT_DOUBLE_EQ(FloatProperty(textures["marble"]->properties(), "variation"), 0.3);
  // A pbrt world point x is yarf's mirror(x) (the shape placed at the
  // identity shows the mirror); the texture takes it back to (x − t) / 2.
  const Matrix4 mirror = ToMatrix(scene.shapes(0).to_world());
  const Matrix4 to_texture = ToMatrix(fbm.values().at("to_texture").transform_value());
  for (const Vec3d x : {Vec3d{0, 0, 0}, Vec3d{1, -2, 5}, Vec3d{-3, 4, 0.5}})
    ExpectNear(to_texture.Point(mirror.Point(x)), (x - Vec3d{1, 2, 3}) * 0.5);
  // The marble, defined at the identity, sees pbrt's world itself.
  const auto& marble = textures["marble"]->properties().values();
  const Matrix4 marble_space =
      marble.count("to_texture") ? ToMatrix(marble.at("to_texture").transform_value()) : Matrix4();
  ExpectNear(marble_space.Point(mirror.Point({1, -2, 5})), {1, -2, 5});
  const auto import = [](const std::string& texture) {
    return ImportPbrt("WorldBegin\nTexture \"t\" " + texture + "\n", "bad.pbrt");
  };
  EXPECT_THROW(import(R"("spectrum" "fbm")"), ImportError);
  EXPECT_THROW(import(R"("float" "marble")"), ImportError);
  EXPECT_THROW(import(R"("float" "wrinkled" "string mapping" "uv")"), ImportError);
  EXPECT_THROW(import(R"("float" "fbm" "integer octaves" 0)"), ImportError);
  EXPECT_THROW(import(R"("float" "fbm" "float roughness" 2)"), ImportError);
  EXPECT_THROW(import(R"("spectrum" "checkerboard" "integer dimension" 4)"), ImportError);
  // A checkerboard of dimension 3 is one in space, bilerp keeps its corners.
  const ImportResult more = ImportPbrt(
      "WorldBegin\nTranslate 0 0 1\nTexture \"c\" \"spectrum\" \"checkerboard\" \"integer dimension\" 3\n"
      "Texture \"b\" \"float\" \"bilerp\" \"float v10\" 0.25 \"float uscale\" 2\n",
      "more.pbrt");
  ASSERT_EQ(more.scene.textures_size(), 2);
  const v1::ComponentSpec& cubes = more.scene.textures(0).texture();
  EXPECT_EQ(cubes.class_name(), "checkerboard3d");
  EXPECT_TRUE(cubes.properties().values().count("to_texture"));
  const v1::ComponentSpec& bilerp = more.scene.textures(1).texture();
  EXPECT_EQ(bilerp.class_name(), "bilerp");
  EXPECT_DOUBLE_EQ(RgbProperty(bilerp.properties(), "v10").x, 0.25);
  EXPECT_DOUBLE_EQ(RgbProperty(bilerp.properties(), "v11").x, 1);
  EXPECT_DOUBLE_EQ(FloatProperty(bilerp.properties(), "uscale"), 2);
  EXPECT_TRUE(more.warnings.empty());
}

}  // namespace
}  // namespace yarf::importers

namespace yarf::importers {
namespace {

using testing::IntProperty;
using testing::FloatProperty;
using testing::Warns;

// A mesh's vertex i, and the triangles it makes (index triples).
Vec3d Vertex(const v1::Mesh& mesh, int i) {
  return {mesh.positions(3 * i), mesh.positions(3 * i + 1), mesh.positions(3 * i + 2)};
}
Vec3d NormalOf(const v1::Mesh& mesh, int i) {
  return {mesh.normals(3 * i), mesh.normals(3 * i + 1), mesh.normals(3 * i + 2)};
}
std::vector<std::array<Vec3d, 3>> Triangles(const v1::Mesh& mesh) {
  std::vector<std::array<Vec3d, 3>> out;
  for (int t = 0; t + 2 < mesh.indices_size(); t += 3)
    out.push_back({Vertex(mesh, int(mesh.indices(t))), Vertex(mesh, int(mesh.indices(t + 1))),
                   Vertex(mesh, int(mesh.indices(t + 2)))});
  return out;
}

TEST(PbrtImport, AFlatBilinearPatchIsTwoTrianglesWoundAsPbrtOrientsIt) {
  // p00 p10 p01 p11 of a 2 × 1 rectangle: ∂p/∂u × ∂p/∂v is +z.
  const ImportResult result =
      ImportPbrt("WorldBegin\nShape \"bilinearmesh\" \"point3 P\" [0 0 0  2 0 0  0 1 0  2 1 0]\n", "patch.pbrt");
  ASSERT_EQ(result.scene.shapes_size(), 1);
  const v1::Mesh& mesh = result.scene.shapes(0).mesh();
  EXPECT_EQ(mesh.normals_size(), 0);  // flat: the facets are the surface
  double area = 0;
  for (const auto& [a, b, c] : Triangles(mesh)) {
    const Vec3d winding = Cross(b - a, c - a);
    EXPECT_GT(winding.z, 0);
    area += Length(winding) / 2;
  }
  EXPECT_EQ(mesh.indices_size(), 6);
  EXPECT_NEAR(area, 2, 1e-9);
  // Without uv each corner has the patch's own (u, v).
  ASSERT_EQ(mesh.uvs_size(), 2 * mesh.positions_size() / 3);
  for (int i = 0; i < mesh.positions_size() / 3; ++i) {
    const Vec3d p = Vertex(mesh, i);
    EXPECT_NEAR(mesh.uvs(2 * i), p.x / 2, 1e-6);
    EXPECT_NEAR(mesh.uvs(2 * i + 1), p.y, 1e-6);
  }
}

TEST(PbrtImport, ATwistedBilinearPatchIsCutIntoFacetsOnItsSurfaceWithItsNormals) {
  // The patch z = x·y over the unit square, with uv given (mirrored in u).
  const ImportResult result = ImportPbrt(
      "WorldBegin\nShape \"bilinearmesh\" \"point3 P\" [0 0 0  1 0 0  0 1 0  1 1 1]"
      " \"point2 uv\" [1 0  0 0  1 1  0 1]\n",
      "twisted.pbrt");
  const v1::Mesh& mesh = result.scene.shapes(0).mesh();
  const int vertices = mesh.positions_size() / 3;
  ASSERT_EQ(mesh.normals_size(), mesh.positions_size());
  ASSERT_EQ(mesh.uvs_size(), 2 * vertices);
  for (int i = 0; i < vertices; ++i) {
    const Vec3d p = Vertex(mesh, i);
    EXPECT_NEAR(p.z, p.x * p.y, 1e-6);
    EXPECT_NEAR(mesh.uvs(2 * i), 1 - p.x, 1e-6);
    EXPECT_NEAR(mesh.uvs(2 * i + 1), p.y, 1e-6);
    // ∂p/∂u × ∂p/∂v = (1, 0, y) × (0, 1, x) = (−y, −x, 1).
    const Vec3d n = NormalOf(mesh, i);
    ExpectNear(n * (1 / Length(n)), Vec3d{-p.y, -p.x, 1} * (1 / std::sqrt(1 + p.x * p.x + p.y * p.y)), 1e-6);
  }
  // Every facet lies within the tolerance of the surface, is wound as its
  // normals point, and the facets' area is the surface's,
  // ∫∫ √(1 + x² + y²) dx dy over the unit square.
  double area = 0, off = 0;
  for (const auto& [a, b, c] : Triangles(mesh)) {
    const Vec3d centroid = (a + b + c) * (1.0 / 3);
    off = std::max(off, std::abs(centroid.z - centroid.x * centroid.y));
    const Vec3d winding = Cross(b - a, c - a);
    EXPECT_GT(Dot(winding, Vec3d{-centroid.y, -centroid.x, 1}), 0);
    area += Length(winding) / 2;
  }
  double exact = 0;
  constexpr int kSteps = 1000;
  for (int i = 0; i < kSteps; ++i)
    for (int j = 0; j < kSteps; ++j) {
      const double x = (i + 0.5) / kSteps, y = (j + 0.5) / kSteps;
      exact += std::sqrt(1 + x * x + y * y) / (kSteps * kSteps);
    }
  EXPECT_GT(mesh.indices_size(), 6);
  EXPECT_LE(off, kBilinearTolerance * std::sqrt(3.0));
  EXPECT_NEAR(area, exact, 1e-3 * exact);
}

TEST(PbrtImport, ALoopSubdivisionSurfaceIsRefinedOntoItsLimitSurface) {
  // An octahedron refined 3 times (pbrt-v3's "nlevels"): 8 · 4³ triangles,
  // every vertex inside the control hull |x| + |y| + |z| ≤ 1, normals unit
  // and outward, triangles wound as the control mesh. A control vertex of
  // valence n goes to (1 − nχ) v + χ Σ ring, χ = 1 / (n + 3 / (8β)) with
  // Loop's β = (5/8 − (3/8 + cos(2π/n)/4)²) / n: (1, 0, 0) to (0.43636…, 0, 0).
  const ImportResult result = ImportPbrt(
      "WorldBegin\nShape \"loopsubdiv\" \"integer nlevels\" 3 \"point3 P\" "
      "[1 0 0  -1 0 0  0 1 0  0 -1 0  0 0 1  0 0 -1] \"integer indices\" "
      "[0 2 4  2 1 4  1 3 4  3 0 4  2 0 5  1 2 5  3 1 5  0 3 5]\n",
      "octahedron.pbrt");
  EXPECT_TRUE(result.warnings.empty());
  ASSERT_EQ(result.scene.shapes_size(), 1);
  const v1::Mesh& mesh = result.scene.shapes(0).mesh();
  EXPECT_EQ(mesh.indices_size(), 3 * 8 * 64);
  ASSERT_EQ(mesh.normals_size(), mesh.positions_size());
  double nearest = 1;
  for (int i = 0; i < mesh.positions_size() / 3; ++i) {
    const Vec3d p = Vertex(mesh, i), n = NormalOf(mesh, i);
    EXPECT_LE(std::abs(p.x) + std::abs(p.y) + std::abs(p.z), 1 + 1e-6);
    EXPECT_NEAR(Length(n), 1, 1e-5);
    EXPECT_GT(Dot(n, p), 0);
    nearest = std::min(nearest, Length(p - Vec3d{1, 0, 0}));
  }
  const double beta = (5.0 / 8 - (3.0 / 8) * (3.0 / 8)) / 4, chi = 1 / (4 + 3 / (8 * beta));
  bool found = false;
  for (int i = 0; i < mesh.positions_size() / 3; ++i)
    found = found || Length(Vertex(mesh, i) - Vec3d{1 - 4 * chi, 0, 0}) < 1e-5;
  EXPECT_TRUE(found) << "no vertex at the limit of (1, 0, 0), " << 1 - 4 * chi;
  for (const auto& [a, b, c] : Triangles(mesh)) EXPECT_GT(Dot(Cross(b - a, c - a), a + b + c), 0);
  // pbrt-v4's "levels" too; levels past the triangle limit are cut.
  const ImportResult once = ImportPbrt(
      "WorldBegin\nShape \"loopsubdiv\" \"integer levels\" 1 \"point3 P\" [0 0 0  1 0 0  0 1 0]"
      " \"integer indices\" [0 1 2]\n",
      "once.pbrt");
  EXPECT_EQ(once.scene.shapes(0).mesh().indices_size(), 3 * 4);
  try {
    ImportPbrt("WorldBegin\nShape \"loopsubdiv\" \"point3 P\" [0 0 0  1 0 0  0 1 0] \"integer indices\" [0 0 1]\n",
               "degenerate.pbrt");
    ADD_FAILURE() << "a control mesh without a triangle imported";
  } catch (const ImportError& e) {
    EXPECT_NE(std::string(e.what()).find("degenerate.pbrt:2: loopsubdiv: no triangle has three different corners"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(LoopLevels(1, 12), 11);  // 4^11 = 2^22 triangles
  EXPECT_EQ(LoopLevels(size_t(1) << 22, 1), 0);
  EXPECT_EQ(LoopLevels(8, 3), 3);
}

TEST(PbrtImport, AnAreaLightOnBilinearPatchesEmitsItsPowerOverTheirArea) {
  // Two unit-square patches sharing an edge, 2 W of power: pbrt-v4 makes a
  // light of each patch, L = Φ / (π A) for A = 1 (each triangle's area, ½,
  // would double it).
  const ImportResult result = ImportPbrt(
      "WorldBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 1 1] \"float power\" 2\n"
      "Shape \"bilinearmesh\" \"point3 P\" [0 0 0  1 0 0  0 1 0  1 1 0  2 0 0  2 1 0]"
      " \"integer indices\" [0 1 2 3  1 4 3 5] \"string emissionfilename\" \"unused.exr\"\n",
      "lit_patches.pbrt");
  const v1::SceneShape& shape = result.scene.shapes(0);
  EXPECT_EQ(shape.mesh().indices_size(), 12);
  ASSERT_TRUE(shape.has_emitter());
  const Vec3d radiance = RgbProperty(shape.emitter().properties(), "radiance");
  EXPECT_NEAR(Luminance(radiance), 2 / M_PI, 1e-6);
  EXPECT_FALSE(Warns(result, "emissionfilename"));
}

// A meshed quadric's triangles: their summed area in world space, and
// whether each, in the shape's own space, faces away from `centre` (its
// winding's normal outward).
struct MeshedArea {
  double area = 0;
  bool outward = true;
};
MeshedArea AreaOf(const v1::SceneShape& shape, Vec3d centre) {
  const Matrix4 to_world = ToMatrix(shape.to_world());
  MeshedArea out;
  for (const auto& t : Triangles(shape.mesh())) {
    out.area += TriangleArea(to_world.Point(t[0]), to_world.Point(t[1]), to_world.Point(t[2]));
    const Vec3d n = Cross(t[1] - t[0], t[2] - t[0]);
    if (Dot(n, (t[0] + t[1] + t[2]) * (1.0 / 3) - centre) <= 0) out.outward = false;
  }
  return out;
}

TEST(PbrtImport, PartialQuadricsAreMeshedWithPbrtsUvAndArea) {
  const ImportResult result = ImportPbrt(
      "WorldBegin\n"
      "Shape \"sphere\" \"float radius\" 2 \"float zmin\" -1 \"float zmax\" 1.5 \"float phimax\" 270\n"
      "Shape \"sphere\" \"float zmax\" 0.5\n"
      "Shape \"disk\" \"float radius\" 2 \"float innerradius\" 0.8 \"float phimax\" 90\n"
      "Shape \"disk\" \"float phimax\" 180\n"
      "Shape \"sphere\" \"float zmin\" 0.5 \"float zmax\" 0.5\n",
      "partial.pbrt");
  ASSERT_EQ(result.scene.shapes_size(), 4);
  EXPECT_TRUE(Warns(result, "partial.pbrt:6: a partial sphere of no area"));
  // The zone: on the sphere of radius 2, between its planes and within its
  // wedge, uv as pbrt's (φ / φmax, θ from zmin's to zmax's), normals outward.
  // (In the sphere's own space, scaled to radius 1: the world is mirrored
  // here, as pbrt's default camera's handedness differs from yarf's.)
  const v1::SceneShape& zone = result.scene.shapes(0);
  ASSERT_FALSE(zone.has_sphere());
  const double phi_max = 1.5 * M_PI, theta_min = std::acos(-0.5), theta_max = std::acos(0.75);
  EXPECT_NEAR(Length(ToMatrix(zone.to_world()).Point({0, 0, 1}) - ToMatrix(zone.to_world()).Point({0, 0, 0})), 2,
              1e-9);
  for (int i = 0; i < zone.mesh().positions_size() / 3; ++i) {
    const Vec3d p = Vertex(zone.mesh(), i) * 2;
    EXPECT_NEAR(Length(p), 2, 1e-5) << i;
    EXPECT_GE(p.z, -1 - 1e-5);
    EXPECT_LE(p.z, 1.5 + 1e-5);
    const double phi = std::atan2(p.y, p.x) < -1e-6 ? std::atan2(p.y, p.x) + 2 * M_PI : std::atan2(p.y, p.x);
    const double u = zone.mesh().uvs(2 * i), v = zone.mesh().uvs(2 * i + 1);
    if (std::hypot(p.x, p.y) > 1e-6 && u < 1) EXPECT_NEAR(u, std::max(phi, 0.0) / phi_max, 1e-5) << i;
    EXPECT_NEAR(v, (std::acos(std::clamp(p.z / 2, -1.0, 1.0)) - theta_min) / (theta_max - theta_min), 1e-4) << i;
    ExpectNear(NormalOf(zone.mesh(), i), p * 0.5, 1e-5);
  }
  // Their areas as pbrt-v4 gives them, φmax r (zmax − zmin) and φmax (r² − rᵢ²) / 2,
  // within the meshing's shortfall, wound outward.
  const MeshedArea zone_area = AreaOf(zone, {0, 0, 0});
  EXPECT_NEAR(zone_area.area, phi_max * 2 * 2.5, 1e-3 * phi_max * 5);
  EXPECT_TRUE(zone_area.outward);
  const MeshedArea cap = AreaOf(result.scene.shapes(1), {0, 0, 0});
  EXPECT_NEAR(cap.area, 2 * M_PI * 1.5, 1e-3 * 2 * M_PI * 1.5);  // from the south pole up to z = 0.5
  EXPECT_TRUE(cap.outward);
  const v1::SceneShape& ring = result.scene.shapes(2);
  EXPECT_NEAR(AreaOf(ring, {0, 0, -1}).area, M_PI / 4 * (4 - 0.64), 1e-3 * M_PI / 4 * (4 - 0.64));
  EXPECT_TRUE(AreaOf(ring, {0, 0, -1}).outward);  // facing +z
  for (int i = 0; i < ring.mesh().positions_size() / 3; ++i) {
    const Vec3d p = Vertex(ring.mesh(), i) * 2;
    const double r = std::hypot(p.x, p.y);
    EXPECT_GE(r, 0.8 - 1e-5);
    EXPECT_GE(std::min(p.x, p.y), -1e-5);  // the first quadrant
    EXPECT_NEAR(ring.mesh().uvs(2 * i + 1), (2 - r) / (2 - 0.8), 1e-5) << i;
  }
  EXPECT_NEAR(AreaOf(result.scene.shapes(3), {0, 0, -1}).area, M_PI / 2, 1e-3 * M_PI / 2);
}

TEST(PbrtImport, PixelFiltersKeepTheirShapeAndEachAxisItsRadius) {
  const auto filter_of = [](const std::string& filter) {
    return ImportPbrt("PixelFilter " + filter + "\nWorldBegin\n", "filter.pbrt").scene.film().filter();
  };
  const v1::ReconstructionFilter mitchell = filter_of(R"("mitchell" "float B" 0.25 "float C" 0.375)");
  EXPECT_EQ(mitchell.kind(), v1::ReconstructionFilter::MITCHELL);
  EXPECT_DOUBLE_EQ(mitchell.radius(), 2);
  EXPECT_DOUBLE_EQ(mitchell.b(), 0.25);
  EXPECT_DOUBLE_EQ(mitchell.c(), 0.375);
  const v1::ReconstructionFilter sinc = filter_of(R"("sinc" "float tau" 2 "float yradius" 3)");
  EXPECT_EQ(sinc.kind(), v1::ReconstructionFilter::LANCZOS);
  EXPECT_DOUBLE_EQ(sinc.radius(), 4);  // pbrt's default
  EXPECT_DOUBLE_EQ(sinc.radius_y(), 3);
  EXPECT_DOUBLE_EQ(sinc.lobes(), 2);
  const v1::ReconstructionFilter gaussian = filter_of(R"("gaussian" "float sigma" 0.75 "float xradius" 2)");
  EXPECT_EQ(gaussian.kind(), v1::ReconstructionFilter::GAUSSIAN);
  EXPECT_DOUBLE_EQ(gaussian.stddev(), 0.75);
  EXPECT_DOUBLE_EQ(gaussian.radius(), 2);
  EXPECT_DOUBLE_EQ(gaussian.radius_y(), 1.5);
  // The default filter: pbrt-v4's Gaussian, σ 0.5 out to 1.5.
  const v1::ReconstructionFilter fallback = ImportPbrt("WorldBegin\n", "none.pbrt").scene.film().filter();
  EXPECT_EQ(fallback.kind(), v1::ReconstructionFilter::GAUSSIAN);
  EXPECT_DOUBLE_EQ(fallback.stddev(), 0.5);
  EXPECT_DOUBLE_EQ(fallback.radius(), 1.5);
  EXPECT_THROW(filter_of(R"("gaussian" "float sigma" 0)"), ImportError);
  EXPECT_THROW(filter_of(R"("sinc" "float tau" -1)"), ImportError);
  EXPECT_THROW(filter_of(R"("box" "float yradius" 0)"), ImportError);
}

TEST(PbrtImport, TheFilmIsExposedForTheShuttersOpenTimeAndIsoAndMayCapSamples) {
  const auto film_of = [](const std::string& camera, const std::string& film) {
    return ImportPbrt("Camera \"perspective\" " + camera + "\nFilm \"rgb\" " + film + "\nWorldBegin\n", "film.pbrt")
        .scene.film();
  };
  EXPECT_DOUBLE_EQ(film_of("", "").exposure(), 0);  // 1 s at ISO 100: as rendered
  EXPECT_DOUBLE_EQ(film_of("", "").max_component_value(), 0);
  EXPECT_DOUBLE_EQ(film_of(R"("float shutteropen" 0.5 "float shutterclose" 0.75)", R"("float iso" 800)").exposure(),
                   2);
  EXPECT_DOUBLE_EQ(film_of("", R"("float maxcomponentvalue" 10)").max_component_value(), 10);
  EXPECT_THROW(film_of(R"("float shutteropen" 1 "float shutterclose" 1)", ""), ImportError);
  EXPECT_THROW(film_of("", R"("float iso" 0)"), ImportError);
  EXPECT_THROW(film_of("", R"("float maxcomponentvalue" -1)"), ImportError);
}

TEST(PbrtImport, ASubsurfaceMaterialIsADielectricAroundItsScatteringMedium) {
  const auto import = [](const std::string& material) {
    return ImportPbrt("WorldBegin\nMaterial \"subsurface\" " + material + "\nShape \"sphere\"\n", "sss.pbrt");
  };
  const auto medium_of = [](const ImportResult& result) -> const v1::Properties& {
    const v1::SceneShape& shape = result.scene.shapes(0);
    EXPECT_TRUE(shape.exterior().empty());
    for (const v1::SceneMedium& m : result.scene.media())
      if (m.name() == shape.interior()) {
        EXPECT_EQ(m.medium().class_name(), "homogeneous");
        return m.medium().properties();
      }
    ADD_FAILURE() << "the shape encloses no medium";
    return result.scene.media(0).medium().properties();
  };
  // σ_a and σ_s as given, times scale; pbrt's volpath bounds the walk apart.
  const ImportResult given = import(R"("rgb sigma_a" [1 2 3] "rgb sigma_s" [4 5 6] "float scale" 2 "float g" 0.5)");
  ExpectNear(RgbProperty(medium_of(given), "sigma_a"), {2, 4, 6});
  ExpectNear(RgbProperty(medium_of(given), "sigma_s"), {8, 10, 12});
  EXPECT_DOUBLE_EQ(FloatProperty(medium_of(given), "g"), 0.5);
  EXPECT_EQ(given.scene.materials(0).class_name(), "dielectric");
  EXPECT_DOUBLE_EQ(FloatProperty(given.scene.materials(0).properties(), "int_ior"), 1.33);  // pbrt's default
  EXPECT_EQ(given.scene.transport().class_name(), "volpath");
  EXPECT_EQ(IntProperty(given.scene.transport().properties(), "max_medium_depth"), -1);
  // A reflectance and mean free path: σ_t = 1 / mfp, split by the albedo
  // whose multiple scattering reflects that much (Christensen and Burley:
  // 0.8 → 1 − (4.09712 + 4.20863·0.8 − √(9.59217 + 41.6808·0.8 + 17.7126·0.64))² = 0.990589).
  const ImportResult reflecting =
      import(R"("rgb reflectance" [0.8 0.8 0.8] "rgb mfp" [0.5 0.5 0.5] "float roughness" 0.04)");
  const Vec3d sigma_a = RgbProperty(medium_of(reflecting), "sigma_a");
  const Vec3d sigma_s = RgbProperty(medium_of(reflecting), "sigma_s");
  EXPECT_NEAR(sigma_a.x + sigma_s.x, 2, 1e-9);
  EXPECT_NEAR(sigma_s.x / 2, 0.990589, 1e-6);
  EXPECT_EQ(reflecting.scene.materials(0).class_name(), "roughdielectric");
  // pbrt-v4's measured media by name (reduced σ_s, g 0), and its default.
  ExpectNear(RgbProperty(medium_of(import(R"("string name" "Skin1")")), "sigma_a"), {0.032, 0.17, 0.48});
  ExpectNear(RgbProperty(medium_of(import("")), "sigma_s"), {2.55, 3.21, 3.77});
  // Two materials of different media share no medium.
  const ImportResult two = ImportPbrt(
      "WorldBegin\nMaterial \"subsurface\" \"string name\" \"Skin1\"\nShape \"sphere\"\n"
      "Material \"subsurface\" \"string name\" \"Ketchup\"\nShape \"sphere\"\n",
      "two.pbrt");
  EXPECT_NE(two.scene.shapes(0).interior(), two.scene.shapes(1).interior());
  EXPECT_THROW(import(R"("rgb sigma_a" [1 1 1])"), ImportError);
  EXPECT_THROW(import(R"("string name" "Unobtainium")"), ImportError);
  EXPECT_THROW(import(R"("rgb reflectance" [0.5 0.5 0.5] "rgb mfp" [0 1 1])"), ImportError);
  for (const char* scale : {R"("float scale" 0)", R"("float scale" 1e300)"}) {
    try {
      import(scale);
      ADD_FAILURE() << scale << " was accepted";
    } catch (const ImportError& e) {
      EXPECT_NE(std::string(e.what()).find("scale must be positive and below 1e30"), std::string::npos) << e.what();
    }
  }
}

TEST(PbrtImport, AttributeDefaultsApplyToTheDirectivesOfTheirKindUntilAttributeEnd) {
  const ImportResult result = ImportPbrt(
      "WorldBegin\n"
      "AttributeBegin\n"
      "  Attribute \"shape\" \"float radius\" 2\n"
      "  Attribute \"material\" \"rgb reflectance\" [0.1 0.2 0.3]\n"
      "  Material \"diffuse\"\n"
      "  Shape \"sphere\"\n"
      "  Shape \"sphere\" \"float radius\" 3\n"  // its own value wins
      "  Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0]\n"  // no use for a radius, no warning
      "  Attribute \"shape\" \"float radius\" 4\n"  // replaces the first
      "  Shape \"sphere\"\n"
      "AttributeEnd\n"
      "Shape \"sphere\"\n",
      "attributes.pbrt");
  ASSERT_EQ(result.scene.shapes_size(), 5);
  EXPECT_DOUBLE_EQ(result.scene.shapes(0).sphere().radius(), 2);
  EXPECT_DOUBLE_EQ(result.scene.shapes(1).sphere().radius(), 3);
  EXPECT_DOUBLE_EQ(result.scene.shapes(3).sphere().radius(), 4);
  EXPECT_DOUBLE_EQ(result.scene.shapes(4).sphere().radius(), 1);  // AttributeEnd restored pbrt's default
  ExpectNear(RgbProperty(result.scene.materials(0).properties(), "reflectance"), {0.1, 0.2, 0.3});
  EXPECT_TRUE(result.warnings.empty()) << result.warnings.front();
  EXPECT_THROW(ImportPbrt("WorldBegin\nAttribute \"camera\" \"float fov\" 30\n", "bad.pbrt"), ImportError);
  // Defaults are bounded: every directive of their kind reads through them.
  std::string many = "WorldBegin\n";
  for (int i = 0; i < 4097; ++i) many += "Attribute \"shape\" \"float radius\" 1\n";
  EXPECT_THROW(ImportPbrt(many, "many.pbrt"), ImportError);
  // AttributeEnd gives back what an AttributeBegin took.
  std::string nested = "WorldBegin\n";
  for (int i = 0; i < 4000; ++i) nested += "AttributeBegin\nAttribute \"shape\" \"float radius\" 1\nAttributeEnd\n";
  EXPECT_NO_THROW(ImportPbrt(nested + "Shape \"sphere\"\n", "nested.pbrt"));
}

TEST(PbrtImport, ACropWindowOrPixelBoundsIsThePartOfTheFilmRendered) {
  const auto crop_of = [](const std::string& film) {
    return ImportPbrt("Film \"rgb\" \"integer xresolution\" 40 \"integer yresolution\" 20 " + film + "\nWorldBegin\n",
                      "crop.pbrt");
  };
  EXPECT_EQ(crop_of("").crop, "");
  // Fractions (written with decimal points), each pair in either order.
  EXPECT_EQ(crop_of(R"("float cropwindow" [0.5 0.25 0 1])").crop, "0.250000,0.500000,0.000000,1.000000");
  EXPECT_EQ(crop_of(R"("integer pixelbounds" [2 30 5 15])").crop, "2,30,5,15");
  // pbrt-v4: the crop window wins; pixel bounds past the film are cut to it.
  const ImportResult both = crop_of(R"("float cropwindow" [0 0.5 0 0.5] "integer pixelbounds" [0 40 -3 50])");
  EXPECT_EQ(both.crop, "0.000000,0.500000,0.000000,0.500000");
  EXPECT_EQ(crop_of(R"("integer pixelbounds" [0 40 -3 50])").crop, "0,40,0,20");
  EXPECT_THROW(crop_of(R"("float cropwindow" [0.3 0.3 0 1])"), ImportError);
  EXPECT_THROW(crop_of(R"("float cropwindow" [0 1 0])"), ImportError);
  EXPECT_THROW(crop_of(R"("integer pixelbounds" [50 60 0 10])"), ImportError);
}

ImportResult PbrtWithIntegrator(const std::string& integrator) {
  return ImportPbrt("Integrator " + integrator + "\nWorldBegin\nShape \"sphere\"\n", "integrator.pbrt");
}

TEST(PbrtImport, IntegratorsMapToTheTransportsThatEstimateTheirImage) {
  for (const auto& [pbrt, yarf] : std::vector<std::pair<std::string, std::string>>{
           {"path", "path"}, {"simplepath", "path"}, {"randomwalk", "path"}, {"volpath", "path"},
           {"bdpt", "bdpt"}, {"lightpath", "light"}, {"sppm", "sppm"}}) {
    const ImportResult result = PbrtWithIntegrator("\"" + pbrt + "\" \"integer maxdepth\" 7");
    EXPECT_EQ(result.scene.transport().class_name(), yarf) << pbrt;
    EXPECT_EQ(IntProperty(result.scene.transport().properties(), "max_depth"), 8) << pbrt;
    EXPECT_FALSE(Warns(result, "is not available")) << pbrt;
  }
  // pbrt-v4 samples large triangles by solid angle; its default light
  // sampler is the BVH.
  EXPECT_EQ(PbrtWithIntegrator("\"path\"").scene.triangle_sampling(), v1::Scene::TRIANGLE_SAMPLING_SOLID_ANGLE);
  EXPECT_EQ(PbrtWithIntegrator("\"path\"").scene.light_sampler(), v1::Scene::LIGHT_SAMPLER_BVH);
  EXPECT_EQ(PbrtWithIntegrator("\"path\" \"string lightsampler\" \"power\"").scene.light_sampler(),
            v1::Scene::LIGHT_SAMPLER_POWER);
  EXPECT_EQ(PbrtWithIntegrator("\"path\" \"string lightsampler\" \"uniform\"").scene.light_sampler(),
            v1::Scene::LIGHT_SAMPLER_UNIFORM);
  const ImportResult sppm =
      PbrtWithIntegrator("\"sppm\" \"float radius\" 0.25 \"integer photonsperiteration\" 1000 \"integer seed\" 3");
  EXPECT_DOUBLE_EQ(FloatProperty(sppm.scene.transport().properties(), "initial_radius"), 0.25);
  EXPECT_EQ(IntProperty(sppm.scene.transport().properties(), "photons_per_pass"), 1000);
  EXPECT_EQ(IntProperty(sppm.scene.transport().properties(), "seed"), 3);
}

TEST(PbrtImport, AmbientOcclusionMapsToItsTransportWithItsParameters) {
  const ImportResult ao =
      PbrtWithIntegrator("\"ambientocclusion\" \"bool cossample\" false \"float maxdistance\" 2.5");
  const v1::Properties& props = ao.scene.transport().properties();
  EXPECT_EQ(ao.scene.transport().class_name(), "ambient_occlusion");
  EXPECT_FALSE(props.values().at("cossample").bool_value());
  EXPECT_DOUBLE_EQ(FloatProperty(props, "maxdistance"), 2.5);
  EXPECT_FALSE(props.values().contains("max_depth"));
  EXPECT_TRUE(ao.warnings.empty());
  // pbrt's defaults: cosine-weighted, no distance (the transport's infinity).
  const ImportResult plain = PbrtWithIntegrator("\"ambientocclusion\"");
  EXPECT_TRUE(plain.scene.transport().properties().values().at("cossample").bool_value());
  EXPECT_FALSE(plain.scene.transport().properties().values().contains("maxdistance"));
  EXPECT_TRUE(plain.warnings.empty());
  EXPECT_THROW(PbrtWithIntegrator("\"ambientocclusion\" \"float maxdistance\" 0"), ImportError);
}

TEST(PbrtImport, AnAcceleratorOtherThanPbrtsNamesTheScenesAggregateClass) {
  const auto with = [](const std::string& accelerator) {
    return ImportPbrt("LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\nAccelerator " + accelerator +
                          "\nWorldBegin\nShape \"sphere\"\n",
                      "accelerator.pbrt");
  };
  // pbrt's own: Embree's BVH, their parameters accepted.
  for (const char* own : {"\"bvh\" \"integer maxnodeprims\" 4", "\"kdtree\" \"integer maxprims\" 2"}) {
    const ImportResult result = with(own);
    EXPECT_FALSE(result.scene.has_aggregate()) << own;
    EXPECT_TRUE(result.warnings.empty()) << own;
  }
  const ImportResult grid = with("\"seads\" \"float density\" 3 \"integer max_resolution\" 64");
  EXPECT_EQ(grid.scene.aggregate().class_name(), "seads");
  EXPECT_DOUBLE_EQ(FloatProperty(grid.scene.aggregate().properties(), "density"), 3);
  EXPECT_EQ(IntProperty(grid.scene.aggregate().properties(), "max_resolution"), 64);
  EXPECT_THROW(with("\"seads\" \"float density\" [1 2]"), ImportError);
  EXPECT_THROW(with("\"seads\" \"rgb density\" [1 2 3]"), ImportError);
}

TEST(PbrtImport, AnOrthographicCameraSpansTwoUnitsOfItsSpaceOverTheShorterAxis) {
  // The CTM's Scale 0.5 makes camera space twice as large in the world.
  const ImportResult result = ImportPbrt(
      "Scale 0.5 0.5 0.5\nLookAt 0 0 5  0 0 0  0 1 0\nCamera \"orthographic\"\nWorldBegin\nShape \"sphere\"\n",
      "orthographic.pbrt");
  EXPECT_EQ(result.scene.camera().model(), v1::Camera::ORTHOGRAPHIC);
  EXPECT_EQ(result.scene.camera().fov_axis(), v1::Camera::SMALLER);
  EXPECT_NEAR(result.scene.camera().view_size(), 4, 1e-9);
  EXPECT_TRUE(result.warnings.empty());
}

TEST(PbrtImport, ZSobolIsTheDefaultSamplerUnlessTheFilmOutgrowsIt) {
  EXPECT_EQ(PbrtWithIntegrator("\"path\"").scene.sampler().class_name(), "zsobol");
  const ImportResult paddedsobol =
      ImportPbrt("Sampler \"paddedsobol\"\nWorldBegin\nShape \"sphere\"\n", "sampler.pbrt");
  EXPECT_EQ(paddedsobol.scene.sampler().class_name(), "sobol");
  // 4096² pixels at 512 samples each: 2^33 points.
  const ImportResult huge = ImportPbrt(
      "Film \"rgb\" \"integer xresolution\" 4096 \"integer yresolution\" 4096\n"
      "Sampler \"zsobol\" \"integer pixelsamples\" 512\nWorldBegin\nShape \"sphere\"\n",
      "sampler.pbrt");
  EXPECT_EQ(huge.scene.sampler().class_name(), "sobol");
  EXPECT_TRUE(Warns(huge, "need more than 2^32 points"));
}

}  // namespace
}  // namespace yarf::importers
