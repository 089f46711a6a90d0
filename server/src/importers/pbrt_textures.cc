// pbrt textures as scene textures (Scene.textures): imagemap, checkerboard
// (of 2 or 3 dimensions), scale, mix, constant, bilerp, dots and the solid
// noise textures (fbm, wrinkled, windy, marble). Each also keeps its mean,
// for the parameters yarf takes as constants; a class yarf has none for is
// its mean alone.
#include <cmath>
#include <optional>

#include "importers/numbers.h"
#include "importers/pbrt_importer.h"
#include "importers/recursion_guard.h"
#include "importers/texture_mean.h"

namespace yarf::importers {
namespace {

Rgb Lerp(double t, const Rgb& a, const Rgb& b) {
  return {a.r + t * (b.r - a.r), a.g + t * (b.g - a.g), a.b + t * (b.b - a.b)};
}

}  // namespace

void PbrtImporter::Texture(const std::string& name, const std::string& type, const std::string& texture_class,
                           PbrtParams& params, const SourceLocation& where) {
  const RecursionGuard guard(nesting_, where);
  const bool spectral = type == "spectrum" || type == "color";
  if (!spectral && type != "float") Fail(where, "texture type must be \"spectrum\" or \"float\", not \"" + type + "\"");
  // A parameter that may itself be a texture of the texture's own type.
  auto input = [&](const std::string& key, double fallback) -> Textured {
    if (spectral) return TexturedColour(params, key, {fallback, fallback, fallback}, SpectrumUse::kReflectance, where);
    return TexturedFloat(params, key, fallback);
  };
  v1::Properties props;
  auto set = [&](const std::string& key, const Textured& value) {
    spectral ? SetColour(props, key, value) : SetFloatOrTexture(props, key, value);
  };
  // pbrt's (u, v) mapping, u' = u·uscale + udelta (likewise v). An image
  // texture then takes v' → 1 − v' (pbrt's images have v = 0 at their
  // bottom row, yarf's at the top): the whole map as a to_uv transform.
  // The checkerboard takes the scales as they are.
  auto map_uv = [&](bool image) {
    const std::string mapping = params.String("mapping", "uv");
    if (mapping != "uv")
      Warn(params.WhereIs("mapping", where), "texture-mapping:" + mapping,
           "texture mapping '" + mapping + "' is not supported: uv mapping used");
    const double us = params.Float("uscale", 1), vs = params.Float("vscale", 1);
    const double ud = params.Float("udelta", 0), vd = params.Float("vdelta", 0);
    params.Accept({"v1", "v2"});
    if (!image) {
      SetFloat(props, "uscale", us), SetFloat(props, "vscale", vs);
      SetFloat(props, "udelta", ud), SetFloat(props, "vdelta", vd);
      return;
    }
    SetTransform(props, "to_uv", Matrix4({us, 0, 0, ud, 0, -vs, 0, 1 - vd, 0, 0, 1, 0, 0, 0, 0, 1}));
  };

  Rgb mean{0.5, 0.5, 0.5};
  std::string yarf_class = texture_class;
  // A solid texture's space: the CTM at the Texture directive.
  std::optional<Matrix4> texture_to_world;
  auto place_in_space = [&] {
    if (!state_.ctm.Inverse()) Fail(where, "the texture's transform is singular");
    texture_to_world = state_.ctm;
    const std::string mapping = params.String("mapping", "point");
    if (mapping != "point")
      Fail(params.WhereIs("mapping", where), "a solid texture's mapping must be \"point\", not \"" + mapping + "\"");
  };
  const bool solid_checkerboard = texture_class == "checkerboard" && params.Float("dimension", 2) == 3;
  if (texture_class == "checkerboard" && !solid_checkerboard && params.Float("dimension", 2) != 2)
    Fail(params.WhereIs("dimension", where), "checkerboard: dimension must be 2 or 3");
  if (texture_class == "fbm" || texture_class == "wrinkled" || texture_class == "windy" ||
      texture_class == "marble") {
    if (texture_class == "marble" && !spectral) Fail(where, "pbrt's marble is a spectrum texture");
    if (texture_class != "marble" && spectral) Fail(where, "pbrt's " + texture_class + " is a float texture");
    place_in_space();
    // What the mean stands in for (light power, constants): fbm and windy
    // swing about 0, marble about its greys; wrinkled's turbulence is about
    // its octaves' weights times 0.2, pbrt's own stand-in for |noise|.
    mean = texture_class == "marble" ? Rgb{0.58, 0.58, 0.6} : Rgb{0, 0, 0};
    if (texture_class != "windy") {
      const int64_t octaves = params.Integer("octaves", 8);
      if (octaves < 1 || octaves > 64) Fail(params.WhereIs("octaves", where), "octaves must lie in [1, 64]");
      const double roughness = params.Float("roughness", 0.5);
      if (!(roughness >= 0 && roughness <= 1))
        Fail(params.WhereIs("roughness", where), "roughness must lie in [0, 1]");
      SetInt(props, "octaves", octaves);
      SetFloat(props, "roughness", roughness);
      double weights = 0;
      for (int64_t i = 0; i <= octaves; ++i) weights += std::pow(roughness, double(i));
      if (texture_class == "wrinkled") mean = Rgb{0.2 * weights, 0.2 * weights, 0.2 * weights};
    }
    if (texture_class == "marble") {
      SetFloat(props, "scale", params.Float("scale", 1));
      SetFloat(props, "variation", params.Float("variation", 0.2));
    }
  } else if (solid_checkerboard) {
    yarf_class = "checkerboard3d";
    const Textured a = input("tex1", 1), b = input("tex2", 0);
    mean = Lerp(0.5, a.constant, b.constant);
    set("tex1", a);
    set("tex2", b);
    place_in_space();
  } else if (texture_class == "bilerp") {
    const Rgb v00 = input("v00", 0).constant, v10 = input("v10", 0).constant;
    const Rgb v01 = input("v01", 1).constant, v11 = input("v11", 1).constant;
    mean = Lerp(0.5, Lerp(0.5, v00, v10), Lerp(0.5, v01, v11));
    for (const auto& [key, value] : {std::pair{"v00", v00}, {"v10", v10}, {"v01", v01}, {"v11", v11}})
      SetRgb(props, key, value);
    map_uv(false);
  } else if (texture_class == "dots") {
    const Textured inside = input("inside", 1), outside = input("outside", 0);
    // A stand-in: the dots cover about a fifth of the plane.
    mean = Lerp(0.2, outside.constant, inside.constant);
    set("inside", inside);
    set("outside", outside);
    map_uv(false);
  } else if (texture_class == "constant") {
    yarf_class = "constant_texture";  // "constant" is the constant environment
    const Textured value = input("value", 1);
    mean = value.constant;
    set("value", value);
  } else if (texture_class == "scale") {
    const Textured tex = input("tex", 1);
    const Textured scale = TexturedFloat(params, "scale", 1);
    mean = tex.constant * scale.constant.r;
    set("tex", tex);
    SetFloatOrTexture(props, "scale", scale);
  } else if (texture_class == "mix") {
    const Textured a = input("tex1", 0), b = input("tex2", 1);
    const Textured amount = TexturedFloat(params, "amount", 0.5);
    mean = Lerp(amount.constant.r, a.constant, b.constant);
    set("tex1", a);
    set("tex2", b);
    SetFloatOrTexture(props, "amount", amount);
  } else if (texture_class == "checkerboard") {
    const Textured a = input("tex1", 1), b = input("tex2", 0);
    mean = Lerp(0.5, a.constant, b.constant);
    set("tex1", a);
    set("tex2", b);
    map_uv(false);
  } else if (texture_class == "imagemap") {
    yarf_class = "bitmap";
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
    const double scale = params.Float("scale", 1);
    const bool invert = params.Bool("invert", false);
    mean = ImageMeanColour(file, kind, gamma, where) * scale;
    if (invert) mean = {1 - mean.r, 1 - mean.g, 1 - mean.b};
    SetString(props, "filename", folder_.Relative(file));
    SetString(props, "encoding", encoding);
    if (scale != 1) SetFloat(props, "scale", scale);
    if (invert) SetBool(props, "invert", true);
    for (const char* key : {"filter", "wrap"})
      if (params.Has(key)) SetString(props, key, params.String(key, ""));
    params.Accept({"maxanisotropy"});
    map_uv(true);
  } else {
    Warn(where, "texture:" + texture_class,
         "texture '" + texture_class + "' is not supported: replaced by its mean (grey 0.5)");
    yarf_class.clear();
  }
  params.WarnUnused(diagnostics_, "texture '" + texture_class + "'");
  const double grey = (mean.r + mean.g + mean.b) / 3;
  Textured result{spectral ? mean : Rgb{grey, grey, grey}, ""};
  if (!yarf_class.empty())
    result.texture = assembly_.AddTexture(name, Spec(yarf_class, std::move(props)), texture_to_world);
  (spectral ? spectrum_textures_ : float_textures_)[name] = result;
}

}  // namespace yarf::importers
