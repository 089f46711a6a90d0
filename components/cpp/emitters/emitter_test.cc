// Tests of the emitter plugins (emitters/*.cc), loaded through the
// registry as yarfd loads them: where each emits, that SampleDirection
// agrees with PdfDirection, that each density integrates to one, and that
// an area light's radiance may be a texture.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <cmath>
#include <algorithm>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "../textures/temporary_folder.h"
#include "components/registry.h"
#include "yarf/support/hash.h"
#include "yarf/surface.h"
#include "yarf/texture.h"
#include "yarf/support/warps.h"

namespace yarf {
namespace {

class EmitterTest : public testing::Test {
 protected:
  EmitterTest() : folder_("yarf-emitter-test") { registry_.LoadDirectory(YARF_PLUGIN_DIR); }

  // A float RGB image of `width` × `height` in the test's folder: texel
  // (x, y) is Sky(x, y), with black texels and a bright one, so that
  // sampling by the image matters.
  static Vec3 Sky(int x, int y) {
    if (x == 5 && y == 2) return Vec3(400, 300, 200);
    if ((x + y) % 5 == 0) return Vec3();
    return Vec3(0.1f * float(x + 1), 0.2f * float(y + 1), 0.5f);
  }
  std::filesystem::path WriteSky(const std::string& name, int width, int height) const {
    std::vector<float> texels;
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x)
        for (int c = 0; c < 3; ++c) texels.push_back(Sky(x, y)[c]);
    const std::filesystem::path path = folder_.path() / name;
    auto out = OIIO::ImageOutput::create(path.string());
    EXPECT_TRUE(out && out->open(path.string(), OIIO::ImageSpec(width, height, 3, OIIO::TypeFloat)));
    EXPECT_TRUE(out->write_image(OIIO::TypeFloat, texels.data()));
    out->close();
    return path;
  }
  Properties EnvironmentMap(const std::string& mapping, int width, int height, double scale = 1) const {
    Properties props;
    props.Set("filename", WriteSky(mapping + ".exr", width, height));
    props.Set("mapping", mapping);
    props.Set("scale", scale);
    return props;
  }

  // A projector of the Sky image (width × height), fov along x.
  Properties Projector(int width, int height, double fov, double scale = 1) const {
    Properties props;
    props.Set("filename", WriteSky("projected_" + std::to_string(width) + "x" + std::to_string(height) + ".exr",
                                   width, height));
    props.Set("fov", fov);
    props.Set("scale", scale);
    return props;
  }
  // A goniometric light of the Sky image (side × side), intensity (1, 2, 3).
  Properties Goniometric(int side, double scale = 1) const {
    Properties props;
    props.Set("filename", WriteSky("goniometric_" + std::to_string(side) + ".exr", side, side));
    props.Set("intensity", Rgb{Vec3(1, 2, 3)});
    props.Set("scale", scale);
    return props;
  }
  // A to_world that rotates 30° about x, stretches x by 1.5 and shrinks z
  // to 0.8, and moves the light: not rigid.
  static Transform Stretched() {
    const double c = std::cos(kPi / 6), s = std::sin(kPi / 6);
    Transform t;
    t.m = {1.5, 0, 0, 1, 0, c, -0.8 * s, 2, 0, s, 0.8 * c, 3, 0, 0, 0, 1};
    return t;
  }

  std::unique_ptr<Emitter> Make(const std::string& name, const Properties& props) const {
    return registry_.CreateAs<Emitter>(name, props);
  }

