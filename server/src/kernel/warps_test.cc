// Tests of yarf/support/warps.h: every pdf integrates to 1 over its domain, the
// samples of every warp follow its pdf (Pearson's χ² goodness-of-fit test,
// as Mitsuba 3 tests its warps), and the Fresnel and refraction helpers
// obey their physical limits.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <random>
#include <vector>

#include "yarf/support/chi_square.h"
#include "yarf/support/hash.h"
#include "yarf/support/warps.h"

namespace yarf {
namespace {

constexpr double kPiDouble = 3.14159265358979323846;
constexpr int kSampleCount = 1'000'000;
constexpr double kSignificance = 0.01;

using Density2D = std::function<double(double, double)>;
using Point2D = std::array<double, 2>;

// A rectangle [a_min, a_max] × [b_min, b_max] of 2-D coordinates cut into
// rows × cols equal cells.
struct Grid {
  int rows, cols;
  double a_min, a_max, b_min, b_max;
};

// ∫ density over cell (row, col) by 5-point Gauss–Legendre quadrature in
// each coordinate: exact for polynomials of degree 9, and its nodes lie
// inside the cell, so a density that jumps on a cell edge (a hemisphere's
// or a cone's rim) is integrated on the correct side.
double CellIntegral(const Grid& grid, int row, int col, const Density2D& density) {
  static constexpr double kNodes[] = {-0.9061798459386640, -0.5384693101056831, 0.0,
                                      0.5384693101056831, 0.9061798459386640};
  static constexpr double kWeights[] = {0.2369268850561891, 0.4786286704993665,
                                        0.5688888888888889, 0.4786286704993665,
                                        0.2369268850561891};
  const double da = (grid.a_max - grid.a_min) / grid.rows;
  const double db = (grid.b_max - grid.b_min) / grid.cols;
  const double a_mid = grid.a_min + (row + 0.5) * da, b_mid = grid.b_min + (col + 0.5) * db;
  double sum = 0;
  for (int s = 0; s < 5; ++s)
    for (int t = 0; t < 5; ++t)
      sum += kWeights[s] * kWeights[t] *
             density(a_mid + 0.5 * da * kNodes[s], b_mid + 0.5 * db * kNodes[t]);
  return sum * (0.5 * da) * (0.5 * db);
}

// Pearson's χ² test that `points` are distributed with `density` over the
// grid (density in the grid's coordinates: it must integrate to the
// fraction of samples expected inside; jumps only on cell edges). Cells expecting fewer than 5
// samples are pooled, as the statistic is χ²-distributed only for
// moderately large expected counts; a sample where the density is 0 fails
// at once.
testing::AssertionResult PassesChiSquare(const std::vector<Point2D>& points, int sample_count,
                                         const Grid& grid, const Density2D& density) {
  const int cells = grid.rows * grid.cols;
  std::vector<double> observed(cells, 0.0), expected(cells, 0.0);
  for (const auto& [a, b] : points) {
    const double fa = (a - grid.a_min) / (grid.a_max - grid.a_min);
    const double fb = (b - grid.b_min) / (grid.b_max - grid.b_min);
    if (!(fa >= 0 && fa <= 1 && fb >= 0 && fb <= 1))
      return testing::AssertionFailure() << "sample (" << a << ", " << b << ") outside the domain";
    const int row = std::min(int(fa * grid.rows), grid.rows - 1);
    const int col = std::min(int(fb * grid.cols), grid.cols - 1);
    observed[row * grid.cols + col] += 1;
  }
  for (int row = 0; row < grid.rows; ++row)
    for (int col = 0; col < grid.cols; ++col)
      expected[row * grid.cols + col] = sample_count * CellIntegral(grid, row, col, density);

  return testing_support::PearsonChiSquareTest(observed, expected, kSignificance);
}

// Uniform floats in [0, 1) from a fixed-seed generator.
class Uniforms {
 public:
  explicit Uniforms(uint64_t seed) : engine_(seed) {}
  float Next() { return ToUnitFloat(uint32_t(engine_() >> 32)); }

