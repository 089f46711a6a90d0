// Integrands with closed-form integrals that the integrator tests share:
// Genz's test families (oscillatory, product and corner peak, Gaussian,
// discontinuous), a polynomial, a sum of smooth functions of two variables
// each, and the families every error bar is calibrated on.
#pragma once

#include <cmath>
#include <complex>
#include <cstdint>
#include <memory>
#include <numbers>
#include <span>
#include <utility>
#include <vector>

#include "yarf/math.h"

namespace yarf {

// Genz's oscillatory family: cos(2πw + Σ a_j x_j) over [0,1]^d, whose
// integral is Re(e^{2πiw} Π_j (e^{i a_j} − 1) / (i a_j)).
class Oscillatory final : public Function {
 public:
  Oscillatory(std::vector<double> a, double w) : a_(std::move(a)), w_(w) {}
  uint32_t InputDimensions() const override { return uint32_t(a_.size()); }
  uint32_t OutputDimensions() const override { return 1; }
  void Evaluate(std::span<const float> points, std::span<float> values) override {
    const size_t d = a_.size();
    for (size_t i = 0; i < points.size() / d; ++i) {
      double phase = 2 * std::numbers::pi * w_;
      for (size_t j = 0; j < d; ++j) phase += a_[j] * points[i * d + j];
      values[i] = float(std::cos(phase));
    }
  }
  double Exact() const {
    std::complex<double> z = std::polar(1.0, 2 * std::numbers::pi * w_);
    for (double a : a_) z *= (std::exp(std::complex<double>(0, a)) - 1.0) / std::complex<double>(0, a);
    return z.real();
  }

 private:
  std::vector<double> a_;
  double w_;
};

// f(x) = e^(x0 + x1) + cos(x2 + 2 x3) over [0,1]^4: smooth, a sum of two
// functions of two variables each.
class PairSum final : public Function {
 public:
  uint32_t InputDimensions() const override { return 4; }
  uint32_t OutputDimensions() const override { return 1; }
  void Evaluate(std::span<const float> points, std::span<float> values) override {
    for (size_t i = 0; i < points.size() / 4; ++i) {
      const double x0 = points[4 * i], x1 = points[4 * i + 1], x2 = points[4 * i + 2], x3 = points[4 * i + 3];
      values[i] = float(std::exp(x0 + x1) + std::cos(x2 + 2 * x3));
    }
  }
  // (e − 1)² + Re((e^i − 1)/i · (e^2i − 1)/(2i)).
  static double Exact() {
    const std::complex<double> i(0, 1);
    return (std::numbers::e - 1) * (std::numbers::e - 1) +
           ((std::exp(i) - 1.0) / i * (std::exp(2.0 * i) - 1.0) / (2.0 * i)).real();
  }
};

// Genz's corner-peak family: (1 + Σ a_j x_j)^−(d+1) over [0,1]^d, peaked
// at the origin; its integral is (1 / (d! Π a_j)) Σ_{v ∈ {0,1}^d}
// (−1)^|v| / (1 + a·v).
class CornerPeak final : public Function {
 public:
  explicit CornerPeak(std::vector<double> a) : a_(std::move(a)) {}
  uint32_t InputDimensions() const override { return uint32_t(a_.size()); }
  uint32_t OutputDimensions() const override { return 1; }
  void Evaluate(std::span<const float> points, std::span<float> values) override {
    const size_t d = a_.size();
    for (size_t i = 0; i < points.size() / d; ++i) {
      double s = 1;
      for (size_t j = 0; j < d; ++j) s += a_[j] * points[i * d + j];
      values[i] = float(std::pow(s, -double(d + 1)));
    }
  }
  double Exact() const {
    const size_t d = a_.size();
    double sum = 0;
    for (uint32_t v = 0; v < (1u << d); ++v) {
      double s = 1;
      int bits = 0;
      for (size_t j = 0; j < d; ++j)
        if (v & (1u << j)) s += a_[j], ++bits;
      sum += (bits % 2 ? -1.0 : 1.0) / s;
    }
    double scale = 1;
    for (size_t j = 0; j < d; ++j) scale *= double(j + 1) * a_[j];
    return sum / scale;
  }

