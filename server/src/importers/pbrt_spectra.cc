// Spectrum-valued and float parameters of pbrt directives: rgb, spectrum
// (pairs, a named spectrum or a file), blackbody, float, and textures.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "importers/numbers.h"
#include "importers/pbrt_importer.h"
#include "importers/spectrum_tables.h"

namespace yarf::importers {
namespace {

// The D65 illuminant, tabulated.
std::vector<double> D65(std::vector<double>& wavelengths) {
  std::vector<double> values;
  for (const CieSample& s : kCie1931) wavelengths.push_back(s.wavelength), values.push_back(s.d65);
  return values;
}

}  // namespace

Rgb PbrtImporter::Colour(PbrtParams& params, const std::string& name, Rgb fallback, SpectrumUse use,
                         const SourceLocation& where) {
  const PbrtParam* p = params.Find(name);
  if (!p) return fallback;
  const bool light = use != SpectrumUse::kReflectance;
  if (p->type == "rgb") {
    if (p->numbers.size() != 3) Fail(p->where, "rgb parameter '" + name + "' needs 3 values");
    return {p->numbers[0], p->numbers[1], p->numbers[2]};
  }
  if (p->type == "float") {
    if (p->numbers.size() != 1) Fail(p->where, "parameter '" + name + "' needs one value");
    return {p->numbers[0], p->numbers[0], p->numbers[0]};
  }
  if (p->type == "texture") {
    const std::string texture = params.String(name, "");
    const auto it = spectrum_textures_.find(texture);
    if (it == spectrum_textures_.end()) Fail(p->where, "texture '" + texture + "' is not defined");
    if (it->second.IsTexture())
      Warn(p->where, "texture-constant:" + name,
           "texture '" + texture + "' where yarf takes a constant (" + name + "): replaced by its mean");
    return it->second.constant;
  }
  if (p->type == "blackbody") {
    if (p->numbers.empty() || p->numbers.size() > 2) Fail(p->where, "blackbody needs a temperature");
    const double kelvin = p->numbers[0];
    if (!(kelvin > 0 && kelvin < 1e6)) Fail(p->where, "blackbody temperature out of range");
    Warn(p->where, "blackbody", "blackbody spectra converted to RGB (the colour of unit luminance)");
    const double scale = p->numbers.size() == 2 ? p->numbers[1] : 1.0;  // pbrt-v3's second value
    if (light) return BlackbodyRgb(kelvin) * scale;
    // As a reflectance: the spectrum normalised to a maximum of 1.
    std::vector<double> wavelengths, values;
    for (double lambda = kCieMinWavelength; lambda <= kCieMaxWavelength; lambda += 5) {
      const double l = lambda * 1e-9;
      wavelengths.push_back(lambda);
      values.push_back(1 / (std::pow(l, 5) * (std::exp(0.0143877735 / (l * kelvin)) - 1)));
    }
    const double peak = *std::max_element(values.begin(), values.end());
    for (double& v : values) v = peak > 0 && std::isfinite(peak) ? v / peak : 0;
    return SpectrumToRgb(wavelengths, values, use);
  }
  if (p->type != "spectrum") Fail(p->where, "parameter '" + name + "' has type " + p->type + ", expected a spectrum");

  std::vector<double> wavelengths, values;
  if (p->strings.size() == 1) {
    const std::string& named = p->strings[0];
    if (named == "stdillum-D65") {
      values = D65(wavelengths);
    } else if (named == "stdillum-A") {
      return light ? BlackbodyRgb(2856) : Rgb{1, 1, 1};
    } else if (named.rfind("stdillum-", 0) == 0 || named.rfind("illum-", 0) == 0 || named.rfind("metal-", 0) == 0 ||
               named.rfind("glass-", 0) == 0 || named.rfind("canon_", 0) == 0 || named.rfind("nikon_", 0) == 0 ||
               named.rfind("sony_", 0) == 0) {
      Warn(p->where, "named-spectrum:" + named, "named spectrum '" + named + "' is not tabulated here: white used");
      return {1, 1, 1};
    } else {
      // A file of wavelength-value pairs.
      const auto file = folder_.Resolve(named, origin_.file, p->where);
      std::istringstream lines(ReadTextFile(file, p->where));
      std::string line, numbers;
      while (std::getline(lines, line)) numbers += line.substr(0, line.find('#')) + " ";
      const auto v = ParseDoubleList(numbers);
      if (!v || v->size() % 2 != 0 || v->empty()) Fail(p->where, "spectrum file '" + named + "' needs wavelength value pairs");
      for (size_t i = 0; i < v->size(); i += 2) wavelengths.push_back((*v)[i]), values.push_back((*v)[i + 1]);
    }
  } else if (!p->strings.empty()) {
    Fail(p->where, "spectrum parameter '" + name + "' needs one name or wavelength value pairs");
  } else {
    if (p->numbers.size() % 2 != 0 || p->numbers.empty())
      Fail(p->where, "spectrum parameter '" + name + "' needs wavelength value pairs");
    for (size_t i = 0; i < p->numbers.size(); i += 2)
      wavelengths.push_back(p->numbers[i]), values.push_back(p->numbers[i + 1]);
  }
  for (size_t i = 0; i < wavelengths.size(); ++i)
    if (!(wavelengths[i] > 0) || (i > 0 && !(wavelengths[i] > wavelengths[i - 1])))
      Fail(p->where, "spectrum wavelengths must be positive and increasing");
  Warn(p->where, "spectrum-rgb", "spectra converted to RGB (yarf renders in RGB)");
  return SpectrumToRgb(wavelengths, values, use);
}

double PbrtImporter::FloatOrTexture(PbrtParams& params, const std::string& name, double fallback) {
  const PbrtParam* p = params.Find(name);
  if (!p) return fallback;
  if (p->type == "texture") {
    const std::string texture = params.String(name, "");
    const auto it = float_textures_.find(texture);
    if (it == float_textures_.end()) Fail(p->where, "float texture '" + texture + "' is not defined");
    if (it->second.IsTexture())
      Warn(p->where, "texture-constant:" + name,
           "texture '" + texture + "' where yarf takes a constant (" + name + "): replaced by its mean");
    return it->second.constant.r;
  }
  return params.Float(name, fallback);
}

Textured PbrtImporter::TexturedColour(PbrtParams& params, const std::string& name, Rgb fallback, SpectrumUse use,
                                      const SourceLocation& where) {
  const PbrtParam* p = params.Find(name);
  if (p && p->type == "texture") {
    const std::string texture = params.String(name, "");
    const auto it = spectrum_textures_.find(texture);
    if (it == spectrum_textures_.end()) Fail(p->where, "texture '" + texture + "' is not defined");
    return it->second;
  }
  return {Colour(params, name, fallback, use, where), ""};
}

Textured PbrtImporter::TexturedFloat(PbrtParams& params, const std::string& name, double fallback) {
  const PbrtParam* p = params.Find(name);
  if (p && p->type == "texture") {
    const std::string texture = params.String(name, "");
    const auto it = float_textures_.find(texture);
    if (it == float_textures_.end()) Fail(p->where, "float texture '" + texture + "' is not defined");
    return it->second;
  }
  return Textured::Grey(params.Float(name, fallback));
}

}  // namespace yarf::importers