  std::string CreationError(const std::string& name, const Properties& props) const {
    try {
      registry_.Create(name, props);
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  }

  // Every emitter class, each with a valid configuration.
  std::vector<std::pair<std::string, std::unique_ptr<Emitter>>> All() const {
    Properties area, two_sided, sky, point, spot;
    area.Set("radiance", Rgb{Vec3(1, 2, 3)});
    two_sided.Set("radiance", Rgb{Vec3(1, 2, 3)});
    two_sided.Set("two_sided", true);
    sky.Set("radiance", Rgb{Vec3(1, 2, 3)});
    point.Set("intensity", Rgb{Vec3(1, 2, 3)});
    spot.Set("intensity", Rgb{Vec3(1, 2, 3)});
    spot.Set("cutoff_angle", 30.0);
    spot.Set("beam_width", 20.0);
    std::vector<std::pair<std::string, std::unique_ptr<Emitter>>> all;
    all.emplace_back("diffuse_area", Make("diffuse_area", area));
    all.emplace_back("diffuse_area (two-sided)", Make("diffuse_area", two_sided));
    all.emplace_back("constant", Make("constant", sky));
    all.emplace_back("point", Make("point", point));
    all.emplace_back("spot", Make("spot", spot));
    all.emplace_back("envmap (latlong)", Make("envmap", EnvironmentMap("latlong", 16, 8)));
    all.emplace_back("envmap (equal_area)", Make("envmap", EnvironmentMap("equal_area", 8, 8)));
    // Wide frusta: the midpoint rule below resolves their cells.
    all.emplace_back("projector", Make("projector", Projector(8, 6, 100)));
    Properties stretched = Projector(8, 6, 90);
    stretched.Set("to_world", Stretched());
    stretched.Set("wrap_mode", std::string("clamp"));
    all.emplace_back("projector (stretched, clamped)", Make("projector", stretched));
    Properties intensity_image = Projector(8, 6, 100);
    intensity_image.Set("image", std::string("intensity"));
    all.emplace_back("projector (intensity image)", Make("projector", intensity_image));
    all.emplace_back("goniometric", Make("goniometric", Goniometric(8)));
    Properties stretched_goniometric = Goniometric(8);
    stretched_goniometric.Set("to_world", Stretched());
    all.emplace_back("goniometric (stretched)", Make("goniometric", stretched_goniometric));
    return all;
  }

  textures::TemporaryFolder folder_;
  Registry registry_;
};

Vec3 RadianceToward(const Emitter& emitter, Vec3 w) {
  float dir[3], uv[2] = {0, 0}, radiance[3];
  w.Store(dir);
  emitter.Radiance(dir, SurfacePoints{.uv = uv}, radiance);
  return Vec3::Load(radiance);
}

TEST_F(EmitterTest, DiffuseAreaEmitsFromTheFrontOnly) {
  Properties props;
  props.Set("radiance", Rgb{Vec3(1, 2, 3)});
  const auto emitter = Make("diffuse_area", props);
  EXPECT_EQ(emitter->Describe().interfaces, std::vector<std::string>{Emitter::kInterface});
  const std::vector<float> w = {0, 0, 1, 0.6f, 0, 0.8f, 0, 0.6f, -0.8f, 1, 0, 0};
  const std::vector<float> uv(8, 0.0f);
  std::vector<float> radiance(12, -1.0f);
  emitter->Radiance(w, SurfacePoints{.uv = uv}, radiance);
  EXPECT_EQ(radiance, (std::vector<float>{1, 2, 3, 1, 2, 3, 0, 0, 0, 0, 0, 0}));
}

TEST_F(EmitterTest, PointShinesEverywhere) {
  Properties props;
  props.Set("intensity", 2.0);
  const auto emitter = Make("point", props);
  for (Vec3 w : {Vec3(0, 0, 1), Vec3(0, 0, -1), Vec3(1, 0, 0)})
    EXPECT_EQ(RadianceToward(*emitter, w).x, 2.0f);
}

TEST_F(EmitterTest, SpotFallsOffLinearlyInAngleBetweenBeamAndCutoff) {
  Properties props;
  props.Set("intensity", 4.0);
  props.Set("cutoff_angle", 30.0);
  props.Set("beam_width", 20.0);
  const auto emitter = Make("spot", props);
  const auto at = [&](double degrees) {
    const float t = float(degrees * kPi / 180);
    return RadianceToward(*emitter, Vec3(std::sin(t), 0, std::cos(t))).x;
  };
  EXPECT_EQ(at(0), 4.0f);
  EXPECT_EQ(at(19.9), 4.0f);
  EXPECT_NEAR(at(25), 2.0f, 1e-3f);
  EXPECT_NEAR(at(27.5), 1.0f, 1e-3f);
  EXPECT_EQ(at(30.1), 0.0f);
  EXPECT_EQ(at(120), 0.0f);
}

TEST_F(EmitterTest, SpotFallsOffAsPbrtBySmoothstepInCosine) {
  Properties props;
  props.Set("intensity", 4.0);
  props.Set("cutoff_angle", 30.0);
  props.Set("beam_width", 10.0);
  props.Set("falloff", std::string("smoothstep"));
  const auto emitter = Make("spot", props);
  const auto at = [&](double degrees) {
    const float t = float(degrees * kPi / 180);
    return RadianceToward(*emitter, Vec3(std::sin(t), 0, std::cos(t))).x;
  };
  const float cos_end = std::cos(30 * kPi / 180), cos_start = std::cos(10 * kPi / 180);
  for (const double degrees : {12.0, 20.0, 25.0, 29.0}) {
    const float x = (std::cos(float(degrees * kPi / 180)) - cos_end) / (cos_start - cos_end);
    EXPECT_NEAR(at(degrees), 4 * x * x * (3 - 2 * x), 1e-4f) << degrees;
  }
  EXPECT_EQ(at(9.9), 4.0f);
  EXPECT_EQ(at(30.1), 0.0f);
  props.Set("falloff", std::string("cubic"));
  EXPECT_NE(CreationError("spot", props).find("'falloff'"), std::string::npos);
}

TEST_F(EmitterTest, SampledDirectionsCarryTheirDensity) {
  for (const auto& [name, emitter] : All()) {
    constexpr size_t kCount = 4096;
    std::vector<float> u(2 * kCount), w(3 * kCount), pdf(kCount), check(kCount);
    for (size_t k = 0; k < 2 * kCount; ++k) u[k] = ToUnitFloat(uint32_t(Hash(7, k) >> 32));
    emitter->SampleDirection(u, w, pdf);
    emitter->PdfDirection(w, check);
    for (size_t k = 0; k < kCount; ++k) {
      ASSERT_NEAR(Length(Vec3::Load(&w[3 * k])), 1.0f, 1e-4f) << name;
      ASSERT_GT(pdf[k], 0.0f) << name;
      ASSERT_NEAR(pdf[k], check[k], 1e-3f * pdf[k]) << name;
      // Sampling never wastes a direction the light does not shine into.
      ASSERT_GT(MaxComponent(RadianceToward(*emitter, Vec3::Load(&w[3 * k]))), 0.0f) << name;
    }
  }
}

TEST_F(EmitterTest, DirectionDensitiesIntegrateToOne) {
  for (const auto& [name, emitter] : All()) {
    // Midpoint rule over (cos θ, φ), which has the solid-angle measure.
    constexpr int kRows = 2000, kCols = 1024;
    std::vector<float> w(3 * kRows * kCols), pdf(kRows * kCols);
    for (int i = 0; i < kRows; ++i)
      for (int j = 0; j < kCols; ++j) {
        const float z = -1 + (i + 0.5f) * 2 / kRows, phi = (j + 0.5f) * 2 * kPi / kCols;
        const float r = std::sqrt(std::max(0.0f, 1 - z * z));
        Vec3(r * std::cos(phi), r * std::sin(phi), z).Store(&w[3 * (i * kCols + j)]);
      }
    emitter->PdfDirection(w, pdf);
    double sum = 0;
    for (float p : pdf) sum += p;
    EXPECT_NEAR(sum * (2.0 / kRows) * (2 * kPi / kCols), 1.0, 2e-3) << name;
  }
}

TEST_F(EmitterTest, PropertiesAreChecked) {
  EXPECT_NE(CreationError("diffuse_area", Properties()).find("'radiance'"), std::string::npos);
  EXPECT_NE(CreationError("point", Properties()).find("'intensity'"), std::string::npos);
  Properties negative;
  negative.Set("intensity", -1.0);
  EXPECT_NE(CreationError("point", negative).find("non-negative"), std::string::npos);
  Properties wide;
  wide.Set("intensity", 1.0);
  wide.Set("cutoff_angle", 100.0);
  EXPECT_NE(CreationError("spot", wide).find("'cutoff_angle'"), std::string::npos);
  Properties beam;
  beam.Set("intensity", 1.0);
  beam.Set("cutoff_angle", 20.0);
  beam.Set("beam_width", 25.0);
  EXPECT_NE(CreationError("spot", beam).find("'beam_width'"), std::string::npos);
}

// Radiance (4u - 1, 4v, 2): negative where u < 1/4.
class UvRadiance final : public Texture {
 public:
  uint32_t Channels() const override { return 3; }
  void Evaluate(const SurfacePoints& at, std::span<float> value) const override {
    for (size_t k = 0; k < at.Count(); ++k) At(at.uv[2 * k], at.uv[2 * k + 1]).Store(&value[3 * k]);
  }
  std::vector<float> Mean() const override { return {1, 2, 2}; }

