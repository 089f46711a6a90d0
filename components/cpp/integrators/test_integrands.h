// Integrands with closed-form integrals that the integrator tests share:
// Genz's test families (oscillatory, corner peak, discontinuous) and a sum
// of smooth functions of two variables each.
#pragma once

#include <cmath>
#include <complex>
#include <cstdint>
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

}  // namespace yarf
