// The Mitsuba 3 importer, one feature at a time, on the scenes of
// tests/scenes/import/mitsuba_*.xml and malformed/*.xml.
#include <gtest/gtest.h>

#include <cmath>

#include "importers/diagnostics.h"
#include "importers/importer_test_support.h"

namespace yarf::importers {
namespace {

using namespace testing;

void ExpectNear(const Vec3d& a, const Vec3d& b, double tolerance = 1e-9) {
  EXPECT_NEAR(a.x, b.x, tolerance);
  EXPECT_NEAR(a.y, b.y, tolerance);
  EXPECT_NEAR(a.z, b.z, tolerance);
}

Vec3d ToVec(const v1::Vec3& v) { return {v.x(), v.y(), v.z()}; }

TEST(MitsubaImport, DefaultsSubstituteAndParametersOverrideThem) {
  const ImportResult result = Import("mitsuba_defaults.xml");
  EXPECT_EQ(result.scene.film().width(), 32u);
  EXPECT_EQ(result.scene.film().height(), 32u);
  EXPECT_EQ(IntProperty(result.scene.transport().properties(), "max_depth"), 4);
  EXPECT_EQ(result.sample_count, 8u);
  EXPECT_EQ(result.scene.sampler().class_name(), "stratified");
  EXPECT_EQ(IntProperty(result.scene.sampler().properties(), "sample_count"), 8);
  // Lights are chosen as Mitsuba chooses them: uniformly.
  EXPECT_EQ(result.scene.light_sampler(), v1::Scene::LIGHT_SAMPLER_UNIFORM);

  const ImportResult small = Import("mitsuba_defaults.xml", {{{"res", "16"}, {"spp", "2"}}});
  EXPECT_EQ(small.scene.film().width(), 16u);
  EXPECT_EQ(small.sample_count, 2u);
}

TEST(MitsubaImport, IncludesResolveRelativeToTheIncludingFile) {
  const ImportResult result = Import("mitsuba_include.xml");
  const v1::Material& red = MaterialOf(result.scene, ShapeNamed(result.scene, "ball"));
  EXPECT_EQ(red.name(), "red");
  ExpectNear(RgbProperty(red.properties(), "reflectance"), {0.8, 0.1, 0.1});
  // fragments/materials.xml includes more_materials.xml beside it.
  EXPECT_EQ(ShapeNamed(result.scene, "card").material(), "blue");
}

TEST(MitsubaImport, TransformsComposeInOrder) {
  const ImportResult result = Import("mitsuba_transforms.xml");
  // scale 2, then rotate 90° about y, then translate (1, 2, 3).
  const Matrix4 moved = ToMatrix(ShapeNamed(result.scene, "moved").to_world());
  ExpectNear(moved.Point({1, 0, 0}), {1, 2, 1});
  ExpectNear(moved.Point({0, 1, 0}), {1, 4, 3});
  EXPECT_EQ(ShapeNamed(result.scene, "moved").mesh().file(), "assets/triangle.obj");
  ExpectNear(ToMatrix(ShapeNamed(result.scene, "matrix").to_world()).Point({0, 0, 0}), {5, 6, 7});
  // lookat: yarf's camera takes the same origin, direction and up.
  ExpectNear(ToVec(result.scene.camera().origin()), {0, 0, 10});
  ExpectNear(ToVec(result.scene.camera().target()), {0, 0, 9});
  ExpectNear(ToVec(result.scene.camera().up()), {0, 1, 0});
  EXPECT_TRUE(result.warnings.empty()) << result.warnings.front();
}

TEST(MitsubaImport, EveryShapeTypeBecomesAYarfShape) {
  const ImportResult result = Import("mitsuba_shapes.xml");
  const v1::Scene& scene = result.scene;
  EXPECT_EQ(ShapeNamed(scene, "obj").mesh().format(), "obj");
  EXPECT_EQ(ShapeNamed(scene, "ply").mesh().file(), "assets/quad.ply");
  EXPECT_TRUE(ShapeNamed(scene, "ply").flip_normals());
  // shape_index 1 of the serialized file: its square, inlined.
  const v1::Mesh& serialized = ShapeNamed(scene, "serialized").mesh();
  EXPECT_EQ(serialized.positions_size(), 12);
  EXPECT_EQ(serialized.indices_size(), 6);
  EXPECT_FLOAT_EQ(serialized.positions(3), 2.0f);
  const v1::Sphere& sphere = ShapeNamed(scene, "sphere").sphere();
  ExpectNear(ToVec(sphere.center()), {1, 2, 3});
  EXPECT_DOUBLE_EQ(sphere.radius(), 0.5);
  EXPECT_TRUE(ShapeNamed(scene, "rectangle").has_rectangle());
  EXPECT_EQ(ShapeNamed(scene, "cube").mesh().indices_size(), 36);
  EXPECT_EQ(ShapeNamed(scene, "disk").mesh().indices_size(), 3 * 128);
  EXPECT_TRUE(Warns(result, "fans of 128 triangles"));
  // The cylinder: a tube of 128 quads with smooth normals and uv.
  const v1::Mesh& cylinder = ShapeNamed(scene, "cylinder").mesh();
  EXPECT_EQ(cylinder.indices_size(), 6 * 128);
  EXPECT_EQ(cylinder.normals_size(), cylinder.positions_size());
  EXPECT_EQ(cylinder.uvs_size() * 3, cylinder.positions_size() * 2);
  EXPECT_TRUE(Warns(result, "tubes of 128 quads"));
}

TEST(MitsubaImport, CurveFilesBecomeCurvesWithWorldRadii) {
  const ImportResult result = Import("mitsuba_curves.xml");
  const v1::Scene& scene = result.scene;
  const v1::Curves& spline = ShapeNamed(scene, "spline").curves();
  EXPECT_EQ(spline.basis(), v1::Curves::BASIS_BSPLINE);
  EXPECT_EQ(spline.form(), v1::Curves::FORM_ROUND);
  EXPECT_EQ(std::vector<uint32_t>(spline.segments().begin(), spline.segments().end()),
            (std::vector<uint32_t>{0, 1, 5}));
  // Mitsuba's radii are world lengths: yarf's, scaled by to_world's 2,
  // start at half of them.
  EXPECT_FLOAT_EQ(spline.points(3), 0.025f);
  EXPECT_FLOAT_EQ(spline.points(4), 0.2f);  // the second point's x, unscaled
  const v1::SceneShape& lines = ShapeNamed(scene, "lines");
  EXPECT_EQ(lines.curves().basis(), v1::Curves::BASIS_LINEAR);
  EXPECT_EQ(lines.curves().segments_size(), 7);
  EXPECT_FLOAT_EQ(lines.curves().points(3), 0.05f);
  EXPECT_FALSE(lines.has_emitter());
  EXPECT_TRUE(Warns(result, "mitsuba_curves.xml:10: area emitters on curves are not supported"));
}

TEST(MitsubaImport, ShapeGroupsAndInstancesMapToGroupsAndInstances) {
  const v1::Scene scene = Import("mitsuba_shapes.xml").scene;
  ASSERT_EQ(scene.groups_size(), 1);
  EXPECT_EQ(scene.groups(0).name(), "pair");
  EXPECT_EQ(scene.groups(0).shapes_size(), 2);
  ASSERT_EQ(scene.instances_size(), 2);
  EXPECT_EQ(scene.instances(0).group(), "pair");
  ExpectNear(ToMatrix(scene.instances(0).to_world()).Point({0, 0, 0}), {-4, 0, 0});
  ExpectNear(ToMatrix(scene.instances(1).to_world()).Point({0, 0, 0}), {4, 0, 0});
}

TEST(MitsubaImport, BsdfsMapToSurfaceModels) {
  const ImportResult result = Import("mitsuba_materials.xml");
  const v1::Scene& scene = result.scene;
  auto material = [&](const std::string& shape) -> const v1::Material& {
    return MaterialOf(scene, ShapeNamed(scene, shape));
  };
  // A flat 0.5 spectrum over 400–700 nm, as Mitsuba converts it.
  EXPECT_EQ(material("s1").class_name(), "lambertian");
  ExpectNear(RgbProperty(material("s1").properties(), "reflectance"), {0.4977, 0.4999, 0.4975}, 4e-3);
  EXPECT_EQ(material("s2").class_name(), "lambertian");
  ExpectNear(RgbProperty(material("s2").properties(), "reflectance"), {0.2, 0.2, 0.2});
  EXPECT_EQ(material("s3").class_name(), "plastic");
  EXPECT_TRUE(Warns(result, "mitsuba_materials.xml:9: twosided: the back side"));
  EXPECT_EQ(material("s4").class_name(), "conductor");
  EXPECT_EQ(StringProperty(material("s4").properties(), "material"), "Au");
  EXPECT_EQ(material("s5").class_name(), "roughconductor");
  EXPECT_DOUBLE_EQ(FloatProperty(material("s5").properties(), "alpha_u"), 0.05);
  EXPECT_DOUBLE_EQ(FloatProperty(material("s5").properties(), "alpha_v"), 0.3);
  EXPECT_EQ(material("s6").class_name(), "dielectric");
  EXPECT_DOUBLE_EQ(FloatProperty(material("s6").properties(), "int_ior"), 1.3330);  // "water"
  EXPECT_DOUBLE_EQ(FloatProperty(material("s6").properties(), "ext_ior"), 1.000277);  // "air"
  EXPECT_EQ(material("s7").class_name(), "thindielectric");
  EXPECT_DOUBLE_EQ(FloatProperty(material("s7").properties(), "int_ior"), 1.5046);  // bk7
  EXPECT_EQ(material("s8").class_name(), "roughdielectric");
  EXPECT_DOUBLE_EQ(FloatProperty(material("s8").properties(), "alpha"), 0.2);
  // Mitsuba's default distribution, Beckmann, is passed on.
  EXPECT_EQ(StringProperty(material("s8").properties(), "distribution"), "beckmann");
  EXPECT_EQ(material("s9").class_name(), "roughplastic");
  EXPECT_DOUBLE_EQ(FloatProperty(material("s9").properties(), "int_ior"), 1.6);
  EXPECT_EQ(material("s14").class_name(), "conductor");  // brass: not a tabulated metal
  EXPECT_EQ(StringProperty(material("s14").properties(), "material"), "none");
  EXPECT_TRUE(Warns(result, "metal 'CuZn' is not among"));
  ExpectNear(RgbProperty(material("s15").properties(), "specular_reflectance"), {0.5, 0.5, 0.5});
  EXPECT_TRUE(material("s15").properties().values().at("nonlinear").bool_value());
  // Oren and Nayar's model: its slope, its approximation, its sides.
  EXPECT_EQ(material("s16").class_name(), "roughdiffuse");
  EXPECT_DOUBLE_EQ(FloatProperty(material("s16").properties(), "alpha"), 0.7);
  EXPECT_TRUE(material("s16").properties().values().at("use_fast_approx").bool_value());
  EXPECT_FALSE(material("s16").properties().values().at("two_sided").bool_value());
  EXPECT_EQ(material("s17").class_name(), "roughdiffuse");
  EXPECT_DOUBLE_EQ(FloatProperty(material("s17").properties(), "alpha"), 0.2);
  EXPECT_FALSE(material("s17").properties().values().at("use_fast_approx").bool_value());
  EXPECT_TRUE(material("s17").properties().values().at("two_sided").bool_value());
  // pplastic as Mitsuba renders it in RGB, with its roughness and indices.
  EXPECT_EQ(material("s18").class_name(), "pplastic");
  EXPECT_DOUBLE_EQ(FloatProperty(material("s18").properties(), "alpha_u"), 0.1);
  EXPECT_DOUBLE_EQ(FloatProperty(material("s18").properties(), "alpha_v"), 0.2);
  EXPECT_EQ(StringProperty(material("s18").properties(), "distribution"), "beckmann");
  EXPECT_NEAR(FloatProperty(material("s18").properties(), "int_ior"), 1.49, 1e-6);
  EXPECT_EQ(material("s13").name(), "default");
  ExpectNear(RgbProperty(material("s13").properties(), "reflectance"), {0.5, 0.5, 0.5});
}

TEST(MitsubaImport, TexturesBecomeSceneTexturesTheMaterialsReferTo) {
  const ImportResult result = Import("mitsuba_materials.xml");
  const v1::Scene& scene = result.scene;
  const auto texture_of = [&](const std::string& material) -> const v1::ComponentSpec& {
    const v1::Property& value = MaterialNamed(scene, material).properties().values().at("reflectance");
    EXPECT_EQ(value.value_case(), v1::Property::kReference);
    for (const v1::SceneTexture& t : scene.textures())
      if (t.name() == value.reference()) return t.texture();
    ADD_FAILURE() << "no texture named " << value.reference();
    return scene.textures(0).texture();
  };
  ASSERT_EQ(scene.textures_size(), 2);
  const v1::ComponentSpec& bitmap = texture_of("textured");
  EXPECT_EQ(bitmap.class_name(), "bitmap");
  EXPECT_EQ(StringProperty(bitmap.properties(), "filename"), "assets/checker.png");
  const v1::ComponentSpec& checks = texture_of("checks");
  EXPECT_EQ(checks.class_name(), "checkerboard");
  ExpectNear(RgbProperty(checks.properties(), "color0"), {0.2, 0.2, 0.2});
  ExpectNear(RgbProperty(checks.properties(), "color1"), {0.6, 0.6, 0.6});
  EXPECT_FALSE(Warns(result, "mean colour"));
  EXPECT_TRUE(Warns(result, "mitsuba_materials.xml:46: bsdf 'diffuse': parameter 'reflectanse' ignored "
                            "(did you mean 'reflectance'?)"));
}

TEST(MitsubaImport, EmittersBecomeAreaPointAndSpotLights) {
  const ImportResult result = Import("mitsuba_emitters.xml");
  const v1::Scene& scene = result.scene;
  const v1::ComponentSpec& area = ShapeNamed(scene, "panel").emitter();
  EXPECT_EQ(area.class_name(), "diffuse_area");
  ExpectNear(RgbProperty(area.properties(), "radiance"), {5, 4, 3});
  // Then the environment and three directional lights.
  ASSERT_EQ(scene.lights_size(), 6);
  EXPECT_EQ(scene.lights(0).kind(), v1::Light::POSITIONED);
  EXPECT_EQ(scene.lights(0).emitter().class_name(), "point");
  ExpectNear(RgbProperty(scene.lights(0).emitter().properties(), "intensity"), {10, 10, 10});
  ExpectNear(ToMatrix(scene.lights(0).to_world()).Point({0, 0, 0}), {1, 2, 3});
  const v1::Light& spot = scene.lights(1);
  EXPECT_EQ(spot.emitter().class_name(), "spot");
  EXPECT_DOUBLE_EQ(FloatProperty(spot.emitter().properties(), "cutoff_angle"), 30);
  EXPECT_DOUBLE_EQ(FloatProperty(spot.emitter().properties(), "beam_width"), 22.5);
  ExpectNear(ToMatrix(spot.to_world()).Vector({0, 0, 1}), {0, -1, 0});
  ExpectNear(ToMatrix(spot.to_world()).Point({0, 0, 0}), {0, 5, 0});
}

TEST(MitsubaImport, ConstantEmitterBecomesTheEnvironment) {
  const v1::Scene scene = Import("mitsuba_emitters.xml").scene;
  const v1::Light& sky = LightNamed(scene, "sky");
  EXPECT_EQ(sky.kind(), v1::Light::ENVIRONMENT);
  EXPECT_EQ(sky.emitter().class_name(), "constant");
  ExpectNear(RgbProperty(sky.emitter().properties(), "radiance"), {0.5, 1, 2});
  EXPECT_FALSE(sky.has_to_world());
}

TEST(MitsubaImport, DirectionalEmittersTravelAlongDirectionOrTheZOfToWorld) {
  const ImportResult result = Import("mitsuba_emitters.xml");
  const v1::Scene& scene = result.scene;
  const auto expect_directional = [&](const std::string& name, const Vec3d& irradiance, const Vec3d& travel) {
    SCOPED_TRACE(name);
    const v1::Light& light = LightNamed(scene, name);
    EXPECT_EQ(light.kind(), v1::Light::DIRECTIONAL);
    EXPECT_EQ(light.emitter().class_name(), "directional");
    ExpectNear(RgbProperty(light.emitter().properties(), "irradiance"), irradiance);
    const Matrix4 to_world = ToMatrix(light.to_world());
    EXPECT_TRUE(IsRotation(to_world));
    ExpectNear(to_world.Vector({0, 0, 1}), travel);
  };
  expect_directional("sun", {3, 2, 1}, Vec3d{1, -1, 0} * (1 / std::sqrt(2)));
  // to_world scales by 2, then turns +z about x by 90° to -y: a rotation
  // remains.
  expect_directional("tilted", {1, 1, 1}, {0, -1, 0});
  // Mitsuba's defaults: irradiance 1, travelling along +z.
  expect_directional("plain", {1, 1, 1}, {0, 0, 1});
  EXPECT_FALSE(LightNamed(scene, "plain").has_to_world());
  EXPECT_TRUE(Warns(result, "mitsuba_emitters.xml:34: sun and sky models are not supported: emitter 'sunsky'"));
  EXPECT_FALSE(Warns(result, "emitter 'directional'"));  // no parameter ignored
}

TEST(MitsubaImport, EnvmapBecomesAnEnvironmentMapTurnedByItsTransform) {
  const ImportResult result = Import("mitsuba_envmap.xml");
  ASSERT_EQ(result.scene.lights_size(), 1);
  const v1::Light& sky = result.scene.lights(0);
  EXPECT_EQ(sky.name(), "sky");
  EXPECT_EQ(sky.kind(), v1::Light::ENVIRONMENT);
  EXPECT_EQ(sky.emitter().class_name(), "envmap");
  EXPECT_EQ(StringProperty(sky.emitter().properties(), "filename"), "assets/sky.pfm");
  EXPECT_EQ(StringProperty(sky.emitter().properties(), "mapping"), "latlong");
  EXPECT_DOUBLE_EQ(FloatProperty(sky.emitter().properties(), "scale"), 2);
  // Turned by 90° about y (Mitsuba's world mirrored for yarf's camera
  // frame, which leaves a rotation about the vertical a rotation).
  ASSERT_TRUE(sky.has_to_world());
  EXPECT_FALSE(Warns(result, "parameter"));
  EXPECT_FALSE(Warns(result, "not supported"));
}

TEST(MitsubaImport, WithoutASensorMitsubasDefaultCameraIsUsed) {
  const ImportResult result = Import("mitsuba_emitters.xml");
  // A 50 mm lens on a 768×576 film: 38.1848° across x, as Mitsuba reports.
  EXPECT_EQ(result.scene.film().width(), 768u);
  EXPECT_EQ(result.scene.film().height(), 576u);
  EXPECT_EQ(result.scene.film().filter().kind(), v1::ReconstructionFilter::GAUSSIAN);
  EXPECT_NEAR(result.scene.camera().fov(), 38.1848, 1e-4);
  EXPECT_EQ(result.scene.camera().fov_axis(), v1::Camera::X);
  EXPECT_EQ(result.sample_count, 4u);
  EXPECT_TRUE(Warns(result, "the scene has no sensor"));
}

TEST(MitsubaImport, ThinLensAndDiagonalFieldOfView) {
  const v1::Scene scene = Import("mitsuba_camera.xml").scene;
  const v1::Camera& camera = scene.camera();
  EXPECT_EQ(camera.model(), v1::Camera::THIN_LENS);
  EXPECT_DOUBLE_EQ(camera.lens_radius(), 0.1);
  EXPECT_DOUBLE_EQ(camera.focus_distance(), 5);
  // 60° across the 50-pixel diagonal of a 40×30 film is this much across x.
  EXPECT_EQ(camera.fov_axis(), v1::Camera::X);
  EXPECT_NEAR(camera.fov(), 2 * std::atan(std::tan(M_PI / 6) * 40 / 50) * 180 / M_PI, 1e-9);
  EXPECT_EQ(scene.film().filter().kind(), v1::ReconstructionFilter::TENT);
}

TEST(MitsubaImport, AMirroringSensorMirrorsTheWorldAndKeepsLitSides) {
  const v1::Scene scene = Import("mitsuba_camera.xml").scene;
  // Mitsuba draws +x on the left here (the sensor transform scales x by
  // -1): yarf reflects the world about the camera's vertical plane, x = 0.
  ExpectNear(ToVec(scene.camera().origin()), {0, 0, 5});
  ExpectNear(ToVec(scene.camera().target()), {0, 0, 4});
  const v1::SceneShape& right = ShapeNamed(scene, "right");
  ExpectNear(ToMatrix(right.to_world()).Point(ToVec(right.sphere().center())), {-2, 0, 0});
  // The reflection reverses the triangle's winding: turning its winding's
  // normal back keeps the emitting side toward the camera.
  const v1::SceneShape& lit = ShapeNamed(scene, "lit");
  EXPECT_LT(ToMatrix(lit.to_world()).Determinant3(), 0);
  EXPECT_TRUE(lit.flip_winding());
  EXPECT_FALSE(lit.flip_normals());
  EXPECT_FALSE(right.flip_normals());
  EXPECT_FALSE(right.flip_winding());
}

// The importer reads what its user can read: a file beside the scene's
// folder is named relative to it (the client uploads it by hash), and a
// <path> folder is searched as Mitsuba's file resolver does.
TEST(MitsubaImport, NamesFilesOutsideTheSceneFolderAndSearchesPathFolders) {
  EXPECT_EQ(Import("beside/outside.xml").scene.shapes(0).mesh().file(), "../assets/triangle.obj");
  EXPECT_EQ(ShapeNamed(Import("beside/search_path.xml").scene, "found").mesh().file(), "../assets/triangle.obj");
}

// Confined, as for a scene from someone else, the same files are not found.
TEST(MitsubaImport, ConfinedFindsNoFileOutsideTheSceneFolder) {
  ImportOptions confined;
  confined.confine_to_folder = true;
  for (const char* file : {"beside/outside.xml", "beside/search_path.xml"}) {
    try {
      Import(file, confined);
      ADD_FAILURE() << file << " imported although it names a file outside its folder";
    } catch (const ImportError& error) {
      EXPECT_NE(std::string(error.what()).find("not found inside the scene's folder"), std::string::npos)
          << error.what();
    }
  }
  // Files inside it are found as ever.
  EXPECT_GT(Import("mitsuba_include.xml", confined).scene.shapes_size(), 0);
}

TEST(MitsubaImport, MalformedFilesFailWithFileAndLine) {
  const std::pair<const char*, const char*> cases[] = {
      {"malformed/truncated.xml", "truncated.xml:3: malformed XML"},
      {"malformed/wrong_type.xml", "wrong_type.xml:3: <shape type=\"sphere\">: property 'radius' must be"},
      {"malformed/bad_number.xml", "bad_number.xml:3: radius: '1e999' is not a finite number"},
      {"malformed/missing_ref.xml", "missing_ref.xml:3: reference to an unknown id 'nowhere'"},
      {"malformed/missing_path.xml", "missing_path.xml:2: <path>: folder 'nowhere' not found"},
      {"malformed/absurd.xml", "absurd.xml:3: film resolution 100000x100000 is out of range"},
      {"malformed/cycle_a.xml", "cycle_b.xml:2: include cycle"},
      {"malformed/undefined_parameter.xml", "undefined_parameter.xml:3: undefined parameter $size"},
      {"malformed/no_version.xml", "no_version.xml:1: <scene> needs a version"},
      {"malformed/self_reference.xml", "self_reference.xml:2: references nested too deeply"},
      {"malformed/bad_serialized.xml", "bad_serialized.xml:2: not a Mitsuba serialized mesh"},
      {"malformed/two_environments.xml", "two_environments.xml:3: only one environment emitter"},
      {"malformed/short_curve.xml", "short_hair.txt:4: a curve needs at least 4 control points, this one has 3"},
  };
  for (const auto& [file, message] : cases)
    EXPECT_NE(ImportErrorOf(file).find(message), std::string::npos) << file << ": " << ImportErrorOf(file);
}

TEST(Diagnostics, ReportsEachKindOfWarningOnceWithItsFirstPlace) {
  Diagnostics d;
  d.Warn({"a.xml", 3}, "key", "something ignored");
  d.Warn({"a.xml", 9}, "key", "something ignored");
  d.Warn({"b.xml", 1}, "other", "something else");
  EXPECT_EQ(d.Lines(), (std::vector<std::string>{"a.xml:3: something ignored (and 1 more place)",
                                                 "b.xml:1: something else"}));
}

}  // namespace
}  // namespace yarf::importers

