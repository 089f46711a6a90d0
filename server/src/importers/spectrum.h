// Spectra to linear sRGB (Rec. 709 primaries), yarf's colour space:
// integrate against the CIE 1931 matching functions to XYZ, then convert.
#pragma once

#include <span>

namespace yarf::importers {

struct Rgb {
  double r = 0, g = 0, b = 0;
  Rgb operator*(double s) const { return {r * s, g * s, b * s}; }
};

// Luminance of a linear sRGB colour (Rec. 709 weights), as pbrt-v4 takes
// it to normalise lights by their power.
inline double Luminance(const Rgb& c) { return 0.212671 * c.r + 0.715160 * c.g + 0.072169 * c.b; }

// What a spectrum describes decides how it is normalised.
enum class SpectrumUse {
  // A reflectance: weighted by D65 and normalised so a constant 1 is white
  // (1, 1, 1), as Mitsuba's RGB variants convert reflectance spectra.
  kReflectance,
  // Radiance or intensity: XYZ per unit of Y's integral, so a constant 1
  // is the equal-energy white, as Mitsuba's RGB variants convert emission.
  kEmission,
  // Emission normalised to unit luminance (Y = 1): pbrt-v4 divides every
  // light's spectrum by its photometric value before applying "scale".
  kUnitLuminance,
};

// A piecewise-linear spectrum (wavelengths in nm, increasing), zero
// outside its wavelength range. Reflectances are not clamped here.
Rgb SpectrumToRgb(std::span<const double> wavelengths, std::span<const double> values, SpectrumUse use);

// A constant spectrum of value v.
Rgb UniformSpectrumToRgb(double v, SpectrumUse use);

// A blackbody at `kelvin`, normalised to unit luminance (pbrt-v4's
// max-normalised BlackbodySpectrum divided by its photometric value).
Rgb BlackbodyRgb(double kelvin);

Rgb XyzToLinearSrgb(double x, double y, double z);

}  // namespace yarf::importers
