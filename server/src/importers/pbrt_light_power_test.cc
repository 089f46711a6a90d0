// pbrt-v4's photometric light parameters: an area light's `power` and an
// image infinite light's `illuminance`.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "importers/importer_test_support.h"

namespace yarf::importers {
namespace {

using namespace testing;

ImportResult Pbrt(const std::string& world, const std::filesystem::path& file = "power.pbrt") {
  return ImportPbrt("WorldBegin\n" + world, file);
}

Vec3d Radiance(const ImportResult& result, int shape = 0) {
  return RgbProperty(result.scene.shapes(shape).emitter().properties(), "radiance");
}

void ExpectGrey(const Vec3d& c, double value, double relative = 1e-6) {
  EXPECT_NEAR(c.x, value, relative * value);
  EXPECT_NEAR(c.y, value, relative * value);
  EXPECT_NEAR(c.z, value, relative * value);
}

// A triangle of legs 2 and 3 (area 3), scaled by 2 in x by the CTM (area 6).
const std::string kTriangle =
    "Scale 2 1 1\n"
    "Shape \"trianglemesh\" \"point3 P\" [0 0 0 2 0 0 0 3 0] \"integer indices\" [0 1 2]\n";

TEST(PbrtLightPower, ATriangleEmitsThePowerOverPiTimesItsAreaAfterTheTransform) {
  ExpectGrey(Radiance(Pbrt("AreaLightSource \"diffuse\" \"float power\" 12\n" + kTriangle)), 12 / (M_PI * 6));
  // Two-sided: the power shared by both sides.
  ExpectGrey(Radiance(Pbrt("AreaLightSource \"diffuse\" \"float power\" 12 \"bool twosided\" true\n" + kTriangle)),
             12 / (2 * M_PI * 6));
  // L and scale multiply (RGB L is taken as given, as pbrt-v4 does).
  const Vec3d coloured =
      Radiance(Pbrt("AreaLightSource \"diffuse\" \"float power\" 12 \"rgb L\" [1 2 3] \"float scale\" 2\n" + kTriangle));
  const double unit = 12 / (M_PI * 6);
  EXPECT_NEAR(coloured.x, 2 * unit, 1e-9);
  EXPECT_NEAR(coloured.y, 4 * unit, 1e-9);
  EXPECT_NEAR(coloured.z, 6 * unit, 1e-9);
  EXPECT_FALSE(Warns(Pbrt("AreaLightSource \"diffuse\" \"float power\" 12\n" + kTriangle), "power"));
}

// pbrt-v4 makes a light per triangle of a mesh, each emitting the power:
// a quad of area A split in two triangles has radiance P / (π A / 2).
TEST(PbrtLightPower, EachTriangleOfAMeshEmitsThePower) {
  const ImportResult quad = Pbrt(
      "AreaLightSource \"diffuse\" \"float power\" 10\n"
      "Shape \"trianglemesh\" \"point3 P\" [0 0 0 2 0 0 2 2 0 0 2 0] \"integer indices\" [0 1 2 0 2 3]\n");
  ExpectGrey(Radiance(quad), 10 / (M_PI * 2));
  EXPECT_FALSE(Warns(quad, "power"));
  // Unequal triangles: one radiance, the mean triangle's, and a warning.
  const ImportResult uneven = Pbrt(
      "AreaLightSource \"diffuse\" \"float power\" 10\n"
      "Shape \"trianglemesh\" \"point3 P\" [0 0 0 2 0 0 2 2 0 0 6 0] \"integer indices\" [0 1 2 0 2 3]\n");
  ExpectGrey(Radiance(uneven), 10 / (M_PI * 4));  // areas 2 and 6
  EXPECT_TRUE(Warns(uneven, "power.pbrt:2: area light power: pbrt-v4 gives each triangle"));
}

TEST(PbrtLightPower, QuadricsUsePbrtsAreas) {
  // A sphere of radius 2: 16π, in object space as pbrt-v4 takes it.
  ExpectGrey(Radiance(Pbrt("AreaLightSource \"diffuse\" \"float power\" 100\n"
                           "Scale 3 3 3 Shape \"sphere\" \"float radius\" 2\n")),
             100 / (M_PI * 16 * M_PI));
  // A disk of radius 2: 4π.
  ExpectGrey(Radiance(Pbrt("AreaLightSource \"diffuse\" \"float power\" 100\n"
                           "Shape \"disk\" \"float radius\" 2\n")),
             100 / (M_PI * 4 * M_PI), 1e-6);
}

TEST(PbrtLightPower, AMeshFromAFileKeepsLAndScale) {
  const ImportResult result = ImportPbrt(
      "WorldBegin\nAreaLightSource \"diffuse\" \"float power\" 10 \"rgb L\" [2 2 2]\n"
      "Shape \"plymesh\" \"string filename\" \"assets/quad.ply\"\n",
      TestScene("power.pbrt"));
  ExpectGrey(Radiance(result), 2);
  EXPECT_TRUE(Warns(result, "power.pbrt:2: area light power on shape 'plymesh' is not supported"));
}

// A constant equal-area map as a PFM file (bottom row first).
std::filesystem::path ConstantMap(const std::string& name, float value, int side) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "yarf_light_power_test";
  std::filesystem::create_directories(dir);
  std::ofstream out(dir / name, std::ios::binary);
  out << "PF\n" << side << " " << side << "\n-1.0\n";
  const std::vector<float> row(size_t(3 * side), value);
  for (int y = 0; y < side; ++y) out.write(reinterpret_cast<const char*>(row.data()), std::streamsize(4 * row.size()));
  return dir / "sky.pbrt";
}

TEST(PbrtLightPower, AnImageInfiniteLightGivesTheIlluminanceAskedFor) {
  const std::filesystem::path scene = ConstantMap("half.pfm", 0.5f, 64);
  const ImportResult result = ImportPbrt(
      "WorldBegin\nLightSource \"infinite\" \"string filename\" \"half.pfm\" \"float illuminance\" 10 "
      "\"float scale\" 3\n",
      scene);
  ASSERT_EQ(result.scene.lights_size(), 1);
  const v1::Light& sky = result.scene.lights(0);
  EXPECT_EQ(sky.emitter().class_name(), "envmap");
  // Radiance 0.5 × the map's scale is E / π, as from a uniform sky, times
  // the light's own scale (pbrt-v4 multiplies scale by E over the map's).
  const double radiance = 0.5 * FloatProperty(sky.emitter().properties(), "scale");
  // (Within the error of a sum over texel centres, 0.1% at 64 × 64.)
  EXPECT_NEAR(radiance, 3 * 10 / M_PI, 3e-3 * 3 * 10 / M_PI);
  EXPECT_FALSE(Warns(result, "illuminance"));
}

TEST(PbrtImageLights, AGoniometricLightScalesToItsPowerAndTurnsItsMapUp) {
  const std::filesystem::path scene = ConstantMap("grey.pfm", 0.25f, 16);
  const ImportResult result = ImportPbrt(
      "WorldBegin\nLightSource \"goniometric\" \"string filename\" \"grey.pfm\" \"float power\" 10 "
      "\"rgb I\" [1 2 3]\n",
      scene);
  ASSERT_EQ(result.scene.lights_size(), 1);
  const v1::Light& light = result.scene.lights(0);
  EXPECT_EQ(light.emitter().class_name(), "goniometric");
  const Vec3d intensity = RgbProperty(light.emitter().properties(), "intensity");
  EXPECT_NEAR(intensity.x, 1, 1e-9);
  EXPECT_NEAR(intensity.z, 3, 1e-9);
  // Φ = 4π · scale · 0.25.
  EXPECT_NEAR(FloatProperty(light.emitter().properties(), "scale"), 10 / (4 * M_PI * 0.25), 1e-6);
  // The map's +z along +y (pbrt-v4's swap of y and z).
  const Vec3d up = ToMatrix(light.to_world()).Vector({0, 0, 1});
  EXPECT_NEAR(up.x, 0, 1e-12);
  EXPECT_NEAR(up.y, 1, 1e-12);
  EXPECT_NEAR(up.z, 0, 1e-12);
  EXPECT_FALSE(Warns(result, "light"));
}

TEST(PbrtImageLights, AProjectionLightProjectsItsImageAsIntensity) {
  const std::filesystem::path scene = ConstantMap("white.pfm", 1, 64);
  const ImportResult result = ImportPbrt(
      "WorldBegin\nLightSource \"projection\" \"string filename\" \"white.pfm\" \"float power\" 5 "
      "\"float scale\" 2\n",
      scene);
  ASSERT_EQ(result.scene.lights_size(), 1);
  const v1::Light& light = result.scene.lights(0);
  EXPECT_EQ(light.emitter().class_name(), "projector");
  const v1::Properties& props = light.emitter().properties();
  EXPECT_EQ(StringProperty(props, "image"), "intensity");
  EXPECT_EQ(StringProperty(props, "fov_axis"), "smaller");
  EXPECT_DOUBLE_EQ(FloatProperty(props, "fov"), 90);  // pbrt-v4's default
  // A white image through a 90° square frustum, of solid angle 2π/3:
  // Φ = scale · 2π/3 (to the error of a sum over texel centres).
  EXPECT_NEAR(FloatProperty(props, "scale"), 2 * 5 / (2 * M_PI / 3), 2e-3 * 2 * 5 / (2 * M_PI / 3));
  EXPECT_FALSE(Warns(result, "light"));
}

}  // namespace
}  // namespace yarf::importers

