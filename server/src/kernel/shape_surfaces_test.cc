// The shape surfaces' samplers: their densities are the ones Pdf reports,
// and they integrate to the solid angle and area they must.
#include "kernel/shape_surfaces.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "yarf/support/warps.h"

namespace yarf {
namespace {

// A quad (two triangles) of side `side` in the plane z = 0, facing +z.
TriangleMesh Quad(float side) {
  TriangleMesh mesh;
  mesh.positions = {Vec3(0, 0, 0), Vec3(side, 0, 0), Vec3(side, side, 0), Vec3(0, side, 0)};
  mesh.indices = {0, 1, 2, 0, 2, 3};
  mesh.uvs = {0, 0, 1, 0, 1, 1, 0, 1};
  return mesh;
}

MeshSurface QuadSurface(const TriangleMesh& mesh, bool by_solid_angle) {
  std::vector<std::array<Vec3, 3>> corners;
  for (size_t t = 0; t < mesh.TriangleCount(); ++t)
    corners.push_back({mesh.positions[mesh.indices[3 * t]], mesh.positions[mesh.indices[3 * t + 1]],
                       mesh.positions[mesh.indices[3 * t + 2]]});
  return MeshSurface(corners, std::vector<Vec3>(corners.size(), Vec3(0, 0, 1)), mesh, by_solid_angle);
}

std::vector<float> Uniform(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0, 0x1.fffffep-1f);
  std::vector<float> values(3 * n);
  for (float& v : values) v = u(rng);
  return values;
}

// E[1/pdf] over direction samples from p is the solid angle the surface
// subtends there (for a surface every direction meets at most once), and
// Pdf agrees with each sample's density.
double SolidAngleEstimate(const ShapeSurface& surface, Vec3 p, size_t n) {
  const std::vector<float> u = Uniform(n, 7);
  const std::vector<Vec3> from(n, p);
  std::vector<SurfaceSample> samples(n);
  surface.Sample(from, u, samples);
  std::vector<float> pdf(n);
  surface.Pdf(from, samples, pdf);
  double sum = 0;
  for (size_t k = 0; k < n; ++k) {
    EXPECT_GT(samples[k].pdf, 0);
    // Compared as the weights 1/pdf they give: at grazing angles the
    // density is huge and rounding of the point moves it by a little more.
    EXPECT_NEAR(1 / pdf[k], 1 / samples[k].pdf, 1e-3 / samples[k].pdf + 1e-6) << "sample " << k;
    sum += 1 / samples[k].pdf;
  }
  return sum / double(n);
}

// Solid angle of the square [0,a]² at height h above its corner (a
// quarter of the centred square of side 2a: 4·asin(a²/(a²+h²)))
double CornerSquareSolidAngle(double a, double h) { return std::asin(a * a / (a * a + h * h)); }

TEST(ShapeSurfaces, SphereSeenFromOutsideIsSampledInItsCone) {
  SphereGeometry geometry;
  geometry.center = Vec3(0, 0, 3);
  geometry.radius = 1;
  const SphereSurface sphere(geometry, true);
  const Vec3 p(0, 0, 0);
  const float cos_max = std::sqrt(1 - 1.0f / 9);
  const std::vector<float> u = Uniform(1000, 3);
  std::vector<SurfaceSample> samples(1000);
  sphere.Sample(std::vector<Vec3>(1000, p), u, samples);
  for (const SurfaceSample& s : samples) {
    EXPECT_NEAR(Length(s.position - geometry.center), 1, 1e-4);
    // On the near side: the normal faces p.
    EXPECT_LT(Dot(s.normal, s.position - p), 1e-4);
    EXPECT_GE(Normalize(s.position - p).z, cos_max - 1e-5f);
    EXPECT_FLOAT_EQ(s.pdf, 1 / (2 * kPi * (1 - cos_max)));
  }
  EXPECT_NEAR(SolidAngleEstimate(sphere, p, 1000), 2 * kPi * (1 - cos_max), 1e-4);
}

TEST(ShapeSurfaces, SphereByAreaIntegratesToItsWholeArea) {
  SphereGeometry geometry;
  geometry.radius = 2;
  const SphereSurface sphere(geometry, false);
  EXPECT_FLOAT_EQ(sphere.Area(), 16 * kPi);
  const std::vector<float> u = Uniform(20000, 5);
  std::vector<SurfaceSample> samples(20000);
  sphere.Sample(u, samples);
  Vec3 mean;
  for (const SurfaceSample& s : samples) {
    EXPECT_FLOAT_EQ(s.pdf, 1 / sphere.Area());
    EXPECT_NEAR(Length(s.position), 2, 1e-4);
    EXPECT_NEAR(Dot(s.normal, s.position) / 2, 1, 1e-4);
    mean += s.position / 20000.0f;
  }
  // Uniform over the sphere: centred, to ~3σ of 2/√(3·20000).
  EXPECT_LT(Length(mean), 0.03f);
  // From outside by area, every point counts, the far side too: E[1/pdf]
  // is the solid angle counted from both sides, twice the cone's.
  const Vec3 p(0, 0, 6);
  const float cos_max = std::sqrt(1 - 4.0f / 36);
  EXPECT_NEAR(SolidAngleEstimate(sphere, p, 200000), 2 * 2 * kPi * (1 - cos_max), 0.03);
}

TEST(ShapeSurfaces, QuadBySolidAngleAndByAreaSubtendTheSameAngle) {
  const TriangleMesh mesh = Quad(1);
  const Vec3 p(0, 0, 0.5f);
  const double expected = CornerSquareSolidAngle(1, 0.5);
  for (bool by_solid_angle : {false, true}) {
    const MeshSurface quad = QuadSurface(mesh, by_solid_angle);
    EXPECT_FLOAT_EQ(quad.Area(), 1);
    const double estimate = SolidAngleEstimate(quad, p, by_solid_angle ? 2000 : 400000);
    EXPECT_NEAR(estimate, expected, by_solid_angle ? 1e-4 : 0.01 * expected) << "by solid angle " << by_solid_angle;
  }
}

TEST(ShapeSurfaces, TrianglesFarAwayAreSampledByArea) {
  // Under pbrt-v4's bound (3e-4 sr) a triangle is sampled by area even in
  // solid-angle mode: the density is area's converted.
  const TriangleMesh mesh = Quad(0.01f);
  const MeshSurface quad = QuadSurface(mesh, true);
  const Vec3 p(0.005f, 0.005f, 10);
  SurfaceSample s;
  const float u[3] = {0.3f, 0.5f, 0.5f};
  quad.Sample({&p, 1}, u, {&s, 1});
  const Vec3 d = s.position - p;
  EXPECT_NEAR(s.pdf, Dot(d, d) / std::abs(d.z / Length(d)) / quad.Area(), 1e-3 * s.pdf);
}

TEST(ShapeSurfaces, AMeshKeepsThePointPairsStratification) {
  // The pair (u0, u1) picks the triangle too, u0 rescaled within its
  // share: a 16 × 16 grid of pairs puts exactly half its points in each of
  // a quad's two equal triangles, the same points whatever the first
  // number is. Picked by that number, the split would be binomial.
  const TriangleMesh mesh = Quad(1);
  const Vec3 p(0.3f, 0.4f, 0.5f);
  constexpr size_t kSide = 16, kCount = kSide * kSide;
  std::vector<float> grid = Uniform(kCount, 4), regridded = Uniform(kCount, 5);
  for (size_t i = 0; i < kSide; ++i)
    for (size_t j = 0; j < kSide; ++j)
      for (std::vector<float>* u : {&grid, &regridded}) {
        (*u)[3 * (i * kSide + j) + 1] = (i + 0.5f) / kSide;
        (*u)[3 * (i * kSide + j) + 2] = (j + 0.5f) / kSide;
      }
  for (bool by_solid_angle : {false, true}) {
    const MeshSurface quad = QuadSurface(mesh, by_solid_angle);
    std::vector<SurfaceSample> seen(kCount), reseen(kCount), by_area(kCount);
    quad.Sample(std::vector<Vec3>(kCount, p), grid, seen);
    quad.Sample(std::vector<Vec3>(kCount, p), regridded, reseen);
    quad.Sample(grid, by_area);
    for (const std::vector<SurfaceSample>* samples : {&seen, &by_area}) {
      const auto first = std::count_if(samples->begin(), samples->end(),
                                       [](const SurfaceSample& s) { return s.primitive == 0; });
      EXPECT_EQ(first, kCount / 2) << "by solid angle " << by_solid_angle;
    }
    for (size_t k = 0; k < kCount; ++k) {
      EXPECT_EQ(seen[k].primitive, reseen[k].primitive);
      EXPECT_EQ(Length(seen[k].position - reseen[k].position), 0);
    }
  }
}

TEST(ShapeSurfaces, MeshSamplesCarryTheirTextureCoordinates) {
  const TriangleMesh mesh = Quad(2);
  const MeshSurface quad = QuadSurface(mesh, false);
  const std::vector<float> u = Uniform(100, 9);
  std::vector<SurfaceSample> samples(100);
  quad.Sample(u, samples);
  for (const SurfaceSample& s : samples) {
    // The quad's uv is its position over its side.
    EXPECT_NEAR(s.u, s.position.x / 2, 1e-5);
    EXPECT_NEAR(s.v, s.position.y / 2, 1e-5);
    EXPECT_FLOAT_EQ(s.pdf, 0.25f);
  }
  Vec3 lower, upper;
  quad.Bounds(lower, upper);
  EXPECT_EQ(lower.x, 0);
  EXPECT_EQ(upper.y, 2);
}

TEST(ShapeSurfaces, GatheredIntoOnePoint) {
  const TriangleMesh mesh = Quad(2);
  const MeshSurface quad = QuadSurface(mesh, false);
  float area = 0;
  const SurfaceSample centre = quad.Gathered(Vec3(5, 5, 5), area);
  EXPECT_FLOAT_EQ(area, 4);
  EXPECT_NEAR(centre.position.x, 1, 1e-5);
  EXPECT_NEAR(centre.position.y, 1, 1e-5);
  EXPECT_NEAR(centre.normal.z, 1, 1e-6);
  Vec3 axis;
  float cos_theta = 0;
  ASSERT_TRUE(quad.NormalCone(axis, cos_theta));
  EXPECT_NEAR(axis.z, 1, 1e-6);
  EXPECT_GT(cos_theta, 0.99f);

  SphereGeometry geometry;
  geometry.radius = 0.5f;
  const SphereSurface sphere(geometry, true);
  const SurfaceSample facing = sphere.Gathered(Vec3(0, 4, 0), area);
  EXPECT_FLOAT_EQ(area, kPi * 0.25f);
  EXPECT_NEAR(facing.position.y, 0.5f, 1e-6);
  EXPECT_FALSE(sphere.NormalCone(axis, cos_theta));
}

TEST(ShapeSurfaces, PointsFromTwoNumbersAreUniformInArea) {
  // Three triangles of areas 8, 0.5 and 0.3, facing +z.
  TriangleMesh mesh;
  mesh.positions = {Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(0, 4, 0), Vec3(5, 0, 0), Vec3(6, 0, 0),
                    Vec3(5, 1, 0), Vec3(0, 5, 0), Vec3(3, 5, 0), Vec3(0, 5.2f, 0)};
  mesh.indices = {0, 1, 2, 3, 4, 5, 6, 7, 8};
  const MeshSurface surface = QuadSurface(mesh, false);
  const float areas[3] = {8, 0.5f, 0.3f};
  Vec3 centroid, centroids[3];
  for (int t = 0; t < 3; ++t) {
    centroids[t] = (mesh.positions[3 * t] + mesh.positions[3 * t + 1] + mesh.positions[3 * t + 2]) / 3;
    centroid += centroids[t] * (areas[t] / 8.8f);
  }
  constexpr size_t kN = 400000;
  const std::vector<float> u = Uniform(kN, 11);
  double sum[2] = {0, 0}, sum_first[2] = {0, 0};
  size_t count[3] = {0, 0, 0};
  for (size_t k = 0; k < kN; ++k) {
    const SurfaceSample s = surface.SamplePoint(u[3 * k], u[3 * k + 1]);
    ASSERT_LT(s.primitive, 3u);
    EXPECT_FLOAT_EQ(s.pdf, 1 / 8.8f);
    sum[0] += s.position.x, sum[1] += s.position.y;
    if (s.primitive == 0) sum_first[0] += s.position.x, sum_first[1] += s.position.y;
    ++count[s.primitive];
  }
  // Positions spread over about ±2 units: the mean's σ is about 0.003.
  EXPECT_NEAR(sum[0] / kN, centroid.x, 0.015);
  EXPECT_NEAR(sum[1] / kN, centroid.y, 0.015);
  // Within the large triangle too: the reused remainder fills it evenly.
  EXPECT_NEAR(sum_first[0] / double(count[0]), centroids[0].x, 0.015);
  EXPECT_NEAR(sum_first[1] / double(count[0]), centroids[0].y, 0.015);
  for (int t = 0; t < 3; ++t) EXPECT_NEAR(double(count[t]) / kN, areas[t] / 8.8, 0.004) << "triangle " << t;

  // A sphere: centred, with E[z²] = r²/3.
  SphereGeometry geometry;
  geometry.center = Vec3(1, 2, 3);
  geometry.radius = 2;
  const SphereSurface sphere(geometry, true);
  Vec3 mean;
  double z2 = 0;
  for (size_t k = 0; k < kN; ++k) {
    const SurfaceSample s = sphere.SamplePoint(u[3 * k], u[3 * k + 1]);
    EXPECT_NEAR(Length(s.position - geometry.center), 2, 1e-5);
    mean += s.position / float(kN);
    z2 += (s.position.z - 3) * (s.position.z - 3) / kN;
  }
  EXPECT_NEAR(Length(mean - geometry.center), 0, 0.02);
  EXPECT_NEAR(z2, 4.0 / 3, 0.02);
}

}  // namespace
}  // namespace yarf
