// Participating media from pbrt-v4 (MakeNamedMedium, MediumInterface) and
// Mitsuba 3 (<medium>, <phase>, <volume>): the yarf media, boundaries,
// camera medium and transport each importer makes of them.
#include <gtest/gtest.h>

#include <array>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>

#include "importers/importer_test_support.h"

namespace yarf::importers {
namespace {

using namespace testing;

void ExpectNear(const Vec3d& a, const Vec3d& b, double tolerance = 1e-9) {
  EXPECT_NEAR(a.x, b.x, tolerance);
  EXPECT_NEAR(a.y, b.y, tolerance);
  EXPECT_NEAR(a.z, b.z, tolerance);
}

const v1::SceneMedium& MediumNamed(const v1::Scene& scene, const std::string& name) {
  for (const v1::SceneMedium& m : scene.media())
    if (m.name() == name) return m;
  throw std::runtime_error("no medium named " + name);
}
const v1::Properties& PropertiesOf(const v1::Scene& scene, const std::string& medium) {
  return MediumNamed(scene, medium).medium().properties();
}
bool HasProperty(const v1::Properties& p, const std::string& name) { return p.values().count(name) > 0; }
std::vector<float> FloatsProperty(const v1::Properties& p, const std::string& name) {
  const auto& values = p.values().at(name).float_array_value().values();
  return {values.begin(), values.end()};
}

std::string ErrorOf(const std::function<void()>& import) {
  try {
    import();
  } catch (const ImportError& error) {
    return error.what();
  }
  return "";
}

// pbrt-v4

ImportResult Pbrt(const std::string& text) { return ImportPbrt(text, "media.pbrt"); }

TEST(PbrtMedia, TheVolumetricCausticHasAGasBehindItsInterfaceWall) {
  const ImportResult result = Import("pbrt_volumetric_caustic.pbrt");
  const v1::Scene& scene = result.scene;
  ASSERT_EQ(scene.media_size(), 1);
  EXPECT_EQ(scene.media(0).name(), "gas");
  EXPECT_EQ(scene.media(0).medium().class_name(), "homogeneous");
  ExpectNear(RgbProperty(scene.media(0).medium().properties(), "sigma_a"), {0, 0, 0});
  ExpectNear(RgbProperty(scene.media(0).medium().properties(), "sigma_s"), {1, 1, 1});
  ASSERT_EQ(scene.shapes_size(), 8);
  int walls = 0;
  for (const v1::SceneShape& shape : scene.shapes()) {
    const std::string material = MaterialOf(scene, shape).class_name();
    if (material == "null") {
      // The front wall (normal +z, toward the camera): gas inside.
      EXPECT_EQ(shape.interior(), "gas");
      EXPECT_EQ(shape.exterior(), "");
    } else if (material == "dielectric" || shape.has_emitter()) {
      // The sphere and the light sit in the gas.
      EXPECT_EQ(shape.interior(), "");
      EXPECT_EQ(shape.exterior(), "gas");
    } else {
      EXPECT_EQ(shape.interior() + shape.exterior(), "") << "walls bound no medium";
      ++walls;
    }
  }
  EXPECT_EQ(walls, 5);
  EXPECT_EQ(scene.camera_medium(), "");
  EXPECT_GT(scene.camera().origin().z(), 1);  // outside the box, in vacuum
  // pbrt's maxdepth 7 counts bounces, yarf's max_depth path segments.
  EXPECT_EQ(scene.transport().class_name(), "volpath");
  EXPECT_EQ(IntProperty(scene.transport().properties(), "max_depth"), 8);
  EXPECT_FALSE(Warns(result, "medi"));
}

TEST(PbrtMedia, HomogeneousTakesPbrtsDefaultsScaleAsymmetryAndEmission) {
  const ImportResult result = Pbrt(
      "WorldBegin\n"
      "MakeNamedMedium \"plain\" \"string type\" \"homogeneous\"\n"
      "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [0.1 0.2 0.3]\n"
      "  \"rgb sigma_s\" [1 2 3] \"float scale\" 4 \"float g\" 0.7 \"rgb Le\" [0.5 1 2] \"float Lescale\" 3\n"
      "MediumInterface \"plain\" \"fog\"\n"
      "Shape \"sphere\"\n");
  const v1::Properties& plain = PropertiesOf(result.scene, "plain");
  // pbrt-v4's σ_a and σ_s default to 1.
  ExpectNear(RgbProperty(plain, "sigma_a"), {1, 1, 1});
  ExpectNear(RgbProperty(plain, "sigma_s"), {1, 1, 1});
  EXPECT_FALSE(HasProperty(plain, "g"));
  EXPECT_FALSE(HasProperty(plain, "emission"));
  const v1::Properties& fog = PropertiesOf(result.scene, "fog");
  ExpectNear(RgbProperty(fog, "sigma_a"), {0.1, 0.2, 0.3});
  ExpectNear(RgbProperty(fog, "sigma_s"), {1, 2, 3});
  EXPECT_DOUBLE_EQ(FloatProperty(fog, "scale"), 4);
  EXPECT_DOUBLE_EQ(FloatProperty(fog, "g"), 0.7);
  ExpectNear(RgbProperty(fog, "emission"), {1.5, 3, 6});  // Le × Lescale
  EXPECT_EQ(result.scene.shapes(0).interior(), "plain");
  EXPECT_EQ(result.scene.shapes(0).exterior(), "fog");
  EXPECT_TRUE(result.warnings.empty()) << result.warnings.front();
}

TEST(PbrtMedia, PresetsAreTheMeasuredMediaInPerMillimetreRgb) {
  const ImportResult result = Pbrt(
      "WorldBegin\n"
      "MakeNamedMedium \"skin\" \"string type\" \"homogeneous\" \"string preset\" \"Skin1\" \"float scale\" 10\n"
      "MakeNamedMedium \"milk\" \"string type\" \"homogeneous\" \"string preset\" \"Regular Milk\"\n"
      "MakeNamedMedium \"typo\" \"string type\" \"homogeneous\" \"string preset\" \"Ketchupp\"\n"
      "  \"rgb sigma_a\" [0.5 0.5 0.5]\n");
  const v1::Properties& skin = PropertiesOf(result.scene, "skin");
  ExpectNear(RgbProperty(skin, "sigma_a"), {0.032, 0.17, 0.48});
  ExpectNear(RgbProperty(skin, "sigma_s"), {0.74, 0.88, 1.01});
  EXPECT_DOUBLE_EQ(FloatProperty(skin, "scale"), 10);
  ExpectNear(RgbProperty(PropertiesOf(result.scene, "milk"), "sigma_s"), {4.5513, 5.8294, 7.136});
  // An unknown preset: pbrt-v4 warns and reads sigma_a and sigma_s.
  const v1::Properties& typo = PropertiesOf(result.scene, "typo");
  ExpectNear(RgbProperty(typo, "sigma_a"), {0.5, 0.5, 0.5});
  ExpectNear(RgbProperty(typo, "sigma_s"), {1, 1, 1});
  EXPECT_TRUE(Warns(result, "media.pbrt:4: medium 'homogeneous': preset \"Ketchupp\" is not one of pbrt-v4's "
                            "measured media: sigma_a and sigma_s used (did you mean 'Ketchup'?)"));
}

TEST(PbrtMedia, MediumInterfaceIsAnAttributeAndTheSameMediumBothSidesIsNoBoundary) {
  const ImportResult result = Pbrt(
      "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n"
      "MediumInterface \"\" \"fog\"\n"
      "Camera \"perspective\"\n"
      "WorldBegin\n"
      "AttributeBegin\n"
      "  MediumInterface \"fog\"\n"  // one name: both sides
      "  Shape \"sphere\"\n"
      "  Material \"interface\"\n"
      "  Shape \"sphere\"\n"  // no transition: left out, as pbrt-v4 skips it
      "  MediumInterface \"later\" \"fog\"\n"
      "  Shape \"sphere\"\n"
      "AttributeEnd\n"
      "Shape \"sphere\"\n"
      "MakeNamedMedium \"later\" \"string type\" \"homogeneous\"\n");
  const v1::Scene& scene = result.scene;
  // The camera sits in the outside medium in force where it is declared.
  EXPECT_EQ(scene.camera_medium(), "fog");
  ASSERT_EQ(scene.shapes_size(), 3);
  EXPECT_EQ(scene.shapes(0).interior() + scene.shapes(0).exterior(), "");
  // Media may be named before they are made (pbrt-v4 resolves them last).
  EXPECT_EQ(MaterialOf(scene, scene.shapes(1)).class_name(), "null");
  EXPECT_EQ(scene.shapes(1).interior(), "later");
  EXPECT_EQ(scene.shapes(1).exterior(), "fog");
  // AttributeEnd restores the interface from before: vacuum inside, fog outside.
  EXPECT_EQ(scene.shapes(2).interior(), "");
  EXPECT_EQ(scene.shapes(2).exterior(), "fog");
}

TEST(PbrtMedia, AnUndefinedMediumFailsWhereItIsNamed) {
  const std::string error = ErrorOf([] {
    Pbrt("WorldBegin\nMakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n"
         "MediumInterface \"fgo\" \"\"\nShape \"sphere\"\n");
  });
  EXPECT_NE(error.find("media.pbrt:3: medium 'fgo' is not defined (did you mean 'fog'?)"), std::string::npos)
      << error;
  EXPECT_NE(ErrorOf([] {
              Pbrt("MediumInterface \"\" \"smoke\"\nCamera \"perspective\"\nWorldBegin\n");
            }).find("media.pbrt:1: medium 'smoke' is not defined"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] {
              Pbrt("WorldBegin\nMakeNamedMedium \"a\" \"string type\" \"homogeneous\"\n"
                   "MakeNamedMedium \"a\" \"string type\" \"homogeneous\"\n");
            }).find("media.pbrt:3: named medium 'a' defined twice"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { Pbrt("WorldBegin\nMakeNamedMedium \"a\" \"float g\" 0.5\n"); })
                .find("MakeNamedMedium \"a\" needs a \"string type\""),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { Pbrt("WorldBegin\nMakeNamedMedium \"a\" \"string type\" \"homogeneous\" \"float g\" 1\n"); })
                .find("g must lie in (-1, 1)"),
            std::string::npos);
}

