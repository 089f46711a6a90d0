// Tabulated colour science data for spectrum-to-RGB conversion.
#pragma once

#include <array>

namespace yarf::importers {

struct CieSample {
  double wavelength;  // nm
  double x, y, z;     // CIE 1931 2° colour matching functions
  double d65;         // the D65 illuminant, relative
};

constexpr int kCieSampleCount = 95;
constexpr double kCieMinWavelength = 360, kCieMaxWavelength = 830, kCieStep = 5;
extern const std::array<CieSample, kCieSampleCount> kCie1931;

}  // namespace yarf::importers