  static Vec3 At(float u, float v) { return Vec3(4 * u - 1, 4 * v, 2); }
};

TEST_F(EmitterTest, AreaRadianceMayBeATextureLookedUpAtUv) {
  Properties props;
  props.Set("radiance", std::shared_ptr<const Texture>(std::make_shared<const UvRadiance>()));
  const auto emitter = Make("diffuse_area", props);
  const float uv[8] = {0.5f, 0.25f, 0.9f, 0.75f, 0.1f, 0.5f, 0.5f, 0.25f};
  float w[12], radiance[12];
  for (int k = 0; k < 4; ++k) Vec3(0, 0, k == 3 ? -1.0f : 1.0f).Store(&w[3 * k]);
  emitter->Radiance(w, SurfacePoints{.uv = uv}, radiance);
  for (int k = 0; k < 3; ++k) {
    const Vec3 expected = UvRadiance::At(uv[2 * k], uv[2 * k + 1]);
    // Negative values clamped to 0.
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(radiance[3 * k + c], std::max(0.0f, expected[c]))
          << "row " << k << " channel " << c;
  }
  // Nothing from the back.
  for (int c = 0; c < 3; ++c) EXPECT_EQ(radiance[9 + c], 0.0f);
}

TEST_F(EmitterTest, AreaRadianceReferringToNoTextureIsAnError) {
  Properties props;
  props.Set("radiance", Reference{"sky"});
  EXPECT_NE(CreationError("diffuse_area", props)
                .find("property 'radiance' refers to 'sky', which is not a texture of the scene"),
            std::string::npos);
}

}  // namespace
}  // namespace yarf

