// control_variate — Monte Carlo with a fitted control variate, after
// Lafortune & Willems ("The ambient term as a variance reducing technique
// for Monte Carlo ray tracing"): an approximation g of f whose integral is
// known exactly is subtracted, and only the residual f − g is sampled:
//   ∫ f = ∫ g + ∫ (f − g) ≈ ∫ g + V · (1/n) Σ (f(x_i) − g(x_i)).
// The variance is that of the residual, small wherever g follows f.
//
// g is a Function of its own (`LegendreFit`): a least-squares fit of f, on
// a pilot sample, in the tensor Legendre polynomials of total degree ≤ D
// on the box. They are orthonormal over it, so every one but the constant
// integrates to zero and ∫ g = V · c₀. Lafortune's constant "ambient term"
// is the case D = 0; a rendering user supplies the shape of g by the
// degree, a numerical one gets a smooth approximation without writing it.
//
// Integrate: the first P = min(⌊pilot_fraction · N⌋, 20000) points of the
// sampler's sequence fit g; D is the largest degree ≤ "degree" whose K
// basis functions number at most min(P / 10, 256), so that the fit does
// not chase noise. The other N − P points, independent of the pilot, give
// the residual's mean and its standard error V · s / √(N − P). The pilot
// only shapes g and is not in the estimate, so the estimate is unbiased
// and its error bar honest; it counts in `evaluations`, the full budget.
// Each output of f gets its own fit (one shared normal matrix).
//
// Parameters: ControlVariateIntegrator::Parameters() below.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "integration_box.h"
#include "yarf/plugin.h"

namespace yarf {
namespace {

// Points per Evaluate call: large, since f may live in another process.
constexpr uint64_t kBatch = 8192;
constexpr uint64_t kMaxPilot = 20000;
constexpr uint64_t kMaxBasis = 256;
constexpr uint64_t kPilotPointsPerBasisFunction = 10;
constexpr int kMaxDegree = 8;

// Orthonormal shifted Legendre polynomials on [0, 1], degrees 0 … n − 1,
// at u, by Bonnet's recurrence: ∫₀¹ p_i p_j = δ_ij.
void Legendre(double u, int n, double* out) {
  const double t = 2 * u - 1;
  double previous = 1, current = t;
  out[0] = 1;
  if (n > 1) out[1] = std::sqrt(3.0) * t;
  for (int m = 1; m + 1 < n; ++m) {
    const double next = ((2 * m + 1) * t * current - m * previous) / (m + 1);
    previous = current;
    current = next;
    out[m + 1] = std::sqrt(2.0 * (m + 1) + 1) * next;
  }
}

// Every multi-index of d non-negative degrees with total ≤ degree, the
// zero index first.
std::vector<std::vector<uint8_t>> MultiIndices(uint32_t d, int degree) {
  std::vector<std::vector<uint8_t>> out;
  std::vector<uint8_t> index(d, 0);
  const auto recurse = [&](auto& self, uint32_t axis, int left) -> void {
    if (axis == d) {
      out.push_back(index);
      return;
    }
    for (int e = 0; e <= left; ++e) {
      index[axis] = uint8_t(e);
      self(self, axis + 1, left - e);
    }
    index[axis] = 0;
  };
  recurse(recurse, 0, degree);
  return out;
}

// C(d + degree, degree), the size of that basis, or limit + 1 past limit.
uint64_t BasisSize(uint32_t d, int degree, uint64_t limit) {
  double size = 1;
  for (int i = 1; i <= degree; ++i) size = size * double(d + uint32_t(i)) / double(i);
  return size > double(limit) ? limit + 1 : uint64_t(std::llround(size));
}

// Solves A x = b for each of the columns of b (K × k, row-major) with A
// (K × K, symmetric positive semi-definite) by Cholesky, after a ridge of
// 1e-10 of A's mean diagonal keeps it definite.
void SolveNormalEquations(std::vector<double> a, std::vector<double>& b, size_t size, size_t columns) {
  double trace = 0;
  for (size_t i = 0; i < size; ++i) trace += a[i * size + i];
  const double ridge = 1e-10 * std::max(trace / double(size), 1e-300);
  for (size_t i = 0; i < size; ++i) a[i * size + i] += ridge;
  for (size_t j = 0; j < size; ++j) {
    double diagonal = a[j * size + j];
    for (size_t p = 0; p < j; ++p) diagonal -= a[j * size + p] * a[j * size + p];
    const double root = std::sqrt(std::max(diagonal, ridge));
    a[j * size + j] = root;
    for (size_t i = j + 1; i < size; ++i) {
      double s = a[i * size + j];
      for (size_t p = 0; p < j; ++p) s -= a[i * size + p] * a[j * size + p];
      a[i * size + j] = s / root;
    }
  }
  for (size_t c = 0; c < columns; ++c) {
    for (size_t i = 0; i < size; ++i) {  // L y = b
      double s = b[i * columns + c];
      for (size_t p = 0; p < i; ++p) s -= a[i * size + p] * b[p * columns + c];
      b[i * columns + c] = s / a[i * size + i];
    }
    for (size_t i = size; i-- > 0;) {  // Lᵀ x = y
      double s = b[i * columns + c];
      for (size_t p = i + 1; p < size; ++p) s -= a[p * size + i] * b[p * columns + c];
      b[i * columns + c] = s / a[i * size + i];
    }
  }
}

// g: a combination of the box's orthonormal tensor Legendre polynomials,
// one set of coefficients per output of f. ∫ g over the box = V · c₀.
class LegendreFit final : public Function {
 public:
  LegendreFit(std::span<const double> lower, std::span<const double> upper, uint32_t outputs, int degree)
      : lower_(lower.begin(), lower.end()),
        upper_(upper.begin(), upper.end()),
        outputs_(outputs),
        degree_(degree),
        indices_(MultiIndices(uint32_t(lower.size()), degree)),
        coefficients_(indices_.size() * outputs, 0.0) {}