TEST(PbrtMedia, AUniformGridFillsTheBoxP0P1PlacedByTheCtmAtItsDefinition) {
  const ImportResult result = Pbrt(
      "WorldBegin\n"
      "AttributeBegin\n"
      "  Translate 10 0 0\n"
      "  MakeNamedMedium \"smoke\" \"string type\" \"uniformgrid\" \"integer nx\" 2 \"integer ny\" 1 \"integer nz\" 2\n"
      "    \"float density\" [0 1 2 3] \"point3 p0\" [1 2 3] \"point3 p1\" [-1 4 5]\n"
      "    \"rgb sigma_a\" [0.5 0.5 0.5] \"float scale\" 2 \"rgb Le\" [1 2 3] \"float Lescale\" [0 1 0 2]\n"
      "AttributeEnd\n"
      "MediumInterface \"smoke\" \"\"\n"
      "Shape \"sphere\"\n");
  const v1::SceneMedium& smoke = MediumNamed(result.scene, "smoke");
  EXPECT_EQ(smoke.medium().class_name(), "grid");
  const v1::Properties& p = smoke.medium().properties();
  EXPECT_EQ(FloatsProperty(p, "density"), (std::vector<float>{0, 1, 2, 3}));
  EXPECT_EQ(IntProperty(p, "nx"), 2);
  EXPECT_EQ(IntProperty(p, "ny"), 1);
  EXPECT_EQ(IntProperty(p, "nz"), 2);
  ExpectNear(RgbProperty(p, "sigma_a"), {0.5, 0.5, 0.5});
  ExpectNear(RgbProperty(p, "sigma_s"), {1, 1, 1});
  EXPECT_DOUBLE_EQ(FloatProperty(p, "scale"), 2);
  EXPECT_EQ(StringProperty(p, "edge"), "zero");  // pbrt-v4's lookups fade to 0 past the grid
  // Le scaled per voxel by the Lescale grid.
  EXPECT_EQ(FloatsProperty(p, "emission"), (std::vector<float>{0, 0, 0, 1, 2, 3, 0, 0, 0, 2, 4, 6}));
  // The unit cube onto [min(p0, p1), max(p0, p1)], moved by the CTM; and,
  // as the shapes, mirrored in x with the world (pbrt's default camera
  // draws +x to the right).
  const Matrix4 to_world = ToMatrix(p.values().at("to_world").transform_value());
  ExpectNear(to_world.Point({0, 0, 0}), {-9, 2, 3});
  ExpectNear(to_world.Point({1, 1, 1}), {-11, 4, 5});
  EXPECT_TRUE(result.warnings.empty()) << result.warnings.front();

  const ImportResult hot = Pbrt(
      "WorldBegin\nMakeNamedMedium \"fire\" \"string type\" \"uniformgrid\" \"float density\" [1]\n"
      "  \"float temperature\" [1500]\n");
  EXPECT_TRUE(Warns(hot, "media.pbrt:3: medium 'uniformgrid': temperature grids (blackbody emission) are not "
                         "supported: the medium does not emit"));
  EXPECT_FALSE(HasProperty(PropertiesOf(hot.scene, "fire"), "emission"));
  EXPECT_NE(ErrorOf([] {
              Pbrt("WorldBegin\nMakeNamedMedium \"a\" \"string type\" \"uniformgrid\" \"float density\" [1 2 3]\n"
                   "  \"integer nx\" 2\n");
            }).find("3 voxel values given; nx*ny*nz = 2"),
            std::string::npos);
}