 private:
  std::vector<double> a_;
};

// Genz's discontinuous family: exp(Σ_j a_j x_j) where x_0 < w_0 and
// x_1 < w_1, else 0, over [0,1]^d (d >= 2): a jump across two planes that
// no axis-aligned grid edge need meet. Its integral is Π_j (e^{a_j c_j} − 1)
// / a_j with c_j = w_j for j < 2 and 1 beyond.
class Discontinuous final : public Function {
 public:
  Discontinuous(std::vector<double> a, double w0, double w1) : a_(std::move(a)), w_{w0, w1} {}
  uint32_t InputDimensions() const override { return uint32_t(a_.size()); }
  uint32_t OutputDimensions() const override { return 1; }
  void Evaluate(std::span<const float> points, std::span<float> values) override {
    const size_t d = a_.size();
    for (size_t i = 0; i < points.size() / d; ++i) {
      const float* x = &points[i * d];
      if (!(x[0] < w_[0] && x[1] < w_[1])) {
        values[i] = 0;
        continue;
      }
      double s = 0;
      for (size_t j = 0; j < d; ++j) s += a_[j] * x[j];
      values[i] = float(std::exp(s));
    }
  }
  double Exact() const {
    double v = 1;
    for (size_t j = 0; j < a_.size(); ++j) v *= std::expm1(a_[j] * (j < 2 ? w_[j] : 1.0)) / a_[j];
    return v;
  }

 private:
  std::vector<double> a_;
  double w_[2];
};

// f(x, y, z) = (x² y + z + 1, 1); over [0,1]×[0,2]×[-1,1] the integrals
// are 4/3 + 4 and the box's volume, 4.
class Polynomial final : public Function {
 public:
  uint32_t InputDimensions() const override { return 3; }
  uint32_t OutputDimensions() const override { return 2; }
  void Evaluate(std::span<const float> points, std::span<float> values) override {
    for (size_t i = 0; i < points.size() / 3; ++i) {
      const float x = points[3 * i], y = points[3 * i + 1], z = points[3 * i + 2];
      values[2 * i] = x * x * y + z + 1;
      values[2 * i + 1] = 1;
    }
  }
  static constexpr double kLower[] = {0, 0, -1}, kUpper[] = {1, 2, 1};
  static constexpr double kExact = 4.0 / 3.0 + 4.0, kVolume = 4.0;
  double Exact() const { return kExact; }
};

// Genz's product peak Π_j 1 / (a_j⁻² + (x_j - u_j)²) over the unit cube.
class ProductPeak final : public Function {
 public:
  ProductPeak(std::vector<double> a, std::vector<double> u) : a_(std::move(a)), u_(std::move(u)) {}
  uint32_t InputDimensions() const override { return uint32_t(a_.size()); }
  uint32_t OutputDimensions() const override { return 1; }
  void Evaluate(std::span<const float> points, std::span<float> values) override {
    const size_t d = a_.size();
    for (size_t i = 0; i < values.size(); ++i) {
      double v = 1;
      for (size_t j = 0; j < d; ++j) {
        const double t = points[i * d + j] - u_[j];
        v /= 1 / (a_[j] * a_[j]) + t * t;
      }
      values[i] = float(v);
    }
  }
  double Exact() const {
    double v = 1;
    for (size_t j = 0; j < a_.size(); ++j)
      v *= a_[j] * (std::atan(a_[j] * (1 - u_[j])) + std::atan(a_[j] * u_[j]));
    return v;
  }

 private:
  std::vector<double> a_, u_;
};

// A sum of Genz Gaussian peaks Σ_c exp(-Σ_j a_j² (x_j - u_cj)²) over the
// unit cube; a_j = 1 / (σ √2) gives a normal density's shape of width σ.
// Counts its calls and the smallest batch it was given.
class GaussianPeaks final : public Function {
 public:
  GaussianPeaks(std::vector<double> a, std::vector<std::vector<double>> centres)
      : a_(std::move(a)), centres_(std::move(centres)) {}
  uint32_t InputDimensions() const override { return uint32_t(a_.size()); }
  uint32_t OutputDimensions() const override { return 1; }
  void Evaluate(std::span<const float> points, std::span<float> values) override {
    ++calls;
    smallest_batch = std::min<uint64_t>(smallest_batch, values.size());
    points_seen += values.size();
    const size_t d = a_.size();
    for (size_t i = 0; i < values.size(); ++i) {
      double v = 0;
      for (const auto& u : centres_) {
        double exponent = 0;
        for (size_t j = 0; j < d; ++j) {
          const double t = a_[j] * (points[i * d + j] - u[j]);
          exponent += t * t;
        }
        v += std::exp(-exponent);
      }
      values[i] = float(v);
    }
  }
  double Exact() const {
    double sum = 0;
    for (const auto& u : centres_) {
      double v = 1;
      for (size_t j = 0; j < a_.size(); ++j)
        v *= std::sqrt(std::numbers::pi) / (2 * a_[j]) * (std::erf(a_[j] * (1 - u[j])) + std::erf(a_[j] * u[j]));
      sum += v;
    }
    return sum;
  }