namespace yarf::importers {
namespace {

ImportResult MitsubaWithIntegrator(const std::string& integrator) {
  return ImportMitsuba("<scene version=\"3.0.0\">" + integrator + "<shape type=\"sphere\"/></scene>",
                       "scene.xml");
}

TEST(MitsubaImport, IntegratorsMapToTheTransportsThatEstimateTheirImage) {
  const ImportResult ptracer =
      MitsubaWithIntegrator(R"(<integrator type="ptracer"><integer name="max_depth" value="6"/></integrator>)");
  EXPECT_EQ(ptracer.scene.transport().class_name(), "light");
  EXPECT_EQ(testing::IntProperty(ptracer.scene.transport().properties(), "max_depth"), 6);
  EXPECT_FALSE(testing::Warns(ptracer, "integrator"));
  const ImportResult volpath =
      MitsubaWithIntegrator(R"(<integrator type="volpathmis"><integer name="max_depth" value="3"/></integrator>)");
  EXPECT_EQ(volpath.scene.transport().class_name(), "path");
  EXPECT_EQ(testing::IntProperty(volpath.scene.transport().properties(), "max_depth"), 3);
  EXPECT_FALSE(testing::Warns(volpath, "integrator"));
  // moment: its nested integrator renders.
  const ImportResult moment = MitsubaWithIntegrator(
      R"(<integrator type="moment"><integrator type="ptracer"><integer name="max_depth" value="4"/></integrator></integrator>)");
  EXPECT_EQ(moment.scene.transport().class_name(), "light");
  EXPECT_EQ(testing::IntProperty(moment.scene.transport().properties(), "max_depth"), 4);
  EXPECT_FALSE(testing::Warns(moment, "integrator"));
}

TEST(MitsubaImport, AnOrthographicSensorSpansTwoUnitsOfItsScaledSpace) {
  const ImportResult result = ImportMitsuba(
      R"(<scene version="3.0.0"><sensor type="orthographic"><transform name="to_world"><scale value="2"/>)"
      R"(<lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform></sensor><shape type="sphere"/></scene>)",
      "orthographic.xml");
  EXPECT_EQ(result.scene.camera().model(), v1::Camera::ORTHOGRAPHIC);
  EXPECT_EQ(result.scene.camera().fov_axis(), v1::Camera::X);
  EXPECT_NEAR(result.scene.camera().view_size(), 4, 1e-9);
  EXPECT_TRUE(result.warnings.empty());
}

TEST(MitsubaImport, ReconstructionFiltersKeepTheirShape) {
  const auto filter_of = [](const std::string& rfilter) {
    return ImportMitsuba(R"(<scene version="3.0.0"><sensor type="perspective"><film type="hdrfilm">)" + rfilter +
                             "</film></sensor></scene>",
                         "filter.xml")
        .scene.film()
        .filter();
  };
  const v1::ReconstructionFilter mitchell =
      filter_of(R"(<rfilter type="mitchell"><float name="B" value="0.2"/><float name="C" value="0.4"/></rfilter>)");
  EXPECT_EQ(mitchell.kind(), v1::ReconstructionFilter::MITCHELL);
  EXPECT_DOUBLE_EQ(mitchell.radius(), 2);
  EXPECT_DOUBLE_EQ(mitchell.b(), 0.2);
  EXPECT_DOUBLE_EQ(mitchell.c(), 0.4);
  const v1::ReconstructionFilter catmull_rom = filter_of(R"(<rfilter type="catmullrom"/>)");
  EXPECT_EQ(catmull_rom.kind(), v1::ReconstructionFilter::MITCHELL);
  EXPECT_DOUBLE_EQ(catmull_rom.b(), 0);
  EXPECT_DOUBLE_EQ(catmull_rom.c(), 0.5);
  const v1::ReconstructionFilter lanczos =
      filter_of(R"(<rfilter type="lanczos"><integer name="lobes" value="2"/></rfilter>)");
  EXPECT_EQ(lanczos.kind(), v1::ReconstructionFilter::LANCZOS);
  EXPECT_DOUBLE_EQ(lanczos.lobes(), 2);
  EXPECT_DOUBLE_EQ(lanczos.radius(), 2);
  const v1::ReconstructionFilter gaussian =
      filter_of(R"(<rfilter type="gaussian"><float name="stddev" value="0.75"/></rfilter>)");
  EXPECT_EQ(gaussian.kind(), v1::ReconstructionFilter::GAUSSIAN);
  EXPECT_DOUBLE_EQ(gaussian.stddev(), 0.75);
  EXPECT_DOUBLE_EQ(gaussian.radius(), 3);  // Mitsuba's 4 standard deviations
  EXPECT_THROW(filter_of(R"(<rfilter type="gaussian"><float name="stddev" value="0"/></rfilter>)"), ImportError);
  EXPECT_THROW(filter_of(R"(<rfilter type="lanczos"><integer name="lobes" value="0"/></rfilter>)"), ImportError);
}

TEST(MitsubaImport, ACropWindowIsThePartOfTheFilmRendered) {
  const auto crop_of = [](const std::string& crop) {
    return ImportMitsuba(R"(<scene version="3.0.0"><sensor type="perspective"><film type="hdrfilm">)"
                         R"(<integer name="width" value="40"/><integer name="height" value="20"/>)" +
                             crop + "</film></sensor></scene>",
                         "crop.xml")
        .crop;
  };
  EXPECT_EQ(crop_of(""), "");
  EXPECT_EQ(crop_of(R"(<integer name="crop_offset_x" value="4"/><integer name="crop_offset_y" value="2"/>)"
                    R"(<integer name="crop_width" value="10"/><integer name="crop_height" value="8"/>)"),
            "4,14,2,10");
  EXPECT_THROW(crop_of(R"(<integer name="crop_offset_x" value="35"/><integer name="crop_width" value="10"/>)"),
               ImportError);
}

// The import error of a Mitsuba scene given as text, "" when it imports.
std::string ErrorOf(const std::string& xml) {
  try {
    ImportMitsuba(xml, "meter.xml");
  } catch (const ImportError& e) {
    return e.what();
  }
  return "";
}

constexpr const char* kOnePixel = R"(<film type="hdrfilm"><integer name="width" value="1"/>)"
                                  R"(<integer name="height" value="1"/><rfilter type="box"/></film>)";

TEST(MitsubaImport, ARadianceMeterIsOneRayFromItsOriginOrItsToWorld) {
  const ImportResult along = ImportMitsuba(
      std::string(R"(<scene version="3.0.0"><sensor type="radiancemeter"><point name="origin" value="1, 2, 3"/>)"
                  R"(<vector name="direction" value="0, -2, 0"/>)") +
          kOnePixel + "</sensor></scene>",
      "meter.xml");
  const v1::Camera& camera = along.scene.camera();
  EXPECT_EQ(camera.model(), v1::Camera::RADIANCE_METER);
  ExpectNear(ToVec(camera.origin()), {1, 2, 3});
  ExpectNear(ToVec(camera.target()), {1, 0, 3});
  EXPECT_EQ(along.scene.film().filter().kind(), v1::ReconstructionFilter::BOX);
  EXPECT_TRUE(along.warnings.empty()) << along.warnings.front();

  // to_world wins over origin and direction; the ray runs along its +z.
  const ImportResult placed = ImportMitsuba(
      std::string(R"(<scene version="3.0.0"><sensor type="radiancemeter"><point name="origin" value="9, 9, 9"/>)"
                  R"(<vector name="direction" value="1, 0, 0"/><transform name="to_world">)"
                  R"(<lookat origin="0, 1, 0" target="0, 1, -4" up="0, 1, 0"/></transform>)") +
          kOnePixel + "</sensor></scene>",
      "meter.xml");
  ExpectNear(ToVec(placed.scene.camera().origin()), {0, 1, 0});
  ExpectNear(ToVec(placed.scene.camera().target()), {0, 1, -1});
  EXPECT_TRUE(placed.warnings.empty());

  // One value: a film of one pixel, given (Mitsuba's default film is larger).
  EXPECT_NE(ErrorOf(R"(<scene version="3.0.0"><sensor type="radiancemeter"><film type="hdrfilm">)"
                    R"(<integer name="width" value="4"/><integer name="height" value="4"/></film></sensor></scene>)")
                .find("meter.xml:1: sensor 'radiancemeter' measures one value: its film must be 1x1, not 4x4"),
            std::string::npos);
  EXPECT_NE(ErrorOf(R"(<scene version="3.0.0"><sensor type="radiancemeter"/></scene>)").find("needs a 1x1 <film>"),
            std::string::npos);
  EXPECT_NE(ErrorOf(std::string(R"(<scene version="3.0.0"><sensor type="radiancemeter">)"
                                R"(<point name="origin" value="1, 2, 3"/>)") +
                    kOnePixel + "</sensor></scene>")
                .find("give origin and direction together"),
            std::string::npos);
}

TEST(MitsubaImport, AnIrradianceMeterMeasuresOnTheShapeItSitsIn) {
  const ImportResult result = ImportMitsuba(
      std::string(R"(<scene version="3.0.0"><shape type="rectangle" id="floor"/>)"
                  R"(<shape type="rectangle"><sensor type="irradiancemeter"><film type="hdrfilm">)"
                  R"(<integer name="width" value="1"/><integer name="height" value="1"/></film>)"
                  R"(<sampler type="independent"><integer name="sample_count" value="64"/></sampler>)"
                  R"(</sensor></shape></scene>)"),
      "meter.xml");
  const v1::Camera& camera = result.scene.camera();
  EXPECT_EQ(camera.model(), v1::Camera::IRRADIANCE_METER);
  ASSERT_EQ(result.scene.shapes_size(), 2);
  EXPECT_EQ(camera.meter_shape(), result.scene.shapes(1).name());
  EXPECT_NE(result.scene.shapes(0).name(), result.scene.shapes(1).name());
  EXPECT_EQ(result.sample_count, 64u);
  // Mitsuba's default gaussian would weigh the shape's points unevenly.
  EXPECT_EQ(result.scene.film().filter().kind(), v1::ReconstructionFilter::BOX);
  EXPECT_DOUBLE_EQ(result.scene.film().filter().radius(), 0.5);
  EXPECT_TRUE(Warns(result, "the box filter of radius 0.5 used"));
  EXPECT_FALSE(Warns(result, "no sensor"));

  EXPECT_NE(ErrorOf(std::string(R"(<scene version="3.0.0"><shape type="sphere"><sensor type="irradiancemeter">)"
                                R"(<transform name="to_world"><translate x="1"/></transform>)") +
                    kOnePixel + "</sensor></shape></scene>")
                .find("meter.xml:1: sensor 'irradiancemeter' takes no to_world"),
            std::string::npos);
  EXPECT_NE(ErrorOf(std::string(R"(<scene version="3.0.0"><sensor type="irradiancemeter">)") + kOnePixel +
                    "</sensor></scene>")
                .find("must be declared inside the <shape> it measures"),
            std::string::npos);
  EXPECT_NE(ErrorOf(std::string(R"(<scene version="3.0.0"><shape type="sphere"><sensor type="perspective">)") +
                    kOnePixel + "</sensor></shape></scene>")
                .find("only an irradiancemeter can be declared there"),
            std::string::npos);
}

}  // namespace
}  // namespace yarf::importers

