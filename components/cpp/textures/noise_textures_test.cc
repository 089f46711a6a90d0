// Tests of the noise textures (solid_noise.cc, dots.cc,
// yarf/support/perlin_noise.h): noise's lattice zeros, period and range,
// the octave sums, each pattern at its texture-space point, the dots'
// placement, and bad properties refused. (Their values against an
// independent implementation of pbrt's noise, through a pbrt file's
// render: tests/test_noise_textures.py.)
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "texture_test_support.h"
#include "yarf/support/perlin_noise.h"
#include "yarf/texture.h"

namespace yarf {
namespace {

using namespace texture_testing;  // NOLINT: the shared helpers, in every test

TEST(PerlinNoise, IsZeroOnTheLatticeRepeatsEvery256CellsAndStaysWithinOne) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> coordinate(-300, 300);
  for (int k = 0; k < 2000; ++k) {
    const Vec3 lattice(std::floor(coordinate(rng)), std::floor(coordinate(rng)), std::floor(coordinate(rng)));
    EXPECT_EQ(Noise(lattice), 0);
    const Vec3 p(coordinate(rng), coordinate(rng), coordinate(rng));
    const float n = Noise(p);
    EXPECT_LE(std::abs(n), 1.05f) << p.x << " " << p.y << " " << p.z;
    EXPECT_NEAR(Noise(p + Vec3(256, -512, 768)), n, 2e-4f);
  }
  // A point not finite (a position far out, through a transform) has 0.
  EXPECT_EQ(Noise(Vec3(NAN, 0.5f, 0.5f)), 0);
  EXPECT_EQ(Noise(Vec3(0.5f, INFINITY, 0.5f)), 0);
  EXPECT_EQ(Noise(Vec3(0.5f, 0.5f, 3e38f)), Noise(Vec3(0.5f, 0.5f, std::fmod(3e38f, float(1 << 30)))));
  // Not zero between lattice points, and continuous there.
  EXPECT_GT(std::abs(Noise(Vec3(0.3f, 0.6f, 0.2f))), 1e-3f);
  EXPECT_NEAR(Noise(Vec3(0.3f, 0.6f, 0.2f)), Noise(Vec3(0.3001f, 0.6f, 0.2f)), 1e-3f);
}

TEST(PerlinNoise, OctavesAddNoiseEachFinerAndWeighedByRoughness) {
  const Vec3 p(1.37f, -2.21f, 0.58f);
  EXPECT_FLOAT_EQ(FBm(p, 0.7f, 1), Noise(p));
  EXPECT_FLOAT_EQ(FBm(p, 0.7f, 2), Noise(p) + 0.7f * Noise(p * 1.99f));
  // Turbulence: the octaves' |noise|, and 0.2 for those beyond.
  EXPECT_FLOAT_EQ(Turbulence(p, 0.7f, 1), std::abs(Noise(p)) + 0.7f * 0.2f);
  EXPECT_FLOAT_EQ(Turbulence(p, 0.5f, 2), std::abs(Noise(p)) + 0.5f * std::abs(Noise(p * 1.99f)) + 0.25f * 0.2f);
}

class SolidNoiseTest : public TexturePluginTest {
 protected:
  // The first channel of `texture` at world points `positions`.
  static std::vector<float> At(const Texture& texture, const std::vector<Vec3>& positions) {
    std::vector<float> uv(2 * positions.size()), xyz;
    for (const Vec3 p : positions) xyz.insert(xyz.end(), {p.x, p.y, p.z});
    SurfacePoints points{uv};
    points.position = xyz;
    std::vector<float> value(positions.size() * texture.Channels());
    texture.Evaluate(points, value);
    std::vector<float> first;
    for (size_t k = 0; k < positions.size(); ++k) first.push_back(value[k * texture.Channels()]);
    return first;
  }
};

TEST_F(SolidNoiseTest, EachPatternIsItsNoiseAtTheTextureSpacePoint) {
  Transform to_texture;  // x, y, z → 2x + 1, 2y, 2z − 3
  to_texture.m = {2, 0, 0, 1, 0, 2, 0, 0, 0, 0, 2, -3, 0, 0, 0, 1};
  const std::vector<Vec3> world = {Vec3(0.1f, 0.7f, -0.4f), Vec3(3.3f, -1.2f, 5.9f), Vec3(-7.5f, 0.25f, 2)};
  const auto fbm = Make("fbm", With({{"to_texture", to_texture}, {"octaves", int64_t(5)}, {"roughness", 0.6}}));
  const auto wrinkled = Make("wrinkled", With({{"to_texture", to_texture}, {"octaves", int64_t(3)}}));
  const auto windy = Make("windy", With({{"to_texture", to_texture}}));
  ASSERT_EQ(fbm->Channels(), 1u);
  const std::vector<float> f = At(*fbm, world), w = At(*wrinkled, world), g = At(*windy, world);
  for (size_t k = 0; k < world.size(); ++k) {
    const Vec3 p = to_texture.Point(world[k]);
    EXPECT_FLOAT_EQ(f[k], FBm(p, 0.6f, 5));
    EXPECT_FLOAT_EQ(w[k], Turbulence(p, 0.5f, 3));
    EXPECT_FLOAT_EQ(g[k], std::abs(FBm(p * 0.1f, 0.5f, 3)) * FBm(p, 0.5f, 6));
  }
  // Without positions (a point known by its uv alone): the origin's value.
  std::vector<float> value(1);
  const std::vector<float> uv = {0.5f, 0.5f};
  Make("fbm")->Evaluate(SurfacePoints{uv}, value);
  EXPECT_EQ(value[0], 0);
  EXPECT_TRUE(fbm->ReadsPositions());
  EXPECT_FALSE(fbm->ReadsFootprints());
  EXPECT_TRUE(Make("mix", With({{"amount", fbm}}))->ReadsPositions());
  EXPECT_FALSE(Make("mix")->ReadsPositions());
}

TEST_F(SolidNoiseTest, MarbleRunsThroughPbrtsGreysByItsVeins) {
  const auto marble = Make("marble", With({{"variation", 0.0}}));
  ASSERT_EQ(marble->Channels(), 3u);
  // Without variation the veins are y alone: t = ½ + ½ sin y. At y = −π/2
  // the spline starts, at its first control point (0.58, 0.58, 0.6) × 1.5;
  // at y = π/2 it ends, at its last, the same colour.
  for (const float y : {-float(kPi) / 2, float(kPi) / 2}) {
    const std::vector<float> xyz = {0.3f, y, 0.8f}, uv = {0, 0};
    SurfacePoints points{uv};
    points.position = xyz;
    std::vector<float> value(3);
    marble->Evaluate(points, value);
    EXPECT_NEAR(value[0], 0.87f, 1e-4f);
    EXPECT_NEAR(value[2], 0.9f, 1e-4f);
  }
  // A point so far out that its veins are not finite still has a colour.
  const auto far_scaled = Make("marble", With({{"scale", 1e30}}));
  const std::vector<float> far_xyz = {3e9f, 1e9f, 2e9f}, far_uv = {0, 0};
  SurfacePoints far{far_uv};
  far.position = far_xyz;
  std::vector<float> far_value(3);
  far_scaled->Evaluate(far, far_value);
  for (const float c : far_value) EXPECT_TRUE(c > 0.2f && c < 1) << c;
  const std::vector<float> mean = marble->Mean();
  ASSERT_EQ(mean.size(), 3u);
  for (const float m : mean) EXPECT_TRUE(m > 0.3f && m < 1.0f) << m;
}

TEST_F(SolidNoiseTest, BadPropertiesAreRefused) {
  EXPECT_ANY_THROW(Make("fbm", With({{"roughness", 1.5}})));
  EXPECT_ANY_THROW(Make("wrinkled", With({{"octaves", int64_t(0)}})));
  EXPECT_ANY_THROW(Make("fbm", With({{"octaves", int64_t(1000)}})));
  EXPECT_ANY_THROW(Make("marble", With({{"scale", std::nan("")}})));
  Transform infinite;
  infinite.m[3] = INFINITY;
  EXPECT_ANY_THROW(Make("windy", With({{"to_texture", infinite}})));
}

TEST_F(SolidNoiseTest, DotsLieWhereNoiseSaysWithinACellOfSideOne) {
  const auto dots = Make("dots", With({{"inside", Rgb{Vec3(0.8f, 0.8f, 0.8f)}}, {"outside", 0.25}, {"uscale", 2.0}}));
  ASSERT_EQ(dots->Channels(), 3u);
  // Over a grid of (s, t) = (2u, v): every value is inside's or outside's,
  // a point is inside only in a cell whose centre's noise is positive,
  // within 0.35 + 0.15·√2 of that centre, and some fifth of the plane is in dots.
  int in = 0, total = 0;
  for (int i = 0; i < 200; ++i)
    for (int j = 0; j < 200; ++j) {
      const float u = -5 + i * 0.05f, v = -5 + j * 0.05f;
      const float value = Lookup(*dots, {u, v})[0];
      ASSERT_TRUE(value == 0.8f || value == 0.25f) << value;
      ++total;
      if (value != 0.8f) continue;
      ++in;
      const float s = 2 * u, t = v, cell_s = std::floor(s + 0.5f), cell_t = std::floor(t + 0.5f);
      EXPECT_GT(Noise(Vec3(cell_s + 0.5f, cell_t + 0.5f, 0.5f)), 0);
      EXPECT_LT(std::hypot(s - cell_s, t - cell_t), 0.35f + 0.15f * std::sqrt(2.0f) + 1e-4f);
    }
  EXPECT_GT(in, total / 10);
  EXPECT_LT(in, total / 3);
  const float mean = dots->Mean()[0];
  EXPECT_GT(mean, 0.25f);
  EXPECT_LT(mean, 0.8f);
  EXPECT_FALSE(dots->ReadsPositions());
}

}  // namespace
}  // namespace yarf