TEST(PbrtMedia, AnRgbGridKeepsItsVoxelsColours) {
  const ImportResult result = Pbrt(
      "WorldBegin\n"
      "MakeNamedMedium \"ink\" \"string type\" \"rgbgrid\" \"integer nx\" 2\n"
      "  \"rgb sigma_a\" [1 0 0  0 1 0] \"rgb Le\" [1 1 1  2 2 2] \"float Lescale\" 0.5 \"float g\" -0.3\n");
  const v1::Properties& p = PropertiesOf(result.scene, "ink");
  EXPECT_EQ(FloatsProperty(p, "sigma_a"), (std::vector<float>{1, 0, 0, 0, 1, 0}));
  ExpectNear(RgbProperty(p, "sigma_s"), {1, 1, 1});  // pbrt-v4's 1 where not given
  EXPECT_FALSE(HasProperty(p, "density"));
  EXPECT_EQ(FloatsProperty(p, "emission"), (std::vector<float>{0.5, 0.5, 0.5, 1, 1, 1}));
  EXPECT_DOUBLE_EQ(FloatProperty(p, "g"), -0.3);
  EXPECT_TRUE(result.warnings.empty()) << result.warnings.front();
}

TEST(PbrtMedia, NanoVdbMediaAreLeftOutAndTheirBoundariesSeeVacuum) {
  const ImportResult result = Pbrt(
      "Integrator \"volpath\"\nWorldBegin\n"
      "MakeNamedMedium \"cloud\" \"string type\" \"nanovdb\" \"string filename\" \"bunny.nvdb\"\n"
      "MediumInterface \"cloud\" \"\"\nMaterial \"interface\"\nShape \"sphere\"\n");
  EXPECT_EQ(result.scene.media_size(), 0);
  ASSERT_EQ(result.scene.shapes_size(), 1);
  EXPECT_EQ(result.scene.shapes(0).interior(), "");
  EXPECT_EQ(result.scene.transport().class_name(), "path");  // no media left
  EXPECT_TRUE(Warns(result, "media.pbrt:3: medium 'cloud': NanoVDB files (.nvdb) cannot be read"));
  EXPECT_TRUE(Warns(result, "the medium is left out, and shapes bounding it see vacuum"));
}

