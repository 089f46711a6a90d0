// Tests of the warp plugins (warps/*.cc), loaded through the registry as
// yarfd loads them. For every warp: its samples follow its own Pdf
// (Pearson's χ² goodness-of-fit test, as Mitsuba 3 and pbrt test their
// warps), its Pdf integrates to 1 over the image and is 0 off it, Forward
// reports the density Pdf gives, and Inverse undoes Forward where an
// inverse exists. The GGX visible normals are tested for several
// roughnesses and view directions, anisotropic and grazing included.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <memory>
#include <optional>
#include <ostream>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "components/registry.h"
#include "yarf/support/chi_square.h"
#include "yarf/support/hash.h"
#include "yarf/math.h"
#include "yarf/support/warps.h"

namespace yarf {
namespace {

constexpr double kPiDouble = 3.14159265358979323846;
constexpr int kSampleCount = 1'000'000;

using Point2D = std::array<double, 2>;

enum class ImageKind { kDisk, kTriangle, kDirections };

// One configured warp under test.
struct WarpCase {
  std::string label;  // the test's name
  std::string name;   // the component class
  Properties props;
  ImageKind image = ImageKind::kDirections;
  // Directions: the support lies in cos θ ≥ z_min.
  double z_min = -1;
  bool invertible = true;
};

void PrintTo(const WarpCase& c, std::ostream* os) { *os << c.label; }

Properties Props(std::initializer_list<std::pair<std::string, Properties::Value>> values) {
  Properties props;
  for (const auto& [key, value] : values) props.Set(key, value);
  return props;
}

std::vector<WarpCase> BasicCases() {
  using enum ImageKind;
  return {
      {"concentric_disk", "concentric_disk", {}, kDisk},
      {"cosine_hemisphere", "cosine_hemisphere", {}, kDirections, 0.0},
      {"uniform_sphere", "uniform_sphere", {}, kDirections, -1.0},
      {"uniform_hemisphere", "uniform_hemisphere", {}, kDirections, 0.0},
      {"uniform_cone_default", "uniform_cone", {}, kDirections, 0.9},
      {"uniform_cone_narrow", "uniform_cone", Props({{"cos_theta_max", 0.995}}), kDirections,
       0.995},
      {"uniform_cone_wide", "uniform_cone", Props({{"cos_theta_max", -0.37}}), kDirections, -0.37},
      {"uniform_triangle", "uniform_triangle", {}, kTriangle},
      {"phong_lobe_0", "phong_lobe", Props({{"exponent", 0.0}}), kDirections, 0.0},
      {"phong_lobe_default", "phong_lobe", {}, kDirections, 0.0},
      {"phong_lobe_3_5", "phong_lobe", Props({{"exponent", 3.5}}), kDirections, 0.0},
      {"phong_lobe_200", "phong_lobe", Props({{"exponent", int64_t(200)}}), kDirections, 0.0},
  };
}

WarpCase Ggx(std::string label, double alpha_x, double alpha_y, Vec3 wi) {
  return {std::move(label), "ggx_visible_normals",
          Props({{"alpha_x", alpha_x}, {"alpha_y", alpha_y}, {"wi", wi}}), ImageKind::kDirections,
          0.0, false};
}

std::vector<WarpCase> GgxCases() {
  return {
      {"defaults", "ggx_visible_normals", {}, ImageKind::kDirections, 0.0, false},
      Ggx("rough_normal_incidence", 0.5, 0.5, Vec3(0, 0, 1)),
      Ggx("smooth_tilted", 0.1, 0.1, Vec3(0.3f, 0.2f, 0.9f)),
      Ggx("anisotropic", 0.2, 0.6, Vec3(0.5f, -0.4f, 0.6f)),
      Ggx("anisotropic_normal_incidence", 0.05, 0.3, Vec3(0, 0, 1)),
      Ggx("grazing", 0.3, 0.3, Vec3(1.0f, 0.0f, 0.02f)),
      Ggx("anisotropic_grazing", 0.8, 0.15, Vec3(-0.3f, 1.0f, 0.05f)),
      Ggx("very_rough", 2.0, 2.0, Vec3(0.7f, 0.1f, 0.4f)),
      Ggx("nearly_horizontal", 0.5, 0.5, Vec3(0.6f, 0.8f, 0.001f)),
  };
}

// Every χ² test of this file together keeps a 1% chance of a false
// failure (Šidák's correction: 1 - (1 - α)^(1/tests) per test).
double Significance() {
  const double tests = double(BasicCases().size() + GgxCases().size());
  return 1.0 - std::pow(1.0 - 0.01, 1.0 / tests);
}

// Uniform numbers from a hash: reproducible, independent per (seed, k, d).
float UniformAt(uint64_t seed, uint64_t k, uint32_t d) {
  return ToUnitFloat(uint32_t(Hash(seed, k, d) >> 32));
}

// --- Charts: the image seen as a rectangle of 2-D coordinates -------------

// How the χ² test bins a warp's image and how the tests integrate over it.
struct Chart {
  double a_min, a_max, b_min, b_max;
  // Writes the image point at chart coordinates (a, b); returns the
  // image's measure per unit of chart area there (the Jacobian).
  std::function<double(double a, double b, float* point)> point_at;
  // The chart coordinates of an image point; none when it is off the chart.
  std::function<std::optional<Point2D>(const float* point)> coordinates_of;
  // Whether the image is the unit sphere (its points must be unit vectors).
  bool directions = false;
};

Chart DiskChart() {
  return {-1.0, 1.0, -1.0, 1.0,
          [](double x, double y, float* p) {
            p[0] = float(x);
            p[1] = float(y);
            return 1.0;
          },
          [](const float* p) -> std::optional<Point2D> {
            if (std::abs(p[0]) > 1.0f || std::abs(p[1]) > 1.0f) return std::nullopt;
            return Point2D{p[0], p[1]};
          }};
}

// The barycentric triangle in the (b0, b1) plane; b2 follows.
Chart TriangleChart() {
  return {0.0, 1.0, 0.0, 1.0,
          [](double b0, double b1, float* p) {
            p[0] = float(b0);
            p[1] = float(b1);
            p[2] = float(1.0 - b0 - b1);
            return 1.0;
          },
          [](const float* p) -> std::optional<Point2D> {
            if (!(p[0] >= 0 && p[0] <= 1 && p[1] >= 0 && p[1] <= 1)) return std::nullopt;
            if (std::abs(double(p[0]) + p[1] + p[2] - 1.0) > 1e-5) return std::nullopt;
            return Point2D{p[0], p[1]};
          }};
}

// The cap of directions with cos θ ≥ z_min, in coordinates (s, φ) with
// cos θ = 1 - (1 - z_min)·s². Rows of equal s are cells of (cos θ, φ)
// that shrink toward the pole, so that a lobe peaked there (a sharp Phong
// or GGX) still spreads over many rows; dω = d(cos θ) dφ = 2(1 - z_min)·s
// ds dφ.
Chart CapChart(double z_min) {
  const double height = 1.0 - z_min;
  return {0.0, 1.0, -kPiDouble, kPiDouble,
          [height](double s, double phi, float* p) {
            const double one_minus_z = height * s * s;
            const double sin_theta = std::sqrt(std::max(0.0, one_minus_z * (2.0 - one_minus_z)));
            p[0] = float(sin_theta * std::cos(phi));
            p[1] = float(sin_theta * std::sin(phi));
            p[2] = float(1.0 - one_minus_z);
            return 2.0 * height * s;
          },
          [height](const float* p) -> std::optional<Point2D> {
            const double x = p[0], y = p[1], z = p[2];
            // 1 - cos θ from sin θ near the pole, where 1 - z cancels.
            const double one_minus_z = z > 0 ? (x * x + y * y) / (1.0 + z) : 1.0 - z;
            double s = std::sqrt(one_minus_z / height);
            // Rounding may put a sample of the rim a hair outside.
            if (s > 1.0 && s < 1.0 + 1e-5) s = 1.0;
            if (!(s <= 1.0)) return std::nullopt;
            return Point2D{s, std::atan2(y, x)};
          },
          true};
}

// The band z_lo ≤ cos θ ≤ z_hi in coordinates (cos θ, φ).
Chart BandChart(double z_lo, double z_hi) {
  return {z_lo, z_hi, -kPiDouble, kPiDouble,
          [](double z, double phi, float* p) {
            const double sin_theta = std::sqrt(std::max(0.0, 1.0 - z * z));
            p[0] = float(sin_theta * std::cos(phi));
            p[1] = float(sin_theta * std::sin(phi));
            p[2] = float(z);
            return 1.0;
          },
          [](const float*) -> std::optional<Point2D> { return std::nullopt; },
          true};
}

// ∫ pdf dμ over each of rows × cols cells of the chart, in one Pdf call
// per row: 5-point Gauss–Legendre in each coordinate on each of sub × sub
// sub-cells, so that the support's rim crossing a cell costs little
// accuracy.
std::vector<double> CellMasses(const Warp& warp, const Chart& chart, int rows, int cols, int sub) {
  static constexpr double kNodes[] = {-0.9061798459386640, -0.5384693101056831, 0.0,
                                      0.5384693101056831, 0.9061798459386640};
  static constexpr double kWeights[] = {0.2369268850561891, 0.4786286704993665,
                                        0.5688888888888889, 0.4786286704993665,
                                        0.2369268850561891};
  const uint32_t n = warp.ImageDimensions();
  const double da = (chart.a_max - chart.a_min) / (rows * sub);
  const double db = (chart.b_max - chart.b_min) / (cols * sub);
  const size_t per_row = size_t(cols) * sub * sub * 25;
  std::vector<float> points(per_row * n), pdf(per_row);
  std::vector<double> weight(per_row);
  std::vector<double> masses(size_t(rows) * cols, 0.0);
  for (int row = 0; row < rows; ++row) {
    size_t k = 0;
    for (int col = 0; col < cols; ++col)
      for (int i = 0; i < sub; ++i)
        for (int j = 0; j < sub; ++j) {
          const double a_mid = chart.a_min + ((row * sub + i) + 0.5) * da;
          const double b_mid = chart.b_min + ((col * sub + j) + 0.5) * db;
          for (int s = 0; s < 5; ++s)
            for (int t = 0; t < 5; ++t, ++k) {
              const double jacobian = chart.point_at(a_mid + 0.5 * da * kNodes[s],
                                                     b_mid + 0.5 * db * kNodes[t], &points[k * n]);
              weight[k] = kWeights[s] * kWeights[t] * 0.25 * da * db * jacobian;
            }
        }
    warp.Pdf(points, pdf);
    for (size_t m = 0; m < per_row; ++m)
      masses[size_t(row) * cols + m / (size_t(sub) * sub * 25)] += weight[m] * pdf[m];
  }
  return masses;
}

double Integrate(const Warp& warp, const Chart& chart, int rows, int cols) {
  double sum = 0;
  for (double mass : CellMasses(warp, chart, rows, cols, 1)) sum += mass;
  return sum;
}

struct Warped {
  std::vector<float> uniform, points, pdf;
};

Warped ForwardMany(const Warp& warp, int count, uint64_t seed) {
  Warped out;
  const uint32_t m = warp.DomainDimensions(), n = warp.ImageDimensions();
  out.uniform.resize(size_t(count) * m);
  for (int k = 0; k < count; ++k)
    for (uint32_t d = 0; d < m; ++d) out.uniform[size_t(k) * m + d] = UniformAt(seed, k, d);
  out.points.resize(size_t(count) * n);
  out.pdf.resize(count);
  warp.Forward(out.uniform, out.points, out.pdf);
  return out;
}

// Pearson's χ² test that the samples of `sampler` follow the pdf of
// `density`, binned on rows × cols cells of the chart.
testing::AssertionResult SamplesFollowPdf(const Warp& sampler, const Warp& density,
                                          const Chart& chart, int rows, int cols, int sub) {
  const Warped samples = ForwardMany(sampler, kSampleCount, 0x5eed);
  const uint32_t n = sampler.ImageDimensions();
  std::vector<double> observed(size_t(rows) * cols, 0.0);
  for (int k = 0; k < kSampleCount; ++k) {
    const float* p = &samples.points[size_t(k) * n];
    if (chart.directions && std::abs(Length(Vec3::Load(p)) - 1.0f) > 1e-5f)
      return testing::AssertionFailure() << "direction of length " << Length(Vec3::Load(p));
    const std::optional<Point2D> ab = chart.coordinates_of(p);
    if (!ab) {
      testing::AssertionResult failure = testing::AssertionFailure();
      failure << "sample (";
      for (uint32_t d = 0; d < n; ++d) failure << (d ? ", " : "") << p[d];
      return failure << ") outside the image";
    }
    const double fa = ((*ab)[0] - chart.a_min) / (chart.a_max - chart.a_min);
    const double fb = ((*ab)[1] - chart.b_min) / (chart.b_max - chart.b_min);
    const int row = std::clamp(int(fa * rows), 0, rows - 1);
    const int col = std::clamp(int(fb * cols), 0, cols - 1);
    observed[size_t(row) * cols + col] += 1;
  }
  std::vector<double> expected = CellMasses(density, chart, rows, cols, sub);
  for (double& e : expected) e *= kSampleCount;
  return testing_support::PearsonChiSquareTest(observed, expected, Significance());
}

testing::AssertionResult SamplesFollowPdf(const Warp& warp, const WarpCase& c) {
  switch (c.image) {
    case ImageKind::kDisk: return SamplesFollowPdf(warp, warp, DiskChart(), 40, 40, 8);
    // 39 columns: the hypotenuse b0 + b1 = 1 then misses the cells'
    // corners, where a symmetric quadrature rule would put nodes on it.
    case ImageKind::kTriangle: return SamplesFollowPdf(warp, warp, TriangleChart(), 40, 39, 8);
    case ImageKind::kDirections:
      return SamplesFollowPdf(warp, warp, CapChart(c.z_min), 100, 200, 2);
  }
  return testing::AssertionFailure();
}

float PdfAt(const Warp& warp, std::vector<float> point) {
  float pdf = -1;
  warp.Pdf(point, std::span<float>(&pdf, 1));
  return pdf;
}

// --- The tests ----------------------------------------------------------

class WarpComponentTest : public testing::Test {
 protected:
  WarpComponentTest() { registry_.LoadDirectory(YARF_PLUGIN_DIR); }