  uint32_t InputDimensions() const override { return uint32_t(lower_.size()); }
  uint32_t OutputDimensions() const override { return outputs_; }
  size_t BasisSize() const { return indices_.size(); }

  // The basis at a point of the box: K values.
  void Basis(const float* x, std::vector<double>& table, std::vector<double>& out) const {
    const size_t d = lower_.size(), n = size_t(degree_) + 1;
    table.resize(d * n);
    for (size_t j = 0; j < d; ++j) {
      const double width = upper_[j] - lower_[j];
      const double u = width > 0 ? (double(x[j]) - lower_[j]) / width : 0.5;
      Legendre(u, int(n), &table[j * n]);
    }
    out.resize(indices_.size());
    for (size_t b = 0; b < indices_.size(); ++b) {
      double value = 1;
      for (size_t j = 0; j < d; ++j)
        if (indices_[b][j] != 0) value *= table[j * n + indices_[b][j]];
      out[b] = value;
    }
  }

  // Least squares on the points and values of f.
  void Fit(std::span<const float> points, std::span<const float> values) {
    const size_t size = indices_.size(), d = lower_.size(), count = points.size() / d;
    std::vector<double> normal(size * size, 0.0), rhs(size * outputs_, 0.0), table, phi;
    for (size_t i = 0; i < count; ++i) {
      Basis(&points[i * d], table, phi);
      for (size_t r = 0; r < size; ++r) {
        for (size_t s = 0; s <= r; ++s) normal[r * size + s] += phi[r] * phi[s];
        for (uint32_t c = 0; c < outputs_; ++c) rhs[r * outputs_ + c] += phi[r] * values[i * outputs_ + c];
      }
    }
    for (size_t r = 0; r < size; ++r)
      for (size_t s = 0; s < r; ++s) normal[s * size + r] = normal[r * size + s];
    SolveNormalEquations(std::move(normal), rhs, size, outputs_);
    coefficients_ = std::move(rhs);
  }

  void Evaluate(std::span<const float> points, std::span<float> values) override {
    const size_t d = lower_.size(), count = points.size() / d;
    std::vector<double> table, phi;
    for (size_t i = 0; i < count; ++i) At(&points[i * d], &values[i * outputs_], table, phi);
  }

  // ∫ g over the box, output c.
  double Integral(uint32_t c, double volume) const { return volume * coefficients_[c]; }

