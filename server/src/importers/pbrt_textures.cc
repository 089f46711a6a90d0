// pbrt textures, reduced to their mean (yarf has no textures yet).
#include "importers/numbers.h"
#include "importers/pbrt_importer.h"
#include "importers/recursion_guard.h"
#include "importers/texture_mean.h"

namespace yarf::importers {

void PbrtImporter::Texture(const std::string& name, const std::string& type, const std::string& texture_class,
                           PbrtParams& params, const SourceLocation& where) {
  const RecursionGuard guard(nesting_, where);
  const bool spectral = type == "spectrum" || type == "color";
  if (!spectral && type != "float") Fail(where, "texture type must be \"spectrum\" or \"float\", not \"" + type + "\"");
  auto colour = [&](const std::string& key, double fallback) -> Rgb {
    if (spectral) return Colour(params, key, {fallback, fallback, fallback}, SpectrumUse::kReflectance, where);
    const double v = FloatOrTexture(params, key, fallback);
    return {v, v, v};
  };
  params.Accept({"mapping", "uscale", "vscale", "udelta", "vdelta", "v1", "v2", "filter", "maxanisotropy", "wrap"});
  Rgb mean{0.5, 0.5, 0.5};
  const std::string approximated = "yarf has no textures yet: " + texture_class + " textures replaced by their mean";
  if (texture_class == "constant") {
    mean = colour("value", 1);
  } else if (texture_class == "scale") {
    const Rgb t = colour("tex", 1);
    mean = t * FloatOrTexture(params, "scale", 1);
  } else if (texture_class == "mix" || texture_class == "directionmix") {
    const Rgb a = colour("tex1", 0), b = colour("tex2", 1);
    const double t = texture_class == "mix" ? FloatOrTexture(params, "amount", 0.5) : 0.5;
    if (texture_class == "directionmix") {
      params.Accept({"dir"});
      Warn(where, "texture:" + texture_class, approximated);
    }
    mean = {a.r + t * (b.r - a.r), a.g + t * (b.g - a.g), a.b + t * (b.b - a.b)};
  } else if (texture_class == "checkerboard") {
    const Rgb a = colour("tex1", 1), b = colour("tex2", 0);
    mean = {(a.r + b.r) / 2, (a.g + b.g) / 2, (a.b + b.b) / 2};
    params.Accept({"dimension"});
    Warn(where, "texture:checkerboard", approximated);
  } else if (texture_class == "imagemap") {
    const std::string filename = params.String("filename", "");
    const auto file = folder_.Resolve(filename, origin_.file, params.WhereIs("filename", where));
    const std::string encoding = params.String("encoding", "sRGB");
    ImageEncoding kind = ImageEncoding::kAuto;
    double gamma = 1;
    if (encoding == "linear") {
      kind = ImageEncoding::kLinear;
    } else if (encoding.rfind("gamma ", 0) == 0) {
      kind = ImageEncoding::kLinear;
      const auto g = ParseDouble(encoding.substr(6));
      if (!g || !(*g > 0 && *g < 100)) Fail(params.WhereIs("encoding", where), "bad gamma encoding '" + encoding + "'");
      gamma = *g;
    } else if (encoding != "sRGB") {
      Fail(params.WhereIs("encoding", where), "unknown encoding '" + encoding + "'");
    }
    mean = ImageMeanColour(file, kind, gamma, where) * params.Float("scale", 1);
    if (params.Bool("invert", false)) mean = {1 - mean.r, 1 - mean.g, 1 - mean.b};
    Warn(where, "texture:imagemap", approximated);
  } else {
    Warn(where, "texture:" + texture_class, "texture '" + texture_class + "' is not supported: grey 0.5 used");
  }
  if (texture_class == "constant" || texture_class == "scale" || texture_class == "mix" ||
      texture_class == "directionmix" || texture_class == "checkerboard" || texture_class == "imagemap")
    params.WarnUnused(diagnostics_, "texture '" + texture_class + "'");
  if (spectral)
    spectrum_textures_[name] = mean;
  else
    float_textures_[name] = (mean.r + mean.g + mean.b) / 3;
}

}  // namespace yarf::importers