  std::unique_ptr<Warp> Make(const std::string& name, const Properties& props = {}) const {
    return registry_.CreateAs<Warp>(name, props);
  }

  // The message of the Error that creating `name` with `props` throws.
  std::string CreationError(const std::string& name, const Properties& props) const {
    try {
      registry_.Create(name, props);
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  }

  Registry registry_;
};

TEST_F(WarpComponentTest, RegistersEveryWarpWithItsSignature) {
  const struct {
    const char* name;
    uint32_t domain, image;
  } kWarps[] = {{"concentric_disk", 2, 2},    {"cosine_hemisphere", 2, 3},
                {"uniform_sphere", 2, 3},     {"uniform_hemisphere", 2, 3},
                {"uniform_cone", 2, 3},       {"uniform_triangle", 2, 3},
                {"phong_lobe", 2, 3},         {"ggx_visible_normals", 2, 3}};
  for (const auto& [name, domain, image] : kWarps) {
    ASSERT_TRUE(registry_.Has(name)) << name;
    const auto warp = Make(name);
    EXPECT_EQ(warp->Describe().class_name, name);
    EXPECT_EQ(warp->Describe().interfaces, std::vector<std::string>{Warp::kInterface}) << name;
    EXPECT_FALSE(warp->Describe().summary.empty()) << name;
    EXPECT_EQ(warp->DomainDimensions(), domain) << name;
    EXPECT_EQ(warp->ImageDimensions(), image) << name;
  }
}

TEST_F(WarpComponentTest, RejectsBadProperties) {
  const struct {
    const char* name;
    Properties props;
    const char* key;
  } kBad[] = {
      {"phong_lobe", Props({{"exponent", -1.0}}), "'exponent'"},
      {"phong_lobe", Props({{"exponent", std::nan("")}}), "'exponent'"},
      {"uniform_cone", Props({{"cos_theta_max", 1.0}}), "'cos_theta_max'"},
      {"uniform_cone", Props({{"cos_theta_max", -1.0}}), "'cos_theta_max'"},
      {"uniform_cone", Props({{"cos_theta_max", 1.5}}), "'cos_theta_max'"},
      // Below 1 in double, 1 as a float: the cone would have no width.
      {"uniform_cone", Props({{"cos_theta_max", 0.99999999}}), "'cos_theta_max'"},
      {"ggx_visible_normals", Props({{"alpha_x", 0.0}}), "'alpha_x'"},
      {"ggx_visible_normals", Props({{"alpha_x", -0.2}}), "'alpha_x'"},
      {"ggx_visible_normals", Props({{"alpha_x", 0.2}, {"alpha_y", 0.0}}), "'alpha_y'"},
      {"ggx_visible_normals", Props({{"alpha_y", -1.0}}), "'alpha_y'"},
      {"ggx_visible_normals", Props({{"wi", Vec3(0.3f, 0.0f, -0.5f)}}), "'wi'"},
      {"ggx_visible_normals", Props({{"wi", Vec3(1.0f, 0.0f, 0.0f)}}), "'wi'"},
      {"ggx_visible_normals", Props({{"wi", Vec3(0.0f, 0.0f, 0.0f)}}), "'wi'"},
      {"ggx_visible_normals", Props({{"wi", 1.0}}), "'wi'"},
      // A property no warp knows is reported, not ignored.
      {"concentric_disk", Props({{"radius", 2.0}}), "radius"},
  };
  for (const auto& [name, props, key] : kBad) {
    const std::string message = CreationError(name, props);
    EXPECT_NE(message.find(key), std::string::npos) << name << ": '" << message << "'";
  }
}

TEST_F(WarpComponentTest, GgxVisibleNormalsHaveNoInverse) {
  const auto warp = Make("ggx_visible_normals");
  std::vector<float> point = {0, 0, 1}, uniform(2), pdf(1);
  try {
    warp->Inverse(point, uniform, pdf);
    FAIL() << "Inverse did not throw";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("has no inverse"), std::string::npos) << e.what();
  }
}

// The pdf against the closed forms in θ: D(m) = 1 / (π α² cos⁴θm (1 +
// tan²θm / α²)²) and G1(wi) = 2 / (1 + √(1 + α² tan²θi)) for an isotropic
// α, and D_wi(m) = G1(wi) (wi·m) D(m) / cos θi, which at normal incidence
// is D(m) cos θm.
TEST_F(WarpComponentTest, GgxVisibleNormalPdfMatchesClosedForms) {
  constexpr double kAlpha = 0.4;
  const auto closed_d = [&](Vec3 m) {
    const double cos2 = double(m.z) * m.z, tan2 = (1 - cos2) / cos2;
    const double e = 1 + tan2 / (kAlpha * kAlpha);
    return 1 / (kPiDouble * kAlpha * kAlpha * cos2 * cos2 * e * e);
  };
  const auto closed_g1 = [&](Vec3 w) {
    const double cos2 = double(w.z) * w.z, tan2 = (1 - cos2) / cos2;
    return 2 / (1 + std::sqrt(1 + kAlpha * kAlpha * tan2));
  };
  for (const Vec3 wi : {Vec3(0, 0, 1), Normalize(Vec3(0.5f, 0.2f, 0.7f)),
                        Normalize(Vec3(-0.9f, 0.3f, 0.1f))}) {
    const auto warp =
        Make("ggx_visible_normals", Props({{"alpha_x", kAlpha}, {"alpha_y", kAlpha}, {"wi", wi}}));
    for (const Vec3 m : {Vec3(0, 0, 1), Normalize(Vec3(0.1f, -0.2f, 0.9f)),
                         Normalize(Vec3(0.4f, 0.3f, 0.5f)), Normalize(Vec3(-0.6f, 0.1f, 0.3f))}) {
      const double cos_wi_m = std::max(0.0, double(Dot(wi, m)));
      const double expected = closed_g1(wi) * cos_wi_m * closed_d(m) / wi.z;
      EXPECT_NEAR(PdfAt(*warp, {m.x, m.y, m.z}), expected, 1e-5 * (1 + expected))
          << "wi " << wi.x << "," << wi.y << "," << wi.z << " m " << m.x << "," << m.y << ","
          << m.z;
      if (wi.z == 1.0f) {
        EXPECT_NEAR(expected, closed_d(m) * m.z, 1e-6 * (1 + expected));
      }
    }
  }
}

TEST_F(WarpComponentTest, ChiSquareDetectsASlightlyWrongPdf) {
  // The test has power: GGX normals sampled with α = 0.3 are told apart
  // from a pdf with α = 0.33, Phong directions of exponent 30 from 33.
  const Vec3 wi = Normalize(Vec3(1.0f, 0.0f, 0.3f));
  const auto ggx = Make("ggx_visible_normals", Props({{"alpha_x", 0.3}, {"wi", wi}}));
  const auto ggx_wrong = Make("ggx_visible_normals", Props({{"alpha_x", 0.33}, {"wi", wi}}));
  EXPECT_FALSE(SamplesFollowPdf(*ggx, *ggx_wrong, CapChart(0.0), 100, 200, 2));
  const auto phong = Make("phong_lobe");
  const auto phong_wrong = Make("phong_lobe", Props({{"exponent", 33.0}}));
  EXPECT_FALSE(SamplesFollowPdf(*phong, *phong_wrong, CapChart(0.0), 100, 200, 2));
}

class WarpCaseTest : public testing::TestWithParam<WarpCase> {
 protected:
  WarpCaseTest() {
    registry_.LoadDirectory(YARF_PLUGIN_DIR);
    warp_ = registry_.CreateAs<Warp>(GetParam().name, GetParam().props);
  }