  // g at one point x of the box; table and phi are scratch space.
  void At(const float* x, float* out, std::vector<double>& table, std::vector<double>& phi) const {
    Basis(x, table, phi);
    for (uint32_t c = 0; c < outputs_; ++c) {
      double v = 0;
      for (size_t b = 0; b < phi.size(); ++b) v += coefficients_[b * outputs_ + c] * phi[b];
      out[c] = float(v);
    }
  }

 private:
  std::vector<double> lower_, upper_;
  uint32_t outputs_;
  int degree_;
  std::vector<std::vector<uint8_t>> indices_;
  std::vector<double> coefficients_;  // K × outputs, row-major
};

class ControlVariateIntegrator final : public Integrator {
 public:
  static ParameterSchema Parameters() {
    using P = Parameter;
    return {
        P::Int("degree").Default(4).Range(0, kMaxDegree).Doc("most total degree D of the Legendre fit"),
        P::Float("pilot_fraction").Default(0.2).Range(0, 1).Doc("share of the budget that fits g, in (0, 1)"),
    };
  }

  explicit ControlVariateIntegrator(const Properties& props)
      : degree_(props.Int("degree", 4)), pilot_fraction_(props.Float("pilot_fraction", 0.2)) {
    if (degree_ < 0 || degree_ > kMaxDegree)
      throw Error("property 'degree' must be in [0, " + std::to_string(kMaxDegree) + "]");
    if (!(pilot_fraction_ > 0 && pilot_fraction_ < 1)) throw Error("property 'pilot_fraction' must be in (0, 1)");
  }

  IntegrationResult Integrate(Function& f, std::span<const double> lower, std::span<const double> upper,
                              uint64_t evaluations, uint64_t seed, const Sampler& sampler) override {
    const uint32_t d = f.InputDimensions(), k = f.OutputDimensions();
    CheckProperBox(lower, upper, d);
    const uint64_t pilot = std::min(kMaxPilot, uint64_t(pilot_fraction_ * double(evaluations)));
    if (pilot < 1 || evaluations - pilot < 2)
      throw Error("control_variate needs a pilot point and two more; raise the evaluations");

    int degree = degree_;
    const uint64_t basis_limit = std::min(kMaxBasis, pilot / kPilotPointsPerBasisFunction);
    while (degree > 0 && BasisSize(d, degree, basis_limit) > basis_limit) --degree;
    LegendreFit g(lower, upper, k, degree);

    std::vector<float> points, values;
    const auto draw = [&](uint64_t first, uint64_t count) {
      points.resize(count * d);
      values.resize(count * k);
      sampler.Generate(first, uint32_t(count), d, seed, points);
      MapToBox(points, lower, upper);
    };
    {
      std::vector<float> pilot_points, pilot_values;
      for (uint64_t first = 0; first < pilot; first += kBatch) {
        draw(first, std::min(kBatch, pilot - first));
        f.Evaluate(points, values);
        pilot_points.insert(pilot_points.end(), points.begin(), points.end());
        pilot_values.insert(pilot_values.end(), values.begin(), values.end());
      }
      g.Fit(pilot_points, pilot_values);
    }

    RunningMoments residual(k);
    std::vector<float> approximation, difference(k);
    for (uint64_t first = pilot; first < evaluations; first += kBatch) {
      draw(first, std::min(kBatch, evaluations - first));
      f.Evaluate(points, values);
      approximation.resize(values.size());
      g.Evaluate(points, approximation);
      for (size_t i = 0; i < values.size() / k; ++i) {
        for (uint32_t c = 0; c < k; ++c) difference[c] = values[i * k + c] - approximation[i * k + c];
        residual.Add(difference.data());
      }
    }

    const double volume = BoxVolume(lower, upper);
    IntegrationResult result;
    result.evaluations = evaluations;
    for (uint32_t c = 0; c < k; ++c) {
      result.estimate.push_back(g.Integral(c, volume) + volume * residual.Mean(c));
      result.standard_error.push_back(volume * std::sqrt(residual.VarianceOfMean(c)));
    }
    return result;
  }

 private:
  int64_t degree_;
  double pilot_fraction_;
};

}  // namespace
}  // namespace yarf

YARF_PLUGIN(registrar) {
  yarf::Register<yarf::ControlVariateIntegrator>(
      registrar, "control_variate", "1.0.0",
      "Monte Carlo on the residual of a fitted Legendre control variate (Lafortune & Willems)");
}