namespace yarf {
namespace {

TEST_F(EmitterTest, ATwoSidedAreaLightEmitsAlikeFromBothSides) {
  Properties props;
  props.Set("radiance", Rgb{Vec3(1, 2, 3)});
  props.Set("two_sided", true);
  const auto light = Make("diffuse_area", props);
  for (const float z : {0.8f, -0.8f}) {
    const Vec3 l = RadianceToward(*light, Normalize(Vec3(0.3f, 0.1f, z)));
    EXPECT_EQ(l.x, 1.0f);
    EXPECT_EQ(l.z, 3.0f);
  }
  props.Set("two_sided", false);
  EXPECT_EQ(MaxComponent(RadianceToward(*Make("diffuse_area", props), Normalize(Vec3(0.3f, 0.1f, -0.8f)))), 0.0f);
}

}  // namespace
}  // namespace yarf

namespace yarf {
namespace {

TEST_F(EmitterTest, AnEnvironmentMapShowsItsTexelsWhereMitsubaAndPbrtPutThem) {
  // Mitsuba's latitude-longitude map: texel (x, y) of a W × H image seen
  // toward u = (x + ½) / W, v = y / (H − 1), where d = (sin θ sin φ, cos θ,
  // −sin θ cos φ) with φ = 2πu, θ = πv; w is the direction of travel, −d.
  const auto latlong = Make("envmap", EnvironmentMap("latlong", 16, 8, 2));
  for (const auto& [x, y] : {std::pair{5, 2}, {0, 1}, {3, 6}, {15, 4}, {8, 3}}) {
    const float phi = 2 * kPi * (float(x) + 0.5f) / 16, theta = kPi * float(y) / 7;
    const Vec3 d(std::sin(theta) * std::sin(phi), std::cos(theta), -std::sin(theta) * std::cos(phi));
    const Vec3 l = RadianceToward(*latlong, -d), expected = Sky(x, y) * 2;
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(l[c], expected[c], 1e-3f * (1 + expected[c])) << x << " " << y;
  }
  // Halfway between two texels of a row: their mean (bilinear).
  const float phi = 2 * kPi * 7 / 16, theta = kPi * 3 / 7;
  const Vec3 d(std::sin(theta) * std::sin(phi), std::cos(theta), -std::sin(theta) * std::cos(phi));
  const Vec3 mean = (Sky(6, 3) + Sky(7, 3)) * 0.5f * 2;
  EXPECT_NEAR(RadianceToward(*latlong, -d).y, mean.y, 1e-3f);
  // pbrt-v4's equal-area square, +z up: the centre texels look up, the
  // corners down; each texel is seen as it is (no interpolation).
  const auto square = Make("envmap", EnvironmentMap("equal_area", 8, 8));
  EXPECT_EQ(RadianceToward(*square, Vec3(0, 0, -1)).x, Sky(4, 4).x);
  // Straight down is every corner; just beside it, one.
  EXPECT_EQ(RadianceToward(*square, Normalize(Vec3(-0.01f, -0.01f, 1))).x, Sky(7, 7).x);
  // Near +x is just below the middle of the right edge, near +y just
  // right of the middle of the bottom edge.
  EXPECT_EQ(RadianceToward(*square, -Normalize(Vec3(1, 0.05f, 0.05f))).y, Sky(7, 4).y);
  EXPECT_EQ(RadianceToward(*square, -Normalize(Vec3(0.05f, 1, 0.05f))).x, Sky(4, 7).x);
}

TEST_F(EmitterTest, AnEnvironmentMapIsSampledByItsBrightness) {
  // The bright texel holds most of the power: most samples go there.
  const auto latlong = Make("envmap", EnvironmentMap("latlong", 16, 8));
  constexpr size_t kCount = 4096;
  std::vector<float> u(2 * kCount), w(3 * kCount), pdf(kCount);
  for (size_t k = 0; k < 2 * kCount; ++k) u[k] = ToUnitFloat(uint32_t(Hash(3, k) >> 32));
  latlong->SampleDirection(u, w, pdf);
  size_t near_sun = 0;
  const float phi = 2 * kPi * 5.5f / 16, theta = kPi * 2 / 7;
  const Vec3 sun(std::sin(theta) * std::sin(phi), std::cos(theta), -std::sin(theta) * std::cos(phi));
  for (size_t k = 0; k < kCount; ++k) near_sun += Dot(-Vec3::Load(&w[3 * k]), sun) > 0.8f;
  EXPECT_GT(near_sun, kCount * 3 / 4);
}

TEST_F(EmitterTest, AnEnvironmentMapRefusesWhatItCannotRead) {
  Properties props = EnvironmentMap("latlong", 16, 8);
  props.Set("mapping", std::string("mirrorball"));
  EXPECT_NE(CreationError("envmap", props).find("'mapping'"), std::string::npos);
  EXPECT_NE(CreationError("envmap", EnvironmentMap("equal_area", 16, 8)).find("square"), std::string::npos);
  Properties missing;
  missing.Set("filename", folder_.path() / "missing.exr");
  EXPECT_NE(CreationError("envmap", missing).find("does not exist"), std::string::npos);
  Properties negative = EnvironmentMap("latlong", 16, 8, -1);
  EXPECT_NE(CreationError("envmap", negative).find("'scale'"), std::string::npos);
}

}  // namespace
}  // namespace yarf