namespace yarf::importers {
namespace {

TEST(MitsubaImport, PrincipledBecomesThePrincipledModel) {
  const ImportResult result = ImportMitsuba(
      R"(<scene version="3.0.0"><bsdf type="principled" id="disney"><rgb name="base_color" value="0.8, 0.2, 0.1"/>)"
      R"(<float name="metallic" value="0.3"/><float name="roughness" value="0.4"/><float name="eta" value="1.33"/>)"
      R"(<float name="clearcoat" value="0.5"/><float name="sheen" value="1.4"/>)"
      R"(<float name="clearcoat_sampling_rate" value="2"/></bsdf>)"
      R"(<shape type="sphere" id="ball"><ref id="disney"/></shape></scene>)",
      "principled.xml");
  const v1::Material& material = testing::MaterialOf(result.scene, testing::ShapeNamed(result.scene, "ball"));
  EXPECT_EQ(material.class_name(), "principled");
  const v1::Properties& props = material.properties();
  const Vec3d base = testing::RgbProperty(props, "base_color");
  EXPECT_NEAR(base.x, 0.8, 1e-9);
  EXPECT_NEAR(base.y, 0.2, 1e-9);
  EXPECT_NEAR(base.z, 0.1, 1e-9);
  EXPECT_DOUBLE_EQ(testing::FloatProperty(props, "metallic"), 0.3);
  EXPECT_DOUBLE_EQ(testing::FloatProperty(props, "roughness"), 0.4);
  EXPECT_DOUBLE_EQ(testing::FloatProperty(props, "eta"), 1.33);
  EXPECT_DOUBLE_EQ(testing::FloatProperty(props, "clearcoat"), 0.5);
  EXPECT_DOUBLE_EQ(testing::FloatProperty(props, "clearcoat_sampling_rate"), 2.0);
  // Out of [0, 1]: clamped, with a warning naming the place.
  EXPECT_DOUBLE_EQ(testing::FloatProperty(props, "sheen"), 1.0);
  EXPECT_TRUE(testing::Warns(result, "principled.xml:1: bsdf 'principled': sheen clamped into [0, 1]"));
  // Parameters left out take the model's defaults, which are Mitsuba's.
  EXPECT_EQ(props.values().count("spec_trans"), 0u);
  EXPECT_FALSE(testing::Warns(result, "approximated"));
  // eta and specular are one index of refraction given twice.
  try {
    ImportMitsuba(R"(<scene version="3.0.0"><shape type="sphere"><bsdf type="principled">)"
                  R"(<float name="eta" value="1.5"/><float name="specular" value="0.5"/></bsdf></shape></scene>)",
                  "both.xml");
    ADD_FAILURE() << "eta and specular together were accepted";
  } catch (const ImportError& e) {
    EXPECT_NE(std::string(e.what()).find("give eta or specular"), std::string::npos) << e.what();
  }
}

TEST(MitsubaImport, PrincipledThinBecomesTheThinPrincipledModel) {
  const ImportResult result = ImportMitsuba(
      R"(<scene version="3.0.0"><bsdf type="principledthin" id="leaf"><rgb name="base_color" value="0.3, 0.6, 0.2"/>)"
      R"(<float name="spec_trans" value="0.4"/><float name="diff_trans" value="2.5"/><float name="eta" value="1.33"/>)"
      R"(<texture type="checkerboard" name="roughness"/><float name="sheen" value="0.2"/>)"
      R"(<float name="diffuse_transmittance_sampling_rate" value="2"/></bsdf>)"
      R"(<shape type="sphere" id="ball"><ref id="leaf"/></shape></scene>)",
      "thin.xml");
  const v1::Material& material = testing::MaterialOf(result.scene, testing::ShapeNamed(result.scene, "ball"));
  EXPECT_EQ(material.class_name(), "principledthin");
  const v1::Properties& props = material.properties();
  const Vec3d base = testing::RgbProperty(props, "base_color");
  EXPECT_NEAR(base.y, 0.6, 1e-9);
  EXPECT_DOUBLE_EQ(testing::FloatProperty(props, "spec_trans"), 0.4);
  EXPECT_DOUBLE_EQ(testing::FloatProperty(props, "eta"), 1.33);
  EXPECT_DOUBLE_EQ(testing::FloatProperty(props, "sheen"), 0.2);
  EXPECT_DOUBLE_EQ(testing::FloatProperty(props, "diffuse_transmittance_sampling_rate"), 2.0);
  EXPECT_EQ(props.values().at("roughness").value_case(), v1::Property::kReference);
  // diff_trans reaches 2 (all of the diffuse lobe transmitted), no further.
  EXPECT_DOUBLE_EQ(testing::FloatProperty(props, "diff_trans"), 2.0);
  EXPECT_TRUE(testing::Warns(result, "thin.xml:1: bsdf 'principledthin': diff_trans clamped into [0, 2]"));
  EXPECT_FALSE(testing::Warns(result, "approximated"));
}

}  // namespace
}  // namespace yarf::importers

