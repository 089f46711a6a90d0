// Tests of the emitter plugins (emitters/*.cc), loaded through the
// registry as yarfd loads them: where each emits, that SampleDirection
// agrees with PdfDirection, that each density integrates to one, and that
// an area light's radiance may be a texture.
#include <gtest/gtest.h>

#include <cmath>
#include <algorithm>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "components/registry.h"
#include "yarf/hash.h"
#include "yarf/surface.h"
#include "yarf/texture.h"
#include "yarf/warps.h"

namespace yarf {
namespace {

class EmitterTest : public testing::Test {
 protected:
  EmitterTest() { registry_.LoadDirectory(YARF_PLUGIN_DIR); }

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
    return all;
  }

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
    constexpr int kRows = 2000, kCols = 64;
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