namespace yarf {
namespace {

// The camera-space direction toward the image point (u, v) of a projector
// whose plane z = 1 spans tan_x × tan_y either side of its axis: Mitsuba's
// camera space, x to the left, so u = 0 (the left column) is at +x and
// v = 0 (the top row) at +y.
Vec3 TowardImage(float u, float v, float tan_x, float tan_y) {
  return Vec3((1 - 2 * u) * tan_x, (1 - 2 * v) * tan_y, 1);
}

TEST_F(EmitterTest, AProjectorShinesItsTexelsAsMitsubaDoes) {
  // Intensity π · scale · E(u, v) / cos³θ (Mitsuba 3's projector), E looked
  // up as its bitmap texture (texel centres at (x + ½) / W, (y + ½) / H).
  constexpr int kWidth = 8, kHeight = 6;
  const auto projector = Make("projector", Projector(kWidth, kHeight, 60, 2));
  const float tan_x = std::tan(kPi / 6), tan_y = tan_x * kHeight / kWidth;
  const auto expect_texels = [&](float u, float v, Vec3 expected, const std::string& what) {
    const Vec3 q = TowardImage(u, v, tan_x, tan_y);
    const float length = Length(q);
    const Vec3 l = RadianceToward(*projector, Normalize(q));
    expected = expected * (kPi * 2 * length * length * length);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(l[c], expected[c], 1e-4f * (1 + expected[c])) << what << " " << c;
  };
  // The centre: the mean of the four middle texels (bilinear).
  expect_texels(0.5f, 0.5f, (Sky(3, 2) + Sky(4, 2) + Sky(3, 3) + Sky(4, 3)) * 0.25f, "centre");
  // Each corner texel's centre, and the bright one.
  for (const auto& [x, y] : {std::pair{0, 0}, {kWidth - 1, 0}, {0, kHeight - 1}, {kWidth - 1, kHeight - 1}, {5, 2}})
    expect_texels((float(x) + 0.5f) / kWidth, (float(y) + 0.5f) / kHeight, Sky(x, y),
                  "texel " + std::to_string(x) + ", " + std::to_string(y));
  // Within half a texel of the frustum's corner, Mitsuba's default wrap
  // mode "repeat" blends the four corner texels: a quarter texel in, the
  // far ones weigh ¼ along each axis.
  const auto row = [&](int y) { return Sky(kWidth - 1, y) * 0.25f + Sky(0, y) * 0.75f; };
  expect_texels(0.25f / kWidth, 0.25f / kHeight, row(kHeight - 1) * 0.25f + row(0) * 0.75f, "corner");
  // Nothing outside the frustum, sideways or behind.
  for (const Vec3 w : {Normalize(TowardImage(-0.01f, 0.5f, tan_x, tan_y)),
                       Normalize(TowardImage(0.5f, 1.01f, tan_x, tan_y)), Vec3(1, 0, 0), Vec3(0, 0, -1),
                       Normalize(Vec3(0.1f, 0.1f, -1))})
    EXPECT_EQ(MaxComponent(RadianceToward(*projector, w)), 0.0f) << w.x << " " << w.y << " " << w.z;
}

TEST_F(EmitterTest, AProjectorFollowsItsToWorldIncludingItsRoll) {
  // The kernel hands a point light's directions in Frame(axis); the
  // projector finds its own x and y from to_world. Looking down −y with
  // its up along −z (a lookat from above), and stretched.
  for (const bool stretched : {false, true}) {
    Properties props = Projector(8, 6, 60, 1);
    Transform to_world;
    to_world.m = {-1, 0, 0, 0, 0, 0, -1, 3, 0, -1, 0, 0, 0, 0, 0, 1};  // x → −x, y → −z, z → −y
    if (stretched) to_world = Stretched();
    props.Set("to_world", to_world);
    const auto projector = Make("projector", props);
    const Frame frame(Normalize(to_world.Vector(Vec3(0, 0, 1))));
    const float tan_x = std::tan(kPi / 6), tan_y = tan_x * 6 / 8;
    for (const auto& [x, y] : {std::pair{0, 0}, {7, 0}, {5, 2}, {2, 4}}) {
      const Vec3 q = TowardImage((float(x) + 0.5f) / 8, (float(y) + 0.5f) / 6, tan_x, tan_y);
      const Vec3 world = to_world.Vector(q);
      const Vec3 l = RadianceToward(*projector, frame.ToLocal(Normalize(world)));
      // Mitsuba's π E / (z_local² · (n·d)), times the squared distance, with
      // n = to_world's image of +z; z_local = 1 at the distance |world|.
      const float cos_n = Dot(to_world.Vector(Vec3(0, 0, 1)), Normalize(world));
      const float distance2 = Dot(world, world);
      const Vec3 expected = Sky(x, y) * (kPi * distance2 / cos_n);
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(l[c], expected[c], 1e-4f * (1 + expected[c])) << stretched << " " << x << " " << y;
    }
  }
}

TEST_F(EmitterTest, AUniformProjectorSamplesOverItsImagePlane) {
  // A constant image: the density is 1 / (A cos³θ), A the image plane's
  // area at unit distance; fov_axis "y" of a square image is fov along x.
  Properties props;
  props.Set("irradiance", Rgb{Vec3(1, 2, 3)});
  props.Set("fov", 90.0);
  props.Set("fov_axis", std::string("y"));
  const auto projector = Make("projector", props);
  const Vec3 w = Normalize(Vec3(0.5f, -0.25f, 1));
  float dir[3], pdf = 0;
  w.Store(dir);
  projector->PdfDirection(dir, std::span<float>(&pdf, 1));
  const float cos_theta = w.z;
  EXPECT_NEAR(pdf, 1 / (4 * cos_theta * cos_theta * cos_theta), 1e-5f);
  EXPECT_NEAR(RadianceToward(*projector, w).z, 3 * kPi / (cos_theta * cos_theta * cos_theta), 1e-4f);
  EXPECT_EQ(MaxComponent(RadianceToward(*projector, Normalize(Vec3(1.01f, 0, 1)))), 0.0f);
}

TEST_F(EmitterTest, AProjectorRefusesBadParameters) {
  Properties no_fov = Projector(8, 6, 60);
  no_fov.Set("fov", 180.0);
  EXPECT_NE(CreationError("projector", no_fov).find("'fov'"), std::string::npos);
  Properties axis = Projector(8, 6, 60);
  axis.Set("fov_axis", std::string("z"));
  EXPECT_NE(CreationError("projector", axis).find("'fov_axis'"), std::string::npos);
  Properties both = Projector(8, 6, 60);
  both.Set("irradiance", 1.0);
  EXPECT_NE(CreationError("projector", both).find("'irradiance'"), std::string::npos);
  Properties wrap = Projector(8, 6, 60);
  wrap.Set("wrap_mode", std::string("black"));
  EXPECT_NE(CreationError("projector", wrap).find("'wrap_mode'"), std::string::npos);
  Properties scale = Projector(8, 6, 60, -1);
  EXPECT_NE(CreationError("projector", scale).find("'scale'"), std::string::npos);
  Properties flat = Projector(8, 6, 60);
  Transform degenerate;
  degenerate.m[10] = 0;
  flat.Set("to_world", degenerate);
  EXPECT_NE(CreationError("projector", flat).find("'to_world'"), std::string::npos);
  Properties missing;
  missing.Set("fov", 30.0);
  EXPECT_NE(CreationError("projector", missing).find("'filename'"), std::string::npos);
}

}  // namespace
}  // namespace yarf