 private:
  std::mt19937_64 engine_;
};

Vec3 DirectionAt(double cos_theta, double phi) {
  return SphericalDirection(SinFromCos(float(cos_theta)), float(cos_theta), float(phi));
}

// Directions binned by (cos θ, φ): equal cells have equal solid angle and
// dω = d(cos θ) dφ, so the density in these coordinates is the pdf itself.
constexpr Grid kSphereGrid{100, 200, -1.0, 1.0, -kPiDouble, kPiDouble};

Point2D SphereCoordinates(Vec3 w) {
  return {std::clamp(double(w.z), -1.0, 1.0), std::atan2(double(w.y), double(w.x))};
}

testing::AssertionResult DirectionsFollowPdf(const std::function<Vec3(float, float)>& warp,
                                             const std::function<float(Vec3)>& pdf) {
  Uniforms uniforms(0x5eed);
  std::vector<Point2D> points;
  points.reserve(kSampleCount);
  for (int k = 0; k < kSampleCount; ++k) {
    const float u0 = uniforms.Next(), u1 = uniforms.Next();
    const Vec3 w = warp(u0, u1);
    if (std::abs(Length(w) - 1.0f) > 1e-4f)
      return testing::AssertionFailure() << "direction of length " << Length(w);
    points.push_back(SphereCoordinates(w));
  }
  return PassesChiSquare(points, kSampleCount, kSphereGrid,
                         [&](double z, double phi) { return pdf(DirectionAt(z, phi)); });
}

// ∫ pdf dω over the whole sphere by the midpoint rule in (cos θ, φ); 4000
// rows put the cone's and hemisphere's edges (cos θ = 0.5, 0) on cell
// boundaries.
double IntegrateOverSphere(const std::function<float(Vec3)>& pdf) {
  constexpr int kRows = 4000, kCols = 64;
  const double dz = 2.0 / kRows, dphi = 2 * kPiDouble / kCols;
  double sum = 0;
  for (int i = 0; i < kRows; ++i)
    for (int j = 0; j < kCols; ++j)
      sum += pdf(DirectionAt(-1.0 + (i + 0.5) * dz, -kPiDouble + (j + 0.5) * dphi));
  return sum * dz * dphi;
}

constexpr float kConeCosMax = 0.5f;

float CosineHemisphere(Vec3 w) { return CosineHemispherePdf(w.z); }
float UniformHemisphere(Vec3 w) { return UniformHemispherePdf(w.z); }
float UniformSphere(Vec3) { return UniformSpherePdf(); }
float UniformCone(Vec3 w) { return UniformConePdf(w.z, kConeCosMax); }

TEST(WarpsTest, DirectionPdfsIntegrateToOne) {
  EXPECT_NEAR(IntegrateOverSphere(CosineHemisphere), 1.0, 1e-3);
  EXPECT_NEAR(IntegrateOverSphere(UniformHemisphere), 1.0, 1e-3);
  EXPECT_NEAR(IntegrateOverSphere(UniformSphere), 1.0, 1e-3);
  EXPECT_NEAR(IntegrateOverSphere(UniformCone), 1.0, 1e-3);
  for (float exponent : {0.0f, 1.0f, 10.0f, 100.0f})
    EXPECT_NEAR(IntegrateOverSphere([&](Vec3 w) { return PhongLobePdf(w.z, exponent); }), 1.0,
                1e-3)
        << "exponent " << exponent;
}

TEST(WarpsTest, ConcentricDiskPdfIntegratesToOne) {
  // Midpoint rule over a square larger than the disk, so a density leaking
  // outside the disk would show.
  constexpr int kSteps = 2200;
  constexpr double kHalfWidth = 1.1, kStep = 2 * kHalfWidth / kSteps;
  double sum = 0;
  for (int i = 0; i < kSteps; ++i)
    for (int j = 0; j < kSteps; ++j)
      sum += ConcentricDiskPdf(float(-kHalfWidth + (i + 0.5) * kStep),
                               float(-kHalfWidth + (j + 0.5) * kStep));
  EXPECT_NEAR(sum * kStep * kStep, 1.0, 1e-3);
}

TEST(WarpsTest, UniformTrianglePdfIntegratesToOne) {
  // The barycentric triangle b1, b2 ≥ 0, b1 + b2 ≤ 1 has area 1/2.
  constexpr int kSteps = 2000;
  constexpr double kStep = 1.0 / kSteps;
  double sum = 0;
  for (int i = 0; i < kSteps; ++i)
    for (int j = 0; j < kSteps; ++j)
      if ((i + 0.5) * kStep + (j + 0.5) * kStep <= 1.0) sum += UniformTrianglePdf(0.5f);
  EXPECT_NEAR(sum * kStep * kStep, 1.0, 1e-3);
}

TEST(WarpsTest, CosineHemisphereSamplesFollowPdf) {
  EXPECT_TRUE(DirectionsFollowPdf(SampleCosineHemisphere, CosineHemisphere));
}

TEST(WarpsTest, UniformHemisphereSamplesFollowPdf) {
  EXPECT_TRUE(DirectionsFollowPdf(SampleUniformHemisphere, UniformHemisphere));
}

TEST(WarpsTest, UniformSphereSamplesFollowPdf) {
  EXPECT_TRUE(DirectionsFollowPdf(SampleUniformSphere, UniformSphere));
}

TEST(WarpsTest, UniformConeSamplesFollowPdf) {
  EXPECT_TRUE(DirectionsFollowPdf(
      [](float u0, float u1) { return SampleUniformCone(u0, u1, kConeCosMax); }, UniformCone));
}

TEST(WarpsTest, PhongLobeSamplesFollowPdf) {
  for (float exponent : {1.0f, 10.0f})
    EXPECT_TRUE(DirectionsFollowPdf(
        [&](float u0, float u1) { return SamplePhongLobe(u0, u1, exponent); },
        [&](Vec3 w) { return PhongLobePdf(w.z, exponent); }))
        << "exponent " << exponent;
}

TEST(WarpsTest, ConcentricDiskSamplesFollowPdf) {
  // Binned by (r², φ): dA = r dr dφ = ½ d(r²) dφ, so equal cells have
  // equal area and the density in these coordinates is pdf / 2.
  const Grid grid{50, 100, 0.0, 1.0, -kPiDouble, kPiDouble};
  Uniforms uniforms(0xd15c);
  std::vector<Point2D> points;
  for (int k = 0; k < kSampleCount; ++k) {
    const float u0 = uniforms.Next(), u1 = uniforms.Next();
    const auto [x, y] = SampleConcentricDisk(u0, u1);
    points.push_back({double(x) * x + double(y) * y, std::atan2(double(y), double(x))});
  }
  EXPECT_TRUE(PassesChiSquare(points, kSampleCount, grid, [](double r2, double phi) {
    const double r = std::sqrt(r2);
    return 0.5 * ConcentricDiskPdf(float(r * std::cos(phi)), float(r * std::sin(phi)));
  }));
}

TEST(WarpsTest, UniformTriangleSamplesFollowPdf) {
  // Binned by (s, t) = ((b1 + b2)², b2 / (b1 + b2)): db1 db2 = ½ ds dt,
  // so equal cells have equal area and the density is pdf / 2.
  const Grid grid{50, 50, 0.0, 1.0, 0.0, 1.0};
  constexpr float kBarycentricArea = 0.5f;
  Uniforms uniforms(0x7e1a);
  std::vector<Point2D> points;
  for (int k = 0; k < kSampleCount; ++k) {
    const float u0 = uniforms.Next(), u1 = uniforms.Next();
    const auto [b0, b1, b2] = SampleUniformTriangle(u0, u1);
    ASSERT_GE(b0, 0.0f);
    ASSERT_GE(b1, 0.0f);
    ASSERT_GE(b2, -1e-6f);
    const double sum = double(b1) + b2;
    points.push_back({sum * sum, sum > 0 ? b2 / sum : 0.0});
  }
  EXPECT_TRUE(PassesChiSquare(points, kSampleCount, grid, [&](double s, double) {
    return s <= 1.0 ? 0.5 * UniformTrianglePdf(kBarycentricArea) : 0.0;
  }));
}

TEST(WarpsTest, ChiSquareRejectsAWrongPdf) {
  // The test has power: uniform-hemisphere samples are not cosine-distributed.
  Uniforms uniforms(0xbad);
  std::vector<Point2D> points;
  for (int k = 0; k < kSampleCount; ++k) {
    const float u0 = uniforms.Next(), u1 = uniforms.Next();
    points.push_back(SphereCoordinates(SampleUniformHemisphere(u0, u1)));
  }
  EXPECT_FALSE(PassesChiSquare(points, kSampleCount, kSphereGrid, [](double z, double) {
    return CosineHemispherePdf(float(z));
  }));
}

TEST(WarpsTest, FresnelAtNormalIncidence) {
  for (float eta : {1.1f, 1.5f, 2.4f, 1.0f / 1.5f}) {
    const float expected = ((eta - 1) / (eta + 1)) * ((eta - 1) / (eta + 1));
    EXPECT_NEAR(FresnelDielectric(1.0f, eta), expected, 1e-6f) << "eta " << eta;
    // Seen from below, the interface has index 1/eta: the same reflectance.
    EXPECT_NEAR(FresnelDielectric(-1.0f, eta), expected, 1e-6f) << "eta " << eta;
  }
}

TEST(WarpsTest, FresnelLimits) {
  constexpr float kEta = 1.5f;
  // Grazing incidence reflects everything.
  EXPECT_NEAR(FresnelDielectric(1e-6f, kEta), 1.0f, 1e-4f);
  // Index-matched media do not reflect.
  EXPECT_NEAR(FresnelDielectric(0.7f, 1.0f), 0.0f, 1e-7f);
  // From inside, beyond the critical angle (sin θc = 1/η), total internal
  // reflection; just inside it, partial.
  const float cos_critical = std::sqrt(1.0f - 1.0f / (kEta * kEta));
  EXPECT_EQ(FresnelDielectric(-0.5f * cos_critical, kEta), 1.0f);
  EXPECT_EQ(FresnelDielectric(-0.1f, kEta), 1.0f);
  EXPECT_LT(FresnelDielectric(-1.05f * cos_critical, kEta), 1.0f);
  // Reflectance grows monotonically toward grazing.
  float previous = 0;
  for (float cos_i = 1.0f; cos_i > 0.01f; cos_i -= 0.01f) {
    const float f = FresnelDielectric(cos_i, kEta);
    EXPECT_GE(f, previous - 1e-6f);
    previous = f;
  }
}

TEST(WarpsTest, RefractObeysSnell) {
  constexpr float kEta = 1.5f;
  Uniforms uniforms(0x5e11);
  for (int k = 0; k < 1000; ++k) {
    const float u0 = uniforms.Next(), u1 = uniforms.Next();
    const Vec3 wi = SampleUniformSphere(u0, u1);
    Vec3 wt;
    const bool refracted = Refract(wi, kEta, &wt);
    EXPECT_EQ(refracted, FresnelDielectric(wi.z, kEta) < 1.0f) << "wi.z " << wi.z;
    if (!refracted) continue;
    const float eta_i = wi.z > 0 ? 1.0f : kEta, eta_t = wi.z > 0 ? kEta : 1.0f;
    EXPECT_NEAR(Length(wt), 1.0f, 1e-5f);
    EXPECT_LT(wi.z * wt.z, 0.0f) << "refracted ray stays on its side";
    EXPECT_NEAR(eta_i * SinFromCos(wi.z), eta_t * SinFromCos(wt.z), 1e-5f);
    // wi, wt and the normal are coplanar, wt on the far side of the normal.
    EXPECT_NEAR(wi.x * wt.y - wi.y * wt.x, 0.0f, 1e-5f);
    EXPECT_LE(wi.x * wt.x + wi.y * wt.y, 1e-7f);
  }
}

TEST(WarpsTest, ReflectMirrorsAboutTheNormal) {
  const Vec3 w = Normalize(Vec3(0.3f, -0.4f, 0.5f));
  const Vec3 r = Reflect(w);
  EXPECT_EQ(r.x, -w.x);
  EXPECT_EQ(r.y, -w.y);
  EXPECT_EQ(r.z, w.z);
}

TEST(WarpsTest, SphericalTriangleSamplesAreUniformInItsSolidAngle) {
  // A large triangle close to p: its solid angle matches the formula, each
  // sample's barycentrics give a point of the triangle along its
  // direction, and the mean of f over the samples, times Ω, is ∫ f dω as
  // area sampling (f's cos/d² change of measure) estimates it.
  const Vec3 v[3] = {Vec3(-1, -0.5f, 1), Vec3(1.5f, -0.8f, 0.7f), Vec3(0.2f, 1.2f, 0.9f)};
  const Vec3 p(0.1f, 0.05f, 0);
  const SphericalTriangle seen = SphericalTriangle::Seen(v, p);
  const float solid_angle = seen.area;
  const auto f = [](Vec3 w) { return double(w.z) * w.z + 0.5 * w.x; };
  const Vec3 normal = Normalize(Cross(v[1] - v[0], v[2] - v[0]));
  const double area = 0.5 * Length(Cross(v[1] - v[0], v[2] - v[0]));
  Uniforms uniforms(0x5a);
  double by_angle = 0, by_angle2 = 0, by_area = 0, by_area2 = 0, omega = 0;
  constexpr int kCount = 400'000;
  for (int k = 0; k < kCount; ++k) {
    const float u0 = uniforms.Next(), u1 = uniforms.Next();
    std::array<float, 3> b;
    ASSERT_TRUE(SampleSphericalTriangle(v, p, seen, u0, u1, b));
    ASSERT_GE(std::min({b[0], b[1], b[2]}), 0.0f);
    ASSERT_NEAR(b[0] + b[1] + b[2], 1.0f, 1e-5f);
    const Vec3 w = Normalize(v[0] * b[0] + v[1] * b[1] + v[2] * b[2] - p);
    const double x = f(w) * solid_angle;
    by_angle += x, by_angle2 += x * x;
    // The same integral by points uniform in area.
    const auto a = SampleUniformTriangle(u1, u0);
    const Vec3 q = v[0] * a[0] + v[1] * a[1] + v[2] * a[2] - p;
    const double d2 = Dot(q, q), cos = std::abs(Dot(normal, q)) / std::sqrt(d2);
    const double y = f(q / float(std::sqrt(d2))) * cos / d2 * area;
    by_area += y, by_area2 += y * y;
    omega += cos / d2 * area;
  }
  const auto error = [](double sum, double sum2) { return std::sqrt((sum2 / kCount - sum * sum / kCount / kCount) / kCount); };
  EXPECT_NEAR(solid_angle, omega / kCount, 0.01 * solid_angle);
  EXPECT_NEAR(by_angle / kCount, by_area / kCount, 4 * std::hypot(error(by_angle, by_angle2), error(by_area, by_area2)));
  // Seen from a corner there is nothing to sample.
  std::array<float, 3> b;
  EXPECT_FALSE(SampleSphericalTriangle(v, v[0], SphericalTriangle::Seen(v, v[0]), 0.3f, 0.6f, b));
  EXPECT_EQ(SphericalTriangle::Seen(v, v[0]).area, 0.0f);
}

}  // namespace
}  // namespace yarf