TEST(PbrtMedia, CloudsKeepPbrtsParametersAndThePlacement) {
  const ImportResult result = Pbrt(
      "WorldBegin\nTranslate 0 1 0\n"
      "MakeNamedMedium \"sky\" \"string type\" \"cloud\" \"float density\" 2 \"float frequency\" 3\n"
      "  \"point3 p1\" [4 5 6]\n");
  const v1::SceneMedium& sky = MediumNamed(result.scene, "sky");
  EXPECT_EQ(sky.medium().class_name(), "cloud");
  const v1::Properties& p = sky.medium().properties();
  EXPECT_DOUBLE_EQ(FloatProperty(p, "density"), 2);
  EXPECT_DOUBLE_EQ(FloatProperty(p, "wispiness"), 1);
  EXPECT_DOUBLE_EQ(FloatProperty(p, "frequency"), 3);
  ExpectNear(RgbProperty(p, "sigma_a"), {1, 1, 1});
  EXPECT_DOUBLE_EQ(p.values().at("p1").vec3_value().z(), 6);
  ExpectNear(ToMatrix(p.values().at("to_world").transform_value()).Point({0, 0, 0}), {0, 1, 0});
}

TEST(PbrtMedia, VolpathRendersMediaAndOtherIntegratorsSaySoWhenTheyIgnoreThem) {
  const std::string world =
      "WorldBegin\nMakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\nMediumInterface \"fog\" \"\"\n"
      "Shape \"sphere\"\n";
  const ImportResult volpath = Pbrt("Integrator \"volpath\" \"integer maxdepth\" 3\n" + world);
  EXPECT_EQ(volpath.scene.transport().class_name(), "volpath");
  EXPECT_EQ(IntProperty(volpath.scene.transport().properties(), "max_depth"), 4);
  EXPECT_EQ(Pbrt(world).scene.transport().class_name(), "volpath");  // pbrt's default integrator
  const ImportResult path = Pbrt("Integrator \"path\"\n" + world);
  EXPECT_EQ(path.scene.transport().class_name(), "path");
  EXPECT_TRUE(Warns(path, "media.pbrt:1: integrator 'path' does not render participating media: they are "
                          "ignored (pbrt's \"volpath\" renders them)"));
  // Without media volpath is the path tracer.
  EXPECT_EQ(Pbrt("Integrator \"volpath\"\nWorldBegin\nShape \"sphere\"\n").scene.transport().class_name(), "path");
}

TEST(PbrtMedia, AreaLightsOnInterfaceShapesAreIgnoredAsPbrtDoes) {
  const ImportResult result = Pbrt(
      "WorldBegin\nMakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\nMediumInterface \"fog\" \"\"\n"
      "Material \"interface\"\nAreaLightSource \"diffuse\"\nShape \"sphere\"\n");
  ASSERT_EQ(result.scene.shapes_size(), 1);
  EXPECT_FALSE(result.scene.shapes(0).has_emitter());
  EXPECT_TRUE(Warns(result, "media.pbrt:5: area light on a shape of the interface material ignored"));
}