namespace yarf {
namespace {

// pbrt-v4's GoniometricLight: I(l) = scale · I · (mean of the texel's
// channels), the texel where the equal-area map puts l; +z at the centre.
TEST_F(EmitterTest, AGoniometricLightShinesItsTexelsWhereTheEqualAreaMapPutsThem) {
  constexpr int kSide = 8;
  const auto light = Make("goniometric", Goniometric(kSide, 2));
  const auto grey = [](Vec3 c) { return (c.x + c.y + c.z) / 3; };
  for (const auto& [x, y] : {std::pair{5, 2}, {0, 0}, {3, 4}, {7, 6}, {kSide / 2, kSide / 2}}) {
    const Vec3 w = EqualAreaSquareToSphere((float(x) + 0.5f) / kSide, (float(y) + 0.5f) / kSide);
    const Vec3 expected = Vec3(1, 2, 3) * (2 * grey(Sky(x, y)));
    const Vec3 l = RadianceToward(*light, w);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(l[c], expected[c], 1e-4f * (1 + expected[c])) << x << ", " << y;
  }
  // Straight up is the map's centre, whatever the texel there.
  const Vec3 up = RadianceToward(*light, Vec3(0, 0, 1));
  EXPECT_NEAR(up.x, 2 * grey(Sky(kSide / 2, kSide / 2)), 1e-4f);
}

TEST_F(EmitterTest, AGoniometricLightTurnsWithItsToWorldIncludingAMirror) {
  // pbrt-v4 swaps y and z: the map's centre then shines along +y. The
  // kernel hands directions in the frame of to_world's z axis alone.
  Properties props = Goniometric(8);
  Transform swap_yz;
  swap_yz.m = {1, 0, 0, 0, 0, 0, 1, 0, 0, 1, 0, 0, 0, 0, 0, 1};
  props.Set("to_world", swap_yz);
  const auto light = Make("goniometric", props);
  const Frame kernel(Vec3(0, 1, 0));
  const auto toward_world = [&](Vec3 d) { return RadianceToward(*light, kernel.ToLocal(Normalize(d))); };
  const auto plain = Make("goniometric", Goniometric(8));
  for (const Vec3 d : {Vec3(0, 0, 1), Vec3(0.3f, -0.5f, 0.8f), Vec3(-0.7f, 0.1f, -0.2f)}) {
    const Vec3 expected = RadianceToward(*plain, Normalize(d));
    const Vec3 got = toward_world(Vec3(d.x, d.z, d.y));
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], expected[c], 1e-5f * (1 + expected[c]));
  }
}

