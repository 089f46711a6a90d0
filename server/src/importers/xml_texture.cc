// Textures and spectra of Mitsuba scenes: bitmaps and checkerboards become
// scene textures (Scene.textures) that properties refer to; a texture
// where yarf takes a constant, and a spectrum, become one RGB value.
#include <algorithm>
#include <cctype>
#include <sstream>

#include "importers/numbers.h"
#include "importers/properties_util.h"
#include "importers/texture_mean.h"
#include "importers/xml_importer.h"

namespace yarf::importers {
namespace {

std::vector<double> Numbers(const XmlElement& e, const std::string& text) {
  const auto values = ParseDoubleList(text);
  if (!values) Fail(e.where, "'" + text + "' is not a list of finite numbers");
  return *values;
}

// "400:0.1, 500:0.2" into increasing wavelengths and their values.
void ParsePairs(const XmlElement& e, const std::string& text, std::vector<double>& wavelengths,
                std::vector<double>& values) {
  std::string separated = text;
  std::replace(separated.begin(), separated.end(), ':', ' ');
  const std::vector<double> v = Numbers(e, separated);
  if (v.size() % 2 != 0 || v.empty()) Fail(e.where, "a spectrum needs wavelength:value pairs");
  for (size_t i = 0; i < v.size(); i += 2) {
    wavelengths.push_back(v[i]);
    values.push_back(v[i + 1]);
  }
}

void CheckWavelengths(const XmlElement& e, const std::vector<double>& wavelengths) {
  for (size_t i = 0; i < wavelengths.size(); ++i)
    if (!(wavelengths[i] > 0) || (i > 0 && !(wavelengths[i] > wavelengths[i - 1])))
      Fail(e.where, "spectrum wavelengths must be positive and increasing");
}

}  // namespace

Rgb MitsubaImporter::SpectrumValue(const XmlElement& e, bool within_emitter) {
  const RecursionGuard guard(nesting, e.where);
  const SpectrumUse use = within_emitter ? SpectrumUse::kEmission : SpectrumUse::kReflectance;
  std::vector<double> wavelengths, values;
  const std::string type = e.Get("type");
  if (type.empty()) {
    if (const std::string* file = e.Attribute("filename")) {
      // A text file of "wavelength value" lines; '#' starts a comment.
      const std::string text = ReadTextFile(folder_.Resolve(*file, e.file, e.where), e.where);
      std::istringstream lines(text);
      std::string line, numbers;
      while (std::getline(lines, line)) numbers += line.substr(0, line.find('#')) + " ";
      const std::vector<double> v = Numbers(e, numbers);
      if (v.size() % 2 != 0 || v.empty()) Fail(e.where, "spectrum file '" + *file + "' needs wavelength value pairs");
      for (size_t i = 0; i < v.size(); i += 2) wavelengths.push_back(v[i]), values.push_back(v[i + 1]);
    } else {
      const std::string& text = e.Required("value");
      if (text.find(':') == std::string::npos) {
        const std::vector<double> v = Numbers(e, text);
        if (v.size() != 1) Fail(e.where, "a spectrum value is one number or wavelength:value pairs");
        return UniformSpectrumToRgb(v[0], use);
      }
      ParsePairs(e, text, wavelengths, values);
    }
  } else {
    XmlPlugin plugin(e, *this);
    if (type == "uniform") {
      const double v = plugin.Float("value", 1);
      plugin.WarnUnused();
      return {v, v, v};
    }
    if (type == "srgb") {
      const Rgb c = plugin.Color("color", {1, 1, 1});
      plugin.WarnUnused();
      return c;
    }
    if (type == "blackbody") {
      const double kelvin = plugin.Float("temperature", 6504);
      if (!(kelvin > 0 && kelvin < 1e6)) Fail(e.where, "blackbody temperature out of range");
      Warn(e.where, "spectrum:blackbody",
           "blackbody spectrum: converted to the RGB colour of unit luminance (Mitsuba's RGB variants have none)");
      plugin.WarnUnused();
      return BlackbodyRgb(kelvin);
    }
    if (type == "regular") {
      const double lo = plugin.Float("wavelength_min", 360), hi = plugin.Float("wavelength_max", 830);
      const std::vector<double> v = Numbers(e, plugin.String("values", ""));
      if (v.size() < 2 || !(hi > lo)) Fail(e.where, "regular spectrum needs two or more values over a range");
      for (size_t i = 0; i < v.size(); ++i)
        wavelengths.push_back(lo + (hi - lo) * double(i) / double(v.size() - 1)), values.push_back(v[i]);
    } else if (type == "irregular") {
      wavelengths = Numbers(e, plugin.String("wavelengths", ""));
      values = Numbers(e, plugin.String("values", ""));
      if (wavelengths.size() != values.size() || wavelengths.empty())
        Fail(e.where, "irregular spectrum needs as many values as wavelengths");
    } else {
      Warn(e.where, "spectrum:" + type, "spectrum type '" + type + "' is not supported: grey 0.5 used");
      return {0.5, 0.5, 0.5};
    }
    plugin.WarnUnused();
  }
  CheckWavelengths(e, wavelengths);
  Rgb c = SpectrumToRgb(wavelengths, values, use);
  if (use == SpectrumUse::kReflectance) {
    // Reflectances stay in [0, 1], as Mitsuba clamps them.
    c = {std::clamp(c.r, 0.0, 1.0), std::clamp(c.g, 0.0, 1.0), std::clamp(c.b, 0.0, 1.0)};
  }
  return c;
}

std::string MitsubaImporter::TextureReference(const XmlElement& e) {
  if (const auto it = textures_.find(&e); it != textures_.end()) return it->second;
  const std::string type = e.Get("type");
  if (type != "bitmap" && type != "checkerboard" && type != "mesh_attribute") return "";
  const RecursionGuard guard(nesting, e.where);
  XmlPlugin plugin(e, *this);
  v1::Properties props;
  if (type == "bitmap") {
    const std::string name = plugin.String("filename", "");
    const auto file = folder_.Resolve(name, e.file, plugin.WhereIs("filename"));
    SetString(props, "filename", folder_.Relative(file));
    for (const char* key : {"filter_type", "wrap_mode"})
      if (plugin.Has(key)) SetString(props, key, plugin.String(key, ""));
    if (plugin.Has("raw")) SetBool(props, "raw", plugin.Boolean("raw", false));
    plugin.Accept({"format"});
  } else if (type == "mesh_attribute") {
    const std::string attribute = plugin.String("name", "");
    if (!attribute.starts_with("vertex_") && !attribute.starts_with("face_"))
      Fail(plugin.WhereIs("name"), "mesh_attribute: name must start with 'vertex_' or 'face_', got '" + attribute + "'");
    SetString(props, "name", attribute);
    if (plugin.Has("scale")) SetFloat(props, "scale", plugin.Float("scale", 1.0));
  } else {
    SetColour(props, "color0", plugin.TexturedColor("color0", {0.4, 0.4, 0.4}));
    SetColour(props, "color1", plugin.TexturedColor("color1", {0.2, 0.2, 0.2}));
  }
  if (plugin.Has("to_uv")) SetTransform(props, "to_uv", plugin.Transform("to_uv"));
  plugin.WarnUnused();
  const std::string name = assembly_.AddTexture(e.Get("id", type), Spec(type, std::move(props)));
  textures_[&e] = name;
  return name;
}

Rgb MitsubaImporter::TextureMean(const XmlElement& e) {
  const RecursionGuard guard(nesting, e.where);
  XmlPlugin plugin(e, *this);
  const std::string& type = plugin.type();
  plugin.Accept({"to_uv", "filter_type", "wrap_mode", "format"});
  Rgb mean{0.5, 0.5, 0.5};
  if (type == "bitmap") {
    const std::string name = plugin.String("filename", "");
    const auto file = folder_.Resolve(name, e.file, plugin.WhereIs("filename"));
    const bool raw = plugin.Boolean("raw", false);
    mean = ImageMeanColour(file, raw ? ImageEncoding::kLinear : ImageEncoding::kAuto, 1.0, e.where);
    Warn(e.where, "texture-constant:bitmap",
         "a bitmap texture where yarf takes a constant: replaced by its mean colour");
  } else if (type == "checkerboard") {
    const Rgb a = plugin.Color("color0", {0.4, 0.4, 0.4}), b = plugin.Color("color1", {0.2, 0.2, 0.2});
    mean = {(a.r + b.r) / 2, (a.g + b.g) / 2, (a.b + b.b) / 2};
    Warn(e.where, "texture-constant:checkerboard",
         "a checkerboard texture where yarf takes a constant: replaced by its mean colour");
  } else {
    Warn(e.where, "texture:" + type, "texture type '" + type + "' is not supported: grey 0.5 used");
    return mean;
  }
  plugin.WarnUnused();
  return mean;
}

}  // namespace yarf::importers