TEST(PbrtMedia, InstancedShapesBoundMediaToo) {
  const ImportResult result = Pbrt(
      "WorldBegin\nMakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n"
      "ObjectBegin \"ball\"\nMediumInterface \"fog\" \"\"\nShape \"sphere\"\nObjectEnd\nObjectInstance \"ball\"\n");
  ASSERT_EQ(result.scene.groups_size(), 1);
  EXPECT_EQ(result.scene.groups(0).shapes(0).interior(), "fog");
}

// Mitsuba 3

ImportResult Mitsuba(const std::string& body, const std::filesystem::path& file = "media.xml") {
  return ImportMitsuba("<scene version=\"3.0.0\">\n" + body + "</scene>\n", file);
}

TEST(MitsubaMedia, HomogeneousSplitsSigmaTByTheAlbedoAndShapesAndTheSensorReferToIt) {
  const ImportResult result = Mitsuba(
      "<integrator type=\"volpath\"><integer name=\"max_depth\" value=\"12\"/>"
      "<integer name=\"rr_depth\" value=\"7\"/></integrator>\n"
      "<medium type=\"homogeneous\" id=\"fog\">\n"
      "  <rgb name=\"sigma_t\" value=\"1, 2, 4\"/> <rgb name=\"albedo\" value=\"0.5, 0.25, 1\"/>\n"
      "  <float name=\"scale\" value=\"3\"/> <boolean name=\"sample_emitters\" value=\"true\"/>\n"
      "  <phase type=\"hg\"><float name=\"g\" value=\"0.4\"/></phase>\n"
      "</medium>\n"
      "<sensor type=\"perspective\"><ref id=\"fog\"/></sensor>\n"
      "<shape type=\"sphere\"><bsdf type=\"null\"/><ref name=\"exterior\" id=\"fog\"/></shape>\n");
  const v1::Scene& scene = result.scene;
  ASSERT_EQ(scene.media_size(), 1);  // one medium, made once
  const v1::Properties& fog = PropertiesOf(scene, "fog");
  EXPECT_EQ(MediumNamed(scene, "fog").medium().class_name(), "homogeneous");
  ExpectNear(RgbProperty(fog, "sigma_s"), {0.5, 0.5, 4});
  ExpectNear(RgbProperty(fog, "sigma_a"), {0.5, 1.5, 0});
  EXPECT_DOUBLE_EQ(FloatProperty(fog, "scale"), 3);
  EXPECT_DOUBLE_EQ(FloatProperty(fog, "g"), 0.4);
  EXPECT_EQ(scene.camera_medium(), "fog");
  ASSERT_EQ(scene.shapes_size(), 1);
  EXPECT_EQ(MaterialOf(scene, scene.shapes(0)).class_name(), "null");
  EXPECT_EQ(scene.shapes(0).exterior(), "fog");
  EXPECT_EQ(scene.shapes(0).interior(), "");
  EXPECT_EQ(scene.transport().class_name(), "volpath");
  EXPECT_EQ(IntProperty(scene.transport().properties(), "max_depth"), 12);
  EXPECT_EQ(IntProperty(scene.transport().properties(), "rr_depth"), 7);
  EXPECT_TRUE(result.warnings.empty()) << result.warnings.front();
}

TEST(MitsubaMedia, InlineMediaConstVolumesAndTheDefaults) {
  const ImportResult result = Mitsuba(
      "<integrator type=\"volpathmis\"/> <sensor type=\"perspective\"/>\n"
      "<shape type=\"sphere\">\n"
      "  <bsdf type=\"dielectric\"/>\n"
      "  <medium name=\"interior\" type=\"homogeneous\">\n"
      "    <volume name=\"sigma_t\" type=\"constvolume\"><rgb name=\"value\" value=\"2, 2, 2\"/></volume>\n"
      "    <phase type=\"isotropic\"/>\n"
      "  </medium>\n"
      "</shape>\n");
  const v1::Scene& scene = result.scene;
  ASSERT_EQ(scene.media_size(), 1);
  EXPECT_EQ(scene.shapes(0).interior(), scene.media(0).name());
  const v1::Properties& p = scene.media(0).medium().properties();
  // Mitsuba's default albedo 0.75.
  ExpectNear(RgbProperty(p, "sigma_s"), {1.5, 1.5, 1.5});
  ExpectNear(RgbProperty(p, "sigma_a"), {0.5, 0.5, 0.5});
  EXPECT_FALSE(HasProperty(p, "g"));
  EXPECT_EQ(scene.transport().class_name(), "volpath");
  EXPECT_EQ(scene.camera_medium(), "");
  EXPECT_TRUE(result.warnings.empty()) << result.warnings.front();
}