TEST_F(EmitterTest, AnIntensityImageProjectorShinesItsTexelsWithoutTheCosineFactor) {
  // pbrt-v4's ProjectionLight: I = scale · E(u, v), looked up nearest.
  constexpr int kWidth = 8, kHeight = 6;
  Properties props = Projector(kWidth, kHeight, 60, 2);
  props.Set("image", std::string("intensity"));
  props.Set("filter_type", std::string("nearest"));
  const auto projector = Make("projector", props);
  const float tan_x = std::tan(kPi / 6), tan_y = tan_x * kHeight / kWidth;
  for (const auto& [x, y] : {std::pair{0, 0}, {kWidth - 1, kHeight - 1}, {5, 2}}) {
    const Vec3 q = TowardImage((float(x) + 0.5f) / kWidth, (float(y) + 0.5f) / kHeight, tan_x, tan_y);
    const Vec3 l = RadianceToward(*projector, Normalize(q)), expected = Sky(x, y) * 2;
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(l[c], expected[c], 1e-4f * (1 + expected[c]));
  }
}

TEST_F(EmitterTest, AGoniometricLightRefusesWhatItCannotUse) {
  Properties props = Goniometric(8);
  props.Set("filename", WriteSky("oblong.exr", 8, 4));
  EXPECT_NE(CreationError("goniometric", props).find("square"), std::string::npos);
  Properties negative = Goniometric(8, -1);
  EXPECT_NE(CreationError("goniometric", negative).find("scale"), std::string::npos);
  EXPECT_NE(CreationError("goniometric", Properties()).find("filename"), std::string::npos);
}

}  // namespace
}  // namespace yarf