  // Declared first: the instance's code lives in the registry's plugins.
  Registry registry_;
  std::unique_ptr<Warp> warp_;
};

TEST_P(WarpCaseTest, SamplesFollowPdf) {
  const testing::AssertionResult result = SamplesFollowPdf(*warp_, GetParam());
  EXPECT_TRUE(result);
  RecordProperty("chi_square", result.message());
}

TEST_P(WarpCaseTest, PdfIntegratesToOneOverTheImage) {
  const WarpCase& c = GetParam();
  if (c.image == ImageKind::kDirections) {
    // Fine rows near the pole for the sharp lobes.
    EXPECT_NEAR(Integrate(*warp_, CapChart(c.z_min), 2000, 64), 1.0, 1e-3);
    if (c.z_min > -1) {
      EXPECT_EQ(Integrate(*warp_, BandChart(-1.0, c.z_min), 200, 64), 0.0);
    }
  } else {
    // The box around the disk or triangle, so a pdf leaking outside would show.
    Chart chart = c.image == ImageKind::kDisk ? DiskChart() : TriangleChart();
    chart.a_min -= 0.1;
    chart.a_max += 0.1;
    chart.b_min -= 0.1;
    chart.b_max += 0.1;
    EXPECT_NEAR(Integrate(*warp_, chart, 1000, 1000), 1.0, 1e-3);
  }
}

TEST_P(WarpCaseTest, PdfIsZeroOffTheImage) {
  const WarpCase& c = GetParam();
  std::vector<std::vector<float>> off;
  switch (c.image) {
    case ImageKind::kDisk: off = {{0.8f, 0.8f}, {1.01f, 0.0f}, {0.0f, -1.5f}}; break;
    case ImageKind::kTriangle:
      off = {{0.5f, 0.6f, -0.1f}, {-0.1f, 0.6f, 0.5f}, {0.3f, 0.3f, 0.3f}, {1.2f, -0.1f, -0.1f}};
      break;
    case ImageKind::kDirections:
      off = {{0.0f, 0.0f, 2.0f}, {0.5f, 0.5f, 0.5f}, {0.0f, 0.0f, 0.0f}};
      if (c.z_min > -1) {
        const float z = float(std::max(-1.0, c.z_min - 0.05));
        off.push_back({SinFromCos(z), 0.0f, z});
      }
      break;
  }
  for (const auto& point : off)
    EXPECT_EQ(PdfAt(*warp_, point), 0.0f) << point[0] << ", " << point[1] << ", " << point.back();
}

TEST_P(WarpCaseTest, ForwardReportsThePdfOfItsPoints) {
  constexpr int kCount = 100'000;
  const Warped samples = ForwardMany(*warp_, kCount, 0xf0);
  std::vector<float> pdf(kCount);
  warp_->Pdf(samples.points, pdf);
  for (int k = 0; k < kCount; ++k) {
    ASSERT_GT(samples.pdf[k], 0.0f) << "sample " << k;
    ASSERT_NEAR(samples.pdf[k], pdf[k], 1e-6f * pdf[k]) << "sample " << k;
  }
}

TEST_P(WarpCaseTest, InverseUndoesForward) {
  const WarpCase& c = GetParam();
  constexpr int kCount = 100'000;
  const Warped samples = ForwardMany(*warp_, kCount, 0x1ee);
  std::vector<float> uniform(samples.uniform.size()), pdf(kCount);
  if (!c.invertible) {
    EXPECT_THROW(warp_->Inverse(samples.points, uniform, pdf), Error);
    return;
  }
  warp_->Inverse(samples.points, uniform, pdf);
  const uint32_t m = warp_->DomainDimensions(), n = warp_->ImageDimensions();
  int on_pole = 0;
  for (int k = 0; k < kCount; ++k) {
    // A direction rounded onto the pole has lost its azimuth: any u1 maps
    // to it. Rare (u0 within ~1e-5 of the end that maps to the pole).
    if (c.image == ImageKind::kDirections && samples.points[k * n] == 0 &&
        samples.points[k * n + 1] == 0) {
      ++on_pole;
      ASSERT_NEAR(uniform[k * m], samples.uniform[k * m], 1e-4f) << "sample " << k;
      continue;
    }
    for (uint32_t d = 0; d < m; ++d)
      ASSERT_NEAR(uniform[k * m + d], samples.uniform[k * m + d], 1e-4f)
          << "sample " << k << ", coordinate " << d;
    ASSERT_EQ(pdf[k], samples.pdf[k]) << "sample " << k;
  }
  EXPECT_LE(on_pole, 5);
}

std::string CaseName(const testing::TestParamInfo<WarpCase>& info) { return info.param.label; }

INSTANTIATE_TEST_SUITE_P(Warps, WarpCaseTest, testing::ValuesIn(BasicCases()), CaseName);
INSTANTIATE_TEST_SUITE_P(GgxVisibleNormals, WarpCaseTest, testing::ValuesIn(GgxCases()), CaseName);

}  // namespace
}  // namespace yarf