TEST(MitsubaMedia, PhaseFunctionsBecomeHenyeyGreensteinLobesRayleighsOrATable) {
  const auto medium_with = [](const std::string& phase) {
    const ImportResult result = Mitsuba("<shape type=\"sphere\"><medium name=\"interior\" type=\"homogeneous\">" +
                                        phase + "</medium></shape>\n");
    return std::pair{result, result.scene.media(0).medium().properties()};
  };
  const auto [hg, hg_props] = medium_with("<phase type=\"hg\"/>");
  EXPECT_DOUBLE_EQ(FloatProperty(hg_props, "g"), 0.8);  // Mitsuba's default
  EXPECT_FALSE(HasProperty(hg_props, "phase"));
  const auto [blend, blend_props] = medium_with(
      "<phase type=\"blendphase\"><float name=\"weight\" value=\"0.25\"/>"
      "<phase name=\"phase_0\" type=\"isotropic\"/>"
      "<phase name=\"phase_1\" type=\"hg\"><float name=\"g\" value=\"-0.5\"/></phase></phase>");
  EXPECT_FALSE(HasProperty(blend_props, "g"));
  EXPECT_DOUBLE_EQ(FloatProperty(blend_props, "g2"), -0.5);
  EXPECT_DOUBLE_EQ(FloatProperty(blend_props, "blend"), 0.25);
  const auto [rayleigh, rayleigh_props] = medium_with("<phase type=\"rayleigh\"/>");
  EXPECT_EQ(StringProperty(rayleigh_props, "phase"), "rayleigh");
  EXPECT_FALSE(HasProperty(rayleigh_props, "g"));
  EXPECT_FALSE(Warns(rayleigh, "phase function"));
  // The default integrator, path, says it ignores the medium.
  EXPECT_TRUE(Warns(rayleigh, "integrator 'path' does not render participating media"));
  const auto [table, table_props] =
      medium_with("<phase type=\"tabphase\"><string name=\"values\" value=\"3, 1 0.5\"/></phase>");
  EXPECT_EQ(StringProperty(table_props, "phase"), "tabulated");
  const auto& values = table_props.values().at("phase_values").float_array_value().values();
  // Scaled to a largest of 1: only the shape matters.
  ASSERT_EQ(values.size(), 3);
  EXPECT_FLOAT_EQ(values[0], 1);
  EXPECT_FLOAT_EQ(values[1], 1.0f / 3);
  EXPECT_FLOAT_EQ(values[2], 0.5f / 3);
  // What yarf has no shape for: isotropic, said once.
  const auto [sggx, sggx_props] = medium_with("<phase type=\"sggx\"/>");
  EXPECT_FALSE(HasProperty(sggx_props, "phase"));
  EXPECT_TRUE(Warns(sggx, "media.xml:2: phase function 'sggx' is not supported: isotropic used"));
  const auto [mixed, mixed_props] = medium_with(
      "<phase type=\"blendphase\"><phase type=\"rayleigh\"/>"
      "<phase type=\"hg\"><float name=\"g\" value=\"0.5\"/></phase></phase>");
  EXPECT_TRUE(Warns(mixed, "only Henyey-Greenstein lobes blend: isotropic used for 'rayleigh'"));
  EXPECT_DOUBLE_EQ(FloatProperty(mixed_props, "g2"), 0.5);
  for (const char* values : {"", "1", "1, -2", "0, 0", "1, x"}) {
    const std::string error = ErrorOf([&] {
      Mitsuba(std::string("<shape type=\"sphere\"><medium name=\"interior\" type=\"homogeneous\">"
                          "<phase type=\"tabphase\"><string name=\"values\" value=\"") +
              values + "\"/></phase></medium></shape>\n");
    });
    EXPECT_NE(error.find("phase 'tabphase': values"), std::string::npos) << "values '" << values << "': " << error;
  }
}

// A Mitsuba .vol grid of one channel in a fresh folder.
class MitsubaGridMedia : public ::testing::Test {
 protected:
  void SetUp() override {
    char pattern[] = "/tmp/yarf-media-XXXXXX";
    ASSERT_NE(mkdtemp(pattern), nullptr);
    folder_ = pattern;
  }
  void TearDown() override { std::filesystem::remove_all(folder_); }

