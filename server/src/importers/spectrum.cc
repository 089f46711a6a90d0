#include "importers/spectrum.h"

#include <algorithm>
#include <cmath>
#include <functional>

#include "importers/spectrum_tables.h"

namespace yarf::importers {
namespace {

struct Xyz {
  double x = 0, y = 0, z = 0;
};

// The tabulated CIE data linearly interpolated at `lambda` (nm).
CieSample CieAt(double lambda) {
  const double t = (lambda - kCieMinWavelength) / kCieStep;
  const int i = std::clamp(int(t), 0, kCieSampleCount - 2);
  const double f = std::clamp(t - i, 0.0, 1.0);
  const CieSample& a = kCie1931[i];
  const CieSample& b = kCie1931[i + 1];
  auto lerp = [f](double u, double v) { return u + f * (v - u); };
  return {lambda, lerp(a.x, b.x), lerp(a.y, b.y), lerp(a.z, b.z), lerp(a.d65, b.d65)};
}

// XYZ of a spectrum over 360–830 nm in 1 nm steps, and the Y of the
// normalising reference (white for reflectances, ∫ȳ for emission).
std::pair<Xyz, double> Integrate(const std::function<double(double)>& spectrum, bool d65) {
  Xyz xyz;
  double white_y = 0;
  for (double lambda = kCieMinWavelength; lambda <= kCieMaxWavelength; lambda += 1) {
    const CieSample c = CieAt(lambda);
    const double w = d65 ? c.d65 : 1.0;
    const double s = spectrum(lambda) * w;
    xyz.x += c.x * s;
    xyz.y += c.y * s;
    xyz.z += c.z * s;
    white_y += c.y * w;
  }
  return {xyz, white_y};
}

Rgb Convert(const std::function<double(double)>& spectrum, SpectrumUse use) {
  const auto [xyz, white_y] = Integrate(spectrum, use == SpectrumUse::kReflectance);
  double scale = 1 / white_y;
  if (use == SpectrumUse::kUnitLuminance) scale = xyz.y > 0 ? 1 / xyz.y : 0;
  return XyzToLinearSrgb(xyz.x * scale, xyz.y * scale, xyz.z * scale);
}

}  // namespace

Rgb XyzToLinearSrgb(double x, double y, double z) {
  return {3.240479 * x - 1.537150 * y - 0.498535 * z, -0.969256 * x + 1.875991 * y + 0.041556 * z,
          0.055648 * x - 0.204043 * y + 1.057311 * z};
}

Rgb SpectrumToRgb(std::span<const double> wavelengths, std::span<const double> values, SpectrumUse use) {
  const size_t n = std::min(wavelengths.size(), values.size());
  if (n == 0) return {};
  auto spectrum = [&](double lambda) -> double {
    if (n == 1) return lambda == wavelengths[0] ? values[0] : 0.0;
    if (lambda < wavelengths[0] || lambda > wavelengths[n - 1]) return 0;
    const size_t i = std::upper_bound(wavelengths.begin(), wavelengths.begin() + n, lambda) -
                     wavelengths.begin();
    if (i >= n) return values[n - 1];
    const double width = wavelengths[i] - wavelengths[i - 1];
    if (!(width > 0)) return values[i];
    const double t = (lambda - wavelengths[i - 1]) / width;
    return values[i - 1] + t * (values[i] - values[i - 1]);
  };
  return Convert(spectrum, use);
}

Rgb UniformSpectrumToRgb(double v, SpectrumUse use) {
  if (use == SpectrumUse::kReflectance) return {v, v, v};
  return Convert([v](double) { return v; }, use);
}

Rgb BlackbodyRgb(double kelvin) {
  if (!(kelvin > 0)) return {};
  constexpr double c = 299792458, h = 6.62606957e-34, kb = 1.3806488e-23;
  auto planck = [&](double lambda_nm) {
    const double l = lambda_nm * 1e-9;
    return (2 * h * c * c) / (std::pow(l, 5) * (std::exp((h * c) / (l * kb * kelvin)) - 1));
  };
  return Convert(planck, SpectrumUse::kUnitLuminance);
}

}  // namespace yarf::importers
