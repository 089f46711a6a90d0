// What the surface-model tests (bsdf_test.cc, microfacet_test.cc) share:
// a fixture that loads the plugins as yarfd does, calls of the batch
// interface for one direction or one wi at a time, reproducible uniform
// numbers, the mean of Sample's weights, and the binning of sampled
// directions for Pearson's χ² test. Each test file keeps the quadrature
// its own models need.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "components/registry.h"
#include "yarf/support/chi_square.h"
#include "yarf/support/hash.h"
#include "yarf/surface.h"
#include "yarf/support/warps.h"

namespace yarf::surface_testing {

inline constexpr double kPiDouble = 3.14159265358979323846;

// --- The plugins, loaded as yarfd loads them -------------------------------

class SurfacePluginTest : public testing::Test {
 protected:
  SurfacePluginTest() { registry_.LoadDirectory(YARF_PLUGIN_DIR); }

  std::unique_ptr<SurfaceModel> Make(const std::string& name,
                                     const Properties& props = Properties()) const {
    return registry_.CreateAs<SurfaceModel>(name, props);
  }

  // `name` is registered, under that class name, as a SurfaceModel with a
  // summary. (A fatal failure when it is missing: wrap the call in
  // ASSERT_NO_FATAL_FAILURE to stop there.)
  void ExpectRegisteredSurfaceModel(const std::string& name) const {
    ASSERT_TRUE(registry_.Has(name)) << name;
    const auto model = Make(name);
    const ComponentInfo& info = model->Describe();
    EXPECT_EQ(info.class_name, name);
    EXPECT_EQ(info.interfaces, std::vector<std::string>{SurfaceModel::kInterface}) << name;
    EXPECT_FALSE(info.summary.empty()) << name;
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

// Properties from a list of key-value pairs.
inline Properties Props(std::initializer_list<std::pair<std::string, Properties::Value>> values) {
  Properties props;
  for (const auto& [key, value] : values) props.Set(key, value);
  return props;
}

// --- Calling the batch interface -------------------------------------------

inline Vec3 EvaluateOne(const SurfaceModel& model, Vec3 wi, Vec3 wo,
                        TransportMode mode = TransportMode::kRadiance) {
  float in[3], out[3], value[3];
  const float uv[2] = {0, 0};
  wi.Store(in);
  wo.Store(out);
  model.Evaluate(mode, in, out, SurfacePoints{.uv = uv}, value);
  return Vec3::Load(value);
}

inline float PdfOne(const SurfaceModel& model, Vec3 wi, Vec3 wo) {
  float in[3], out[3], pdf[1];
  const float uv[2] = {0, 0};
  wi.Store(in);
  wo.Store(out);
  model.Pdf(in, out, SurfacePoints{.uv = uv}, pdf);
  return pdf[0];
}

// Pdf and Evaluate of one wi against many wo, in one call each.
inline std::vector<float> PdfBatch(const SurfaceModel& model, Vec3 wi,
                                   const std::vector<Vec3>& wo) {
  const size_t count = wo.size();
  std::vector<float> in(3 * count), out(3 * count), uv(2 * count, 0.0f), pdf(count);
  for (size_t k = 0; k < count; ++k) {
    wi.Store(&in[3 * k]);
    wo[k].Store(&out[3 * k]);
  }
  model.Pdf(in, out, SurfacePoints{.uv = uv}, pdf);
  return pdf;
}

inline std::vector<Vec3> EvaluateBatch(const SurfaceModel& model, Vec3 wi,
                                       const std::vector<Vec3>& wo, TransportMode mode) {
  const size_t count = wo.size();
  std::vector<float> in(3 * count), out(3 * count), uv(2 * count, 0.0f), value(3 * count);
  for (size_t k = 0; k < count; ++k) {
    wi.Store(&in[3 * k]);
    wo[k].Store(&out[3 * k]);
  }
  model.Evaluate(mode, in, out, SurfacePoints{.uv = uv}, value);
  std::vector<Vec3> result(count);
  for (size_t k = 0; k < count; ++k) result[k] = Vec3::Load(&value[3 * k]);
  return result;
}

// One row of Sample's result.
struct Scattered {
  Vec3 wo, weight;
  float pdf = 0;
  uint32_t flags = kScatterNone;
};

// Sample for a batch of (wi, uniform) pairs in one call.
inline std::vector<Scattered> SampleBatch(const SurfaceModel& model, const std::vector<Vec3>& wi,
                                          const std::vector<std::array<float, 3>>& uniform,
                                          uint32_t allowed = 0,
                                          TransportMode mode = TransportMode::kRadiance) {
  const size_t count = wi.size();
  std::vector<float> in(3 * count), uv(2 * count, 0.0f), u(3 * count), wo(3 * count),
      weight(3 * count), pdf(count);
  std::vector<uint32_t> flags(count);
  for (size_t k = 0; k < count; ++k) {
    wi[k].Store(&in[3 * k]);
    std::copy(uniform[k].begin(), uniform[k].end(), &u[3 * k]);
  }
  model.Sample(mode, in, SurfacePoints{.uv = uv}, u, allowed, wo, weight, pdf, flags);
  std::vector<Scattered> out(count);
  for (size_t k = 0; k < count; ++k)
    out[k] = {Vec3::Load(&wo[3 * k]), Vec3::Load(&weight[3 * k]), pdf[k], flags[k]};
  return out;
}

inline Scattered SampleOne(const SurfaceModel& model, Vec3 wi, std::array<float, 3> uniform,
                           uint32_t allowed = 0, TransportMode mode = TransportMode::kRadiance) {
  return SampleBatch(model, {wi}, {uniform}, allowed, mode)[0];
}

// Uniform numbers from a hash: reproducible, and independent per (seed, k).
inline std::array<float, 3> Uniform3(uint64_t seed, uint64_t k) {
  return {ToUnitFloat(uint32_t(Hash(seed, k, 0) >> 32)),
          ToUnitFloat(uint32_t(Hash(seed, k, 1) >> 32)),
          ToUnitFloat(uint32_t(Hash(seed, k, 2) >> 32))};
}

// `count` samples at one wi. With `stratify_lobe`, the lobe choice
// uniform[0] is (k + ½)/count.
inline std::vector<Scattered> SampleMany(const SurfaceModel& model, Vec3 wi, int count,
                                         uint64_t seed, uint32_t allowed = 0,
                                         TransportMode mode = TransportMode::kRadiance,
                                         bool stratify_lobe = false) {
  std::vector<std::array<float, 3>> uniform(count);
  for (int k = 0; k < count; ++k) {
    uniform[k] = Uniform3(seed, k);
    if (stratify_lobe) uniform[k][0] = (k + 0.5f) / count;
  }
  return SampleBatch(model, std::vector<Vec3>(count, wi), uniform, allowed, mode);
}

struct MeanWithError {
  Vec3 mean, standard_error;
  double success = 0;  // fraction of the samples that Sample produced
};

// The mean of Sample's weight: an unbiased estimate of the albedo.
inline MeanWithError MeanWeight(const std::vector<Scattered>& samples) {
  double sum[3] = {0, 0, 0}, sum2[3] = {0, 0, 0};
  int produced = 0;
  for (const Scattered& s : samples) {
    if (s.pdf > 0) ++produced;
    for (int c = 0; c < 3; ++c) {
      sum[c] += s.weight[c];
      sum2[c] += double(s.weight[c]) * s.weight[c];
    }
  }
  const double n = double(samples.size());
  float mean[3], error[3];
  for (int c = 0; c < 3; ++c) {
    mean[c] = float(sum[c] / n);
    error[c] = float(std::sqrt(std::max(0.0, sum2[c] / n - mean[c] * double(mean[c])) / n));
  }
  return {Vec3(mean[0], mean[1], mean[2]), Vec3(error[0], error[1], error[2]), produced / n};
}

// --- Integrals over the sphere of directions -------------------------------

// Midpoint rule in (θ, φ), dω = sin θ dθ dφ: uniform in θ, so a lobe
// around the normal spans many rows; the horizon is a row boundary.
struct SphereGrid {
  std::vector<Vec3> directions;
  std::vector<double> weights;
};

inline const SphereGrid& Grid() {
  static const SphereGrid grid = [] {
    constexpr int kRows = 600, kCols = 300;
    const double dtheta = kPiDouble / kRows, dphi = 2 * kPiDouble / kCols;
    SphereGrid g;
    for (int i = 0; i < kRows; ++i)
      for (int j = 0; j < kCols; ++j) {
        const double theta = (i + 0.5) * dtheta, phi = -kPiDouble + (j + 0.5) * dphi;
        g.directions.push_back(
            SphericalDirection(float(std::sin(theta)), float(std::cos(theta)), float(phi)));
        g.weights.push_back(std::sin(theta) * dtheta * dphi);
      }
    return g;
  }();
  return grid;
}

struct SphereIntegrals {
  double pdf = 0;  // ∫ pdf dωo
  Vec3 albedo;     // ∫ f |cos θo| dωo
};

inline SphereIntegrals IntegrateOverSphere(const SurfaceModel& model, Vec3 wi,
                                           TransportMode mode = TransportMode::kRadiance) {
  const SphereGrid& grid = Grid();
  const std::vector<float> pdf = PdfBatch(model, wi, grid.directions);
  const std::vector<Vec3> value = EvaluateBatch(model, wi, grid.directions, mode);
  double pdf_sum = 0, albedo[3] = {0, 0, 0};
  for (size_t k = 0; k < pdf.size(); ++k) {
    pdf_sum += grid.weights[k] * pdf[k];
    for (int c = 0; c < 3; ++c)
      albedo[c] += grid.weights[k] * value[k][c] * std::abs(grid.directions[k].z);
  }
  return {pdf_sum, Vec3(float(albedo[0]), float(albedo[1]), float(albedo[2]))};
}

// --- Directions and their comparison ----------------------------------------

inline Vec3 DirectionAt(double cos_theta, double phi) {
  return SphericalDirection(SinFromCos(float(cos_theta)), float(cos_theta), float(phi));
}

inline std::string Describe(Vec3 v) {
  std::ostringstream s;
  s << "(" << v.x << ", " << v.y << ", " << v.z << ")";
  return s.str();
}

inline void ExpectVecNear(Vec3 actual, Vec3 expected, float relative, const std::string& what) {
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(actual[c], expected[c], relative * std::max(1.0f, std::abs(expected[c])))
        << what << " channel " << c << ": " << Describe(actual) << " vs " << Describe(expected);
}

// --- Pearson's χ² test of sampled directions -------------------------------

// The cells: kChiRows in cos θ by kChiCols in φ, of equal solid angle
// (dω = d cos θ dφ), numbered row * kChiCols + col.
inline constexpr int kChiRows = 50, kChiCols = 100;

// The 5-point Gauss–Legendre rule on [-1, 1], by which the tests
// integrate the pdf over a cell: its nodes lie inside the cell, so a jump
// of the pdf at a cell edge (the horizon) falls on the correct side.
inline constexpr double kGaussNodes[] = {-0.9061798459386640, -0.5384693101056831, 0.0,
                                         0.5384693101056831, 0.9061798459386640};
inline constexpr double kGaussWeights[] = {0.2369268850561891, 0.4786286704993665,
                                           0.5688888888888889, 0.4786286704993665,
                                           0.2369268850561891};

// Bins the directions in the cells and tests the counts against
// `expected` (N ∫ pdf over each cell) at significance 0.01.
inline testing::AssertionResult CellsFollowExpected(const std::vector<Vec3>& directions,
                                                    const std::vector<double>& expected) {
  constexpr double kSignificance = 0.01;
  std::vector<double> observed(kChiRows * kChiCols, 0.0);
  for (Vec3 w : directions) {
    const double z = std::clamp(double(w.z), -1.0, 1.0);
    const double phi = std::atan2(double(w.y), double(w.x));
    const int row = std::min(int((z + 1.0) / 2.0 * kChiRows), kChiRows - 1);
    const int col =
        std::clamp(int((phi + kPiDouble) / (2 * kPiDouble) * kChiCols), 0, kChiCols - 1);
    observed[row * kChiCols + col] += 1;
  }
  return testing_support::PearsonChiSquareTest(observed, expected, kSignificance);
}

// The expected count of a (cos θ, φ) cell is N ∫ pdf over it, by 5-point
// Gauss–Legendre quadrature in θ (dω = sin θ dθ dφ) on each of a few
// slices of it, and across it in φ (all pdf values in one Pdf call). The
// two rows at the poles, where a lobe around the normal (a refraction,
// narrower than its microfacets' spread) lies whole, are cut in many more
// slices.
inline testing::AssertionResult DirectionsFollowPdf(const SurfaceModel& model, Vec3 wi,
                                             const std::vector<Vec3>& directions,
                                             int sample_count) {
  constexpr int kSlices = 4, kPoleSlices = 32;
  const double dz = 2.0 / kChiRows, dphi = 2 * kPiDouble / kChiCols;
  std::vector<double> expected(kChiRows * kChiCols, 0.0);
  std::vector<Vec3> nodes;
  std::vector<double> weights;  // of each node: its share of N ∫ pdf dω
  std::vector<int> cells;       // the cell of each node
  for (int row = 0; row < kChiRows; ++row) {
    // θ decreases as cos θ grows: the row spans θ in [theta_top, theta_bottom].
    const double theta_top = std::acos(std::min(1.0, -1.0 + (row + 1) * dz));
    const double theta_bottom = std::acos(std::max(-1.0, -1.0 + row * dz));
    const int slices = row == 0 || row == kChiRows - 1 ? kPoleSlices : kSlices;
    const double dtheta = (theta_bottom - theta_top) / slices;
    for (int col = 0; col < kChiCols; ++col) {
      const double phi_mid = -kPiDouble + (col + 0.5) * dphi;
      for (int slice = 0; slice < slices; ++slice) {
        const double theta_mid = theta_top + (slice + 0.5) * dtheta;
        for (int s = 0; s < 5; ++s) {
          const double theta = theta_mid + 0.5 * dtheta * kGaussNodes[s];
          for (int t = 0; t < 5; ++t) {
            nodes.push_back(SphericalDirection(float(std::sin(theta)), float(std::cos(theta)),
                                               float(phi_mid + 0.5 * dphi * kGaussNodes[t])));
            weights.push_back(sample_count * kGaussWeights[s] * kGaussWeights[t] *
                              std::sin(theta) * (0.5 * dtheta) * (0.5 * dphi));
            cells.push_back(row * kChiCols + col);
          }
        }
      }
    }
  }
  const std::vector<float> pdf = PdfBatch(model, wi, nodes);
  for (size_t k = 0; k < nodes.size(); ++k) expected[cells[k]] += weights[k] * pdf[k];
  return CellsFollowExpected(directions, expected);
}

}  // namespace yarf::surface_testing