namespace yarf::importers {
namespace {

TEST(MitsubaImport, AProjectorBecomesAPositionedLightWithItsImageAndFrame) {
  const std::string scene_file = TestScene("projector.xml").string();
  const ImportResult result = ImportMitsuba(
      R"(<scene version="3.0.0"><texture type="bitmap" id="slide"><string name="filename" value="assets/sky.pfm"/>)"
      R"(<string name="wrap_mode" value="clamp"/></texture>)"
      R"(<emitter type="projector" id="beamer"><transform name="to_world">)"
      R"(<lookat origin="0, 3, 0" target="0, 0, 0" up="0, 0, -1"/></transform>)"
      R"(<ref name="irradiance" id="slide"/><float name="scale" value="2"/><float name="fov" value="40"/>)"
      R"(<string name="fov_axis" value="y"/></emitter><shape type="sphere"/></scene>)",
      scene_file);
  const v1::Light& light = LightNamed(result.scene, "beamer");
  EXPECT_EQ(light.kind(), v1::Light::POSITIONED);
  EXPECT_EQ(light.emitter().class_name(), "projector");
  const v1::Properties& props = light.emitter().properties();
  EXPECT_EQ(StringProperty(props, "filename"), "assets/sky.pfm");
  EXPECT_EQ(StringProperty(props, "wrap_mode"), "clamp");
  EXPECT_EQ(StringProperty(props, "fov_axis"), "y");
  EXPECT_DOUBLE_EQ(FloatProperty(props, "scale"), 2);
  EXPECT_DOUBLE_EQ(FloatProperty(props, "fov"), 40);
  // The emitter keeps Mitsuba's to_world for its roll; the light is placed by it.
  ASSERT_TRUE(props.values().count("to_world"));
  const Matrix4 frame = ToMatrix(props.values().at("to_world").transform_value());
  ExpectNear(frame.Vector({0, 0, 1}), {0, -1, 0});
  ExpectNear(frame.Vector({0, 1, 0}), {0, 0, -1});
  ExpectNear(ToMatrix(light.to_world()).Point({0, 0, 0}), {0, 3, 0});
  EXPECT_FALSE(Warns(result, "parameter"));

  // A 35 mm focal length spans the diagonal; bad parameters are refused.
  const ImportResult focal = ImportMitsuba(
      R"(<scene version="3.0.0"><emitter type="projector" id="p"><rgb name="irradiance" value="1, 2, 3"/>)"
      R"(<string name="focal_length" value="50mm"/></emitter></scene>)",
      scene_file);
  const v1::Properties& constant = LightNamed(focal.scene, "p").emitter().properties();
  EXPECT_EQ(StringProperty(constant, "fov_axis"), "diagonal");
  EXPECT_NEAR(FloatProperty(constant, "fov"), 2 * std::atan(std::hypot(36.0, 24.0) / 100) * 180 / M_PI, 1e-9);
  ExpectNear(RgbProperty(constant, "irradiance"), {1, 2, 3});
  for (const auto& [body, message] : std::vector<std::pair<std::string, std::string>>{
           {R"(<float name="fov" value="30"/>)", "give the image to project"},
           {R"(<rgb name="irradiance" value="1"/><float name="fov" value="180"/>)", "fov must lie in (0, 180)"},
           {R"(<rgb name="irradiance" value="1"/><float name="scale" value="-1"/>)", "scale must be finite"},
           {R"(<texture type="checkerboard" name="irradiance"/><float name="fov" value="30"/>)",
            "must be a bitmap texture"},
       }) {
    try {
      ImportMitsuba(R"(<scene version="3.0.0"><emitter type="projector">)" + body + "</emitter></scene>", scene_file);
      ADD_FAILURE() << "accepted: " << body;
    } catch (const ImportError& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace yarf::importers