  void WriteVol(const std::string& name, int nx, int ny, int nz, const std::vector<float>& values,
                std::array<float, 6> box = {0, 0, 0, 1, 1, 1}) {
    std::ofstream out(folder_ / name, std::ios::binary);
    const int32_t header[] = {1, nx, ny, nz, int32_t(values.size() / (size_t(nx) * ny * nz))};
    out.write("VOL\x03", 4);
    out.write(reinterpret_cast<const char*>(header), sizeof header);
    out.write(reinterpret_cast<const char*>(box.data()), sizeof box);
    out.write(reinterpret_cast<const char*>(values.data()), std::streamsize(4 * values.size()));
  }
  ImportResult Import(const std::string& body) { return Mitsuba(body, folder_ / "scene.xml"); }

  std::filesystem::path folder_;
};

TEST_F(MitsubaGridMedia, AHeterogeneousSigmaTGridBecomesAGridPlacedByTheVolume) {
  WriteVol("density.vol", 2, 1, 1, {0, 1});
  const ImportResult result = Import(
      "<medium type=\"heterogeneous\" id=\"smoke\">\n"
      "  <volume name=\"sigma_t\" type=\"gridvolume\"><string name=\"filename\" value=\"density.vol\"/>\n"
      "    <transform name=\"to_world\"><scale value=\"2\"/><translate x=\"1\"/></transform></volume>\n"
      "  <rgb name=\"albedo\" value=\"0.9, 0.5, 0.1\"/> <float name=\"scale\" value=\"20\"/>\n"
      "</medium>\n"
      "<shape type=\"cube\"><ref name=\"interior\" id=\"smoke\"/><bsdf type=\"null\"/></shape>\n"
      "<sensor type=\"perspective\"/>\n");
  const v1::SceneMedium& smoke = MediumNamed(result.scene, "smoke");
  EXPECT_EQ(smoke.medium().class_name(), "grid");
  const v1::Properties& p = smoke.medium().properties();
  EXPECT_EQ(StringProperty(p, "filename"), "density.vol");
  ExpectNear(RgbProperty(p, "sigma_s"), {0.9, 0.5, 0.1});
  ExpectNear(RgbProperty(p, "sigma_a"), {0.1, 0.5, 0.9}, 1e-12);
  EXPECT_DOUBLE_EQ(FloatProperty(p, "scale"), 20);
  ExpectNear(ToMatrix(p.values().at("to_world").transform_value()).Point({1, 1, 1}), {3, 2, 2});
  EXPECT_EQ(result.scene.shapes(0).interior(), "smoke");
  EXPECT_TRUE(Warns(result, "integrator 'path' does not render participating media"));
  EXPECT_EQ(result.warnings.size(), 1u) << result.warnings.front();
}

TEST_F(MitsubaGridMedia, AnAlbedoGridAndTheFilesBoundingBox) {
  WriteVol("density.vol", 1, 1, 1, {1}, {-1, -2, -3, 1, 2, 3});
  WriteVol("albedo.vol", 1, 1, 1, {0.5});
  const ImportResult result = Import(
      "<medium type=\"heterogeneous\" id=\"smoke\">\n"
      "  <volume name=\"sigma_t\" type=\"gridvolume\"><string name=\"filename\" value=\"density.vol\"/>\n"
      "    <boolean name=\"use_grid_bbox\" value=\"true\"/></volume>\n"
      "  <volume name=\"albedo\" type=\"gridvolume\"><string name=\"filename\" value=\"albedo.vol\"/></volume>\n"
      "</medium>\n"
      "<shape type=\"cube\"><ref name=\"interior\" id=\"smoke\"/></shape>\n");
  const v1::Properties& p = PropertiesOf(result.scene, "smoke");
  ExpectNear(RgbProperty(p, "sigma_a"), {0, 0, 0});
  ExpectNear(RgbProperty(p, "sigma_s"), {1, 1, 1});
  EXPECT_EQ(StringProperty(p, "albedo_filename"), "albedo.vol");
  // The unit cube onto the file's bounding box.
  const Matrix4 to_world = ToMatrix(p.values().at("to_world").transform_value());
  ExpectNear(to_world.Point({0, 0, 0}), {-1, -2, -3}, 1e-6);
  ExpectNear(to_world.Point({1, 1, 1}), {1, 2, 3}, 1e-6);
  EXPECT_TRUE(Warns(result, "the albedo grid is placed as the sigma_t grid"));
}

TEST_F(MitsubaGridMedia, GridsWhereAConstantIsTakenAreReplacedByTheirMean) {
  WriteVol("albedo.vol", 2, 1, 1, {0.25, 0.75});
  const ImportResult result = Import(
      "<medium type=\"homogeneous\" id=\"milk\"><float name=\"sigma_t\" value=\"2\"/>\n"
      "  <volume name=\"albedo\" type=\"gridvolume\"><string name=\"filename\" value=\"albedo.vol\"/></volume>\n"
      "</medium>\n"
      "<shape type=\"sphere\"><ref name=\"interior\" id=\"milk\"/></shape>\n");
  ExpectNear(RgbProperty(PropertiesOf(result.scene, "milk"), "sigma_s"), {1, 1, 1});
  EXPECT_TRUE(Warns(result, "scene.xml:3: medium 'homogeneous': a grid albedo where yarf's medium takes a "
                            "constant: replaced by the grid's mean"));
}