namespace yarf::importers {
namespace {

using namespace testing;

// The bitmap texture a shape's emitter reads its radiance from.
const v1::SceneTexture& RadianceTexture(const ImportResult& result) {
  const std::string name = result.scene.shapes(0).emitter().properties().values().at("radiance").reference();
  for (const v1::SceneTexture& t : result.scene.textures())
    if (t.name() == name) return t;
  ADD_FAILURE() << "no texture " << name;
  return result.scene.textures(0);
}

TEST(PbrtImageLights, AnImageAreaLightReadsItsImageFlippedAndScaledToItsPower) {
  const std::filesystem::path scene = ConstantMap("glow.pfm", 0.5f, 4);
  const std::string triangle =
      "Shape \"trianglemesh\" \"point3 P\" [0 0 0 2 0 0 0 3 0] \"integer indices\" [0 1 2]\n";
  const ImportResult plain =
      ImportPbrt("WorldBegin\nAreaLightSource \"diffuse\" \"string filename\" \"glow.pfm\" \"float scale\" 3\n" +
                     triangle,
                 scene);
  const v1::SceneTexture& image = RadianceTexture(plain);
  EXPECT_EQ(image.texture().class_name(), "bitmap");
  EXPECT_EQ(StringProperty(image.texture().properties(), "filename"), "glow.pfm");
  EXPECT_NEAR(FloatProperty(image.texture().properties(), "scale"), 3, 1e-9);
  // pbrt looks its image up at (u, 1 − v).
  const Matrix4 to_uv = ToMatrix(image.texture().properties().values().at("to_uv").transform_value());
  const Vec3d corner = to_uv.Point({0, 0, 0});
  EXPECT_NEAR(corner.y, 1, 1e-12);
  EXPECT_FALSE(Warns(plain, "image"));
  // With `power`: Φ = scale · mean luminance (0.5) · π · area (3).
  const ImportResult powered = ImportPbrt(
      "WorldBegin\nAreaLightSource \"diffuse\" \"string filename\" \"glow.pfm\" \"float power\" 6\n" + triangle,
      scene);
  EXPECT_NEAR(FloatProperty(RadianceTexture(powered).texture().properties(), "scale"), 6 / (0.5 * M_PI * 3),
              1e-6);
  // L and an image together are refused, as pbrt refuses them.
  EXPECT_THROW(ImportPbrt("WorldBegin\nAreaLightSource \"diffuse\" \"string filename\" \"glow.pfm\" "
                          "\"rgb L\" [1 1 1]\n" +
                              triangle,
                          scene),
               std::exception);
}

}  // namespace
}  // namespace yarf::importers
