// Spectra to RGB agree with Mitsuba 3's scalar_rgb conversions (reference
// values printed by Mitsuba 3.9 for the same spectra).
#include "importers/spectrum.h"

#include <gtest/gtest.h>

#include <vector>

namespace yarf::importers {
namespace {

void ExpectRgb(const Rgb& c, double r, double g, double b, double tolerance) {
  EXPECT_NEAR(c.r, r, tolerance);
  EXPECT_NEAR(c.g, g, tolerance);
  EXPECT_NEAR(c.b, b, tolerance);
}


const std::vector<double> kWavelengths = {400, 500, 600, 700};
const std::vector<double> kRed = {0.04, 0.06, 0.3, 0.64};

TEST(Spectrum, ReflectanceMatchesMitsuba) {
  ExpectRgb(SpectrumToRgb(kWavelengths, kRed, SpectrumUse::kReflectance), 0.427052, 0.153031, 0.0320103, 4e-3);
}

TEST(Spectrum, ConstantReflectanceIsGrey) {
  const std::vector<double> flat = {0.78, 0.78, 0.78, 0.78};
  ExpectRgb(SpectrumToRgb(kWavelengths, flat, SpectrumUse::kReflectance), 0.776367, 0.77981, 0.776029, 3e-3);
  ExpectRgb(UniformSpectrumToRgb(0.5, SpectrumUse::kReflectance), 0.5, 0.5, 0.5, 0);
}

TEST(Spectrum, EmissionMatchesMitsuba) {
  ExpectRgb(SpectrumToRgb(kWavelengths, kRed, SpectrumUse::kEmission), 0.492773, 0.145997, 0.0263853, 4e-3);
  // A uniform emission spectrum is the equal-energy white, pinkish in sRGB.
  ExpectRgb(UniformSpectrumToRgb(1, SpectrumUse::kEmission), 1.20479, 0.948291, 0.908916, 4e-3);
}

TEST(Spectrum, UnitLuminanceNormalisesAnySpectrum) {
  const Rgb c = SpectrumToRgb(kWavelengths, kRed, SpectrumUse::kUnitLuminance);
  EXPECT_NEAR(Luminance(c), 1.0, 2e-3);
}

TEST(Spectrum, BlackbodyHasUnitLuminanceAndItsColour) {
  const Rgb warm = BlackbodyRgb(2700), daylight = BlackbodyRgb(6504), cold = BlackbodyRgb(12000);
  for (const Rgb& c : {warm, daylight, cold}) EXPECT_NEAR(Luminance(c), 1.0, 2e-3);
  EXPECT_GT(warm.r, warm.b);
  EXPECT_GT(cold.b, cold.r);
  ExpectRgb(daylight, 1.0, 1.0, 1.0, 0.06);  // near the D65 white point
}

}  // namespace
}  // namespace yarf::importers