  uint64_t calls = 0, smallest_batch = UINT64_MAX, points_seen = 0;

 private:
  std::vector<double> a_;
  std::vector<std::vector<double>> centres_;
};

// A peak of width σ = 0.02 off the centre of the 4-cube.
inline GaussianPeaks NarrowPeak() {
  const double a = 1 / (0.02 * std::sqrt(2.0));
  return GaussianPeaks({a, a, a, a}, {{0.35, 0.6, 0.45, 0.7}});
}

// Two peaks on the diagonal of the 4-cube: the grid's dense regions cross
// in 2⁴ places, of which only two hold a peak.
inline GaussianPeaks DoublePeak() {
  const double a = 1 / (0.05 * std::sqrt(2.0));
  return GaussianPeaks({a, a, a, a}, {{0.33, 0.33, 0.33, 0.33}, {0.67, 0.67, 0.67, 0.67}});
}

inline std::vector<double> Zeros(size_t d) { return std::vector<double>(d, 0.0); }
inline std::vector<double> Ones(size_t d) { return std::vector<double>(d, 1.0); }

// An integrand with a known integral over its box, and the budget at
// which an integrator's error bar is checked on it.
struct CalibrationFamily {
  const char* name;
  std::unique_ptr<Function> f;
  double exact;  // of output 0
  uint64_t evaluations;
  std::vector<double> lower, upper;
};

// Every family the integrators' error bars are checked on: smooth,
// peaked, multi-peaked, oscillatory, corner-peaked, separable and
// discontinuous. 10⁴ points suffice for most; the peaks of width 0.02 and
// 0.05 in four dimensions take 10⁵ before an adaptive method's
// iterations agree.
inline std::vector<CalibrationFamily> CalibrationFamilies() {
  std::vector<CalibrationFamily> families;
  const auto add = [&](const char* name, auto f, uint64_t evaluations, std::vector<double> lower = {},
                       std::vector<double> upper = {}) {
    const double exact = f.Exact();
    const size_t d = f.InputDimensions();
    families.push_back({name, std::make_unique<decltype(f)>(std::move(f)), exact, evaluations,
                        lower.empty() ? Zeros(d) : lower, upper.empty() ? Ones(d) : upper});
  };
  constexpr uint64_t kSettled = 10000, kPeaked = 100000;
  add("polynomial d=3", Polynomial{}, kSettled, {0, 0, -1}, {1, 2, 1});
  add("product peak d=3", ProductPeak({10, 15, 8}, {0.3, 0.55, 0.8}), kSettled);
  add("gaussian peak d=3", GaussianPeaks({12, 10, 14}, {{0.4, 0.65, 0.3}}), kSettled);
  add("narrow peak d=4", NarrowPeak(), kPeaked);
  add("double peak d=4", DoublePeak(), kPeaked);
  add("oscillatory d=4", Oscillatory({1.5, 2.5, 0.5, 1.0}, 0.3), kSettled);
  add("corner peak d=3", CornerPeak({3.0, 2.0, 1.0}), kSettled);
  add("pair sum d=4", PairSum{}, kSettled);
  add("discontinuous d=3", Discontinuous({1.0, 2.0, 0.5}, 0.6, 0.35), kSettled);
  return families;
}

// How often, over seeded runs, |estimate − exact| < 2σ and Q < 0.05.
struct Calibration {
  int runs = 0, within_two_sigma = 0, q_below_5_percent = 0;
  double Within() const { return double(within_two_sigma) / runs; }
  double LowQ() const { return double(q_below_5_percent) / runs; }
};

// Runs `integrator` on `family` for seeds 0 … runs − 1.
inline Calibration Calibrate(Integrator& integrator, const Sampler& sampler, CalibrationFamily& family, int runs) {
  Calibration c;
  for (int seed = 0; seed < runs; ++seed) {
    const IntegrationResult r =
        integrator.Integrate(*family.f, family.lower, family.upper, family.evaluations, uint64_t(seed), sampler);
    ++c.runs;
    if (std::abs(r.estimate[0] - family.exact) < 2 * r.standard_error[0]) ++c.within_two_sigma;
    if (!r.q.empty() && r.q[0] < 0.05) ++c.q_below_5_percent;
  }
  return c;
}

}  // namespace yarf