TEST(MitsubaMedia, AConstantHeterogeneousMediumFillsItsVolumesUnitCube) {
  const ImportResult result = Mitsuba(
      "<medium type=\"heterogeneous\" id=\"box\">\n"
      "  <volume name=\"sigma_t\" type=\"constvolume\"><float name=\"value\" value=\"3\"/>\n"
      "    <transform name=\"to_world\"><scale value=\"4\"/></transform></volume>\n"
      "  <float name=\"albedo\" value=\"0.5\"/>\n"
      "</medium>\n"
      "<shape type=\"sphere\"><ref name=\"interior\" id=\"box\"/></shape>\n");
  const v1::Properties& p = PropertiesOf(result.scene, "box");
  EXPECT_EQ(MediumNamed(result.scene, "box").medium().class_name(), "grid");
  EXPECT_EQ(FloatsProperty(p, "density"), std::vector<float>{1});
  EXPECT_EQ(IntProperty(p, "nx"), 1);
  ExpectNear(RgbProperty(p, "sigma_s"), {1.5, 1.5, 1.5});
  ExpectNear(RgbProperty(p, "sigma_a"), {1.5, 1.5, 1.5});
  ExpectNear(ToMatrix(p.values().at("to_world").transform_value()).Point({1, 1, 1}), {4, 4, 4});
}

TEST(MitsubaMedia, NullBsdfsBoundMediaOrEmitAndAreLeftOutOtherwise) {
  const ImportResult result = Mitsuba(
      "<sensor type=\"perspective\"/> <shape type=\"sphere\"><bsdf type=\"null\"/></shape>\n"
      "<shape type=\"sphere\" id=\"lamp\"><bsdf type=\"null\"/><emitter type=\"area\"/></shape>\n");
  ASSERT_EQ(result.scene.shapes_size(), 1);
  EXPECT_EQ(result.scene.shapes(0).name(), "lamp");
  EXPECT_EQ(MaterialOf(result.scene, result.scene.shapes(0)).class_name(), "null");
  EXPECT_TRUE(result.warnings.empty()) << result.warnings.front();
}

TEST(MitsubaMedia, LightsMayNameTheMediumTheySitIn) {
  const ImportResult result = Mitsuba(
      "<sensor type=\"perspective\"/>\n"
      "<medium type=\"homogeneous\" id=\"fog\"><boolean name=\"sample_emitters\" value=\"false\"/></medium>\n"
      "<emitter type=\"point\"><ref id=\"fog\"/></emitter>\n"
      "<shape type=\"sphere\"><ref name=\"interior\" id=\"fog\"/>"
      "<emitter type=\"area\"><ref name=\"medium\" id=\"fog\"/></emitter></shape>\n");
  ASSERT_EQ(result.scene.lights_size(), 1);
  EXPECT_TRUE(result.scene.shapes(0).has_emitter());
  // Only what changes noise, not the image, is said.
  ASSERT_EQ(result.warnings.size(), 2u);
  EXPECT_TRUE(Warns(result, "media.xml:3: medium 'homogeneous': sample_emitters false is not supported"));
  EXPECT_TRUE(Warns(result, "integrator 'path' does not render participating media"));
}

TEST(MitsubaMedia, BadReferencesFailWithTheirPlace) {
  EXPECT_NE(ErrorOf([] { Mitsuba("<shape type=\"sphere\"><ref name=\"interior\" id=\"fgo\"/></shape>\n"); })
                .find("media.xml:2: reference to an unknown id 'fgo'"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] {
              Mitsuba("<bsdf type=\"diffuse\" id=\"white\"/>\n"
                      "<shape type=\"sphere\"><ref name=\"exterior\" id=\"white\"/></shape>\n");
            }).find("media.xml:2: <shape type=\"sphere\">: 'exterior' must be a <medium>, not <bsdf>"),
            std::string::npos);
  const ImportResult unknown = Mitsuba(
      "<medium type=\"fog\" id=\"f\"/>\n<shape type=\"sphere\"><ref name=\"interior\" id=\"f\"/></shape>\n");
  EXPECT_EQ(unknown.scene.media_size(), 0);
  EXPECT_EQ(unknown.scene.shapes(0).interior(), "");
  EXPECT_TRUE(Warns(unknown, "media.xml:2: medium 'fog' is not supported: left out (vacuum)"));
}

}  // namespace
}  // namespace yarf::importers
