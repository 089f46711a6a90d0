// Mitsuba BSDFs as yarf SurfaceModel classes.
#include <algorithm>

#include "importers/colour_checks.h"
#include "importers/properties_util.h"
#include "importers/xml_importer.h"
#include "yarf/support/named_metals.h"

namespace yarf::importers {
namespace {

constexpr double kBk7 = 1.5046, kAir = 1.000277, kPolypropylene = 1.49;

}  // namespace

// The metals yarf's conductors tabulate (components/cpp/bsdfs/metals.h);
// others become a perfect mirror, with a warning.
std::string MitsubaImporter::KnownMetal(const std::string& name, const SourceLocation& where) {
  if (name == "none" || metals::IsNamed(name)) return name;
  Warn(where, "metal:" + name, "metal '" + name + "' is not among Mitsuba's named metals: a perfect mirror used");
  return "none";
}

std::string MitsubaImporter::Material(const XmlElement& element) {
  const auto it = materials_.find(&element);
  if (it != materials_.end()) return it->second;
  const std::string name = MakeMaterial(element, element.Get("id", element.Get("type", "bsdf")));
  materials_[&element] = name;
  return name;
}

std::string MitsubaImporter::MaskAlpha(const XmlElement& bsdf) {
  if (bsdf.Get("type") != "mask") return "";
  if (const auto it = textures_.find(&bsdf); it != textures_.end()) return it->second;
  XmlPlugin p(bsdf, *this);
  const Textured opacity = p.TexturedColor("opacity", {0.5, 0.5, 0.5});
  std::string alpha = opacity.texture;
  if (!opacity.IsTexture() && opacity.constant.r < 1) {
    v1::Properties props;
    SetFloat(props, "value", std::max(0.0, opacity.constant.r));
    alpha = assembly_.AddTexture(bsdf.Get("id", "opacity"), Spec("constant_texture", std::move(props)));
  }
  textures_[&bsdf] = alpha;
  return alpha;
}

// Returns the material's name, or "" for a null BSDF (a surface that does
// not scatter).
std::string MitsubaImporter::MakeMaterial(const XmlElement& e, const std::string& name, bool two_sided) {
  const RecursionGuard guard(nesting, e.where);
  XmlPlugin p(e, *this);
  const std::string& type = p.type();
  const std::string what = "bsdf '" + type + "'";
  v1::Properties props;

  // A reflectance: a texture (clamped into [0, 1] by the model), or a
  // constant clamped here.
  auto reflectance = [&](const std::string& key, const std::string& out, Rgb fallback) {
    Textured value = p.TexturedColor(key, fallback);
    if (!value.IsTexture())
      value.constant = ClampColour(value.constant, 0, 1, [&] {
        Warn(p.WhereIs(key), "clamp:" + key, what + ": " + key + " clamped into [0, 1]");
      });
    SetColour(props, out, value);
  };
  auto ior = [&](const std::string& key, double fallback) {
    const double v = p.Ior(key, fallback);
    if (!(v > 0 && v < 100)) Fail(p.WhereIs(key), what + ": " + key + " must lie in (0, 100)");
    SetFloat(props, key, v);
  };
  // Mitsuba's microfacet models default to Beckmann (yarf's to GGX).
  auto distribution = [&] {
    const std::string d = p.String("distribution", "beckmann");
    if (d != "ggx" && d != "beckmann")
      Fail(p.WhereIs("distribution"), what + ": distribution must be \"ggx\" or \"beckmann\"");
    SetString(props, "distribution", d);
    if (!p.Boolean("sample_visible", true))
      Warn(p.WhereIs("sample_visible"), "sample_visible",
           what + ": sample_visible false is not supported: visible normals are sampled");
  };
  auto alpha = [&](const std::string& key) {
    if (const Textured t = p.TexturedColor(key, {0.1, 0.1, 0.1}); t.IsTexture()) {
      SetReference(props, key, t.texture);
      return;
    }
    const double a = p.Float(key, 0.1);
    if (!(a > 0 && a <= 10)) Fail(p.WhereIs(key), what + ": " + key + " must lie in (0, 10]");
    SetFloat(props, key, a);
  };
  // A microfacet surface: its distribution, and one α or α_u and α_v.
  auto rough_surface = [&] {
    distribution();
    if (p.Has("alpha_u") || p.Has("alpha_v")) {
      alpha("alpha_u");
      alpha("alpha_v");
    } else {
      alpha("alpha");
    }
  };
  // A Disney model's weight in [0, high], a number or a texture: Mitsuba
  // reads them unchecked, yarf's models refuse a constant outside, so
  // clamp here.
  auto disney_weight = [&](const std::string& key, int high) {
    if (!p.Has(key)) return;
    Textured value = p.TexturedColor(key, {0, 0, 0});
    if (!value.IsTexture())
      value.constant = ClampColour(value.constant, 0, high, [&] {
        Warn(p.WhereIs(key), "clamp:" + key, what + ": " + key + " clamped into [0, " + std::to_string(high) + "]");
      });
    SetFloatOrTexture(props, key, value);
  };
  auto sampling_rate = [&](const std::string& key) {
    if (!p.Has(key)) return;
    const double rate = p.Float(key, 1.0);
    if (!(rate >= 0)) Fail(p.WhereIs(key), what + ": " + key + " must be ≥ 0");
    SetFloat(props, key, rate);
  };
  // A nested BSDF stands for a wrapper (twosided, mask, bumpmap...).
  auto inner = [&]() -> const XmlElement& {
    const auto nested = p.Objects("bsdf");
    if (nested.empty()) Fail(e.where, what + " needs a nested <bsdf>");
    if (nested.size() > 1)
      Warn(nested[1]->where, "twosided-two", what + ": only the first nested BSDF is used on both sides");
    p.WarnUnused();
    return *nested.front();
  };

  std::string class_name;
  if (type == "diffuse") {
    class_name = "lambertian";
    reflectance("reflectance", "reflectance", {0.5, 0.5, 0.5});
    SetBool(props, "two_sided", two_sided);
  } else if (type == "roughdiffuse") {
    class_name = "roughdiffuse";
    reflectance("reflectance", "reflectance", {0.5, 0.5, 0.5});
    // The grooves' slope may be 0 (Lambertian), unlike a microfacet α.
    if (const Textured t = p.TexturedColor("alpha", {0.2, 0.2, 0.2}); t.IsTexture()) {
      SetReference(props, "alpha", t.texture);
    } else {
      const double a = p.Float("alpha", 0.2);
      if (!(a >= 0 && a <= 10)) Fail(p.WhereIs("alpha"), what + ": alpha must lie in [0, 10]");
      SetFloat(props, "alpha", a);
    }
    SetBool(props, "use_fast_approx", p.Boolean("use_fast_approx", false));
    SetBool(props, "two_sided", two_sided);
  } else if (type == "twosided") {
    const XmlElement& front = inner();
    if (front.Get("type") != "diffuse" && front.Get("type") != "roughdiffuse")
      Warn(e.where, "twosided", "twosided: the back side follows the inner model's own two-sidedness");
    return MakeMaterial(front, name, true);
  } else if (type == "mask") {
    // Its opacity is the shape's cut-out (MaskAlpha); the surface is the nested BSDF's.
    p.Accept({"opacity"});
    return MakeMaterial(inner(), name, two_sided);
  } else if (type == "normalmap") {
    const Textured normals = p.TexturedColor("normalmap", {0.5, 0.5, 1});
    const std::string nested = MakeMaterial(inner(), name + "-nested", two_sided);
    if (!normals.IsTexture()) {
      Warn(e.where, "normalmap-constant", "normalmap without a normal texture: the nested BSDF is used");
      return nested;
    }
    if (nested.empty()) return "";
    SetReference(props, "bsdf", nested);
    SetReference(props, "normalmap", normals.texture);
    return assembly_.AddMaterial(name, "normalmap", std::move(props));
  } else if (type == "bumpmap") {
    // The height is the nested texture, whatever its name.
    const auto textures = p.Objects("texture");
    if (textures.empty()) Fail(e.where, what + " needs a nested <texture> (the height)");
    const std::string height = TextureReference(*textures.front());
    const double scale = p.Float("scale", 1.0);
    const std::string nested = MakeMaterial(inner(), name + "-nested", two_sided);
    if (height.empty()) {
      Warn(e.where, "bumpmap-texture", "bumpmap: texture type '" + textures.front()->Get("type") +
                                           "' is not supported: the nested BSDF is used unbumped");
      return nested;
    }
    if (nested.empty()) return "";
    SetReference(props, "bsdf", nested);
    SetReference(props, "bumpmap", height);
    SetFloat(props, "scale", scale);
    return assembly_.AddMaterial(name, "bumpmap", std::move(props));
  } else if (type == "blendbsdf") {
    const auto nested = p.Objects("bsdf");
    if (nested.size() != 2) Fail(e.where, what + " needs two nested BSDFs");
    const Textured weight = p.TexturedColor("weight", {0.5, 0.5, 0.5});
    if (!weight.IsTexture() && !(weight.constant.r >= 0 && weight.constant.r <= 1))
      Fail(p.WhereIs("weight"), what + ": weight must lie in [0, 1]");
    p.WarnUnused();
    const std::string first = MakeMaterial(*nested[0], name + "-0", two_sided),
                      second = MakeMaterial(*nested[1], name + "-1", two_sided);
    // A null BSDF in the blend: yarf has no partly invisible surfaces.
    if (first.empty() || second.empty()) {
      Warn(e.where, "blendbsdf-null", what + ": a null nested BSDF: the other one used alone");
      return first.empty() ? second : first;
    }
    SetReference(props, "bsdf_0", first);
    SetReference(props, "bsdf_1", second);
    SetFloatOrTexture(props, "weight", weight);
    return assembly_.AddMaterial(name, "blend", std::move(props));
  } else if (type == "null") {
    // The shape decides: a "null" boundary, or left out (MitsubaImporter::Shape).
    p.WarnUnused();
    return "";
  } else if (type == "conductor" || type == "roughconductor") {
    class_name = type;
    if (p.Has("eta") || p.Has("k")) {
      if (p.Has("material")) Fail(e.where, what + ": give material or eta and k, not both");
      SetColour(props, "eta", p.TexturedColor("eta", {0, 0, 0}));
      SetColour(props, "k", p.TexturedColor("k", {1, 1, 1}));
    } else {
      SetString(props, "material", KnownMetal(p.String("material", "none"), p.WhereIs("material")));
    }
    if (p.Has("specular_reflectance")) reflectance("specular_reflectance", "specular_reflectance", {1, 1, 1});
    if (type == "roughconductor") {
      rough_surface();
    }
  } else if (type == "dielectric" || type == "thindielectric" || type == "roughdielectric") {
    class_name = type;
    ior("int_ior", kBk7);
    ior("ext_ior", kAir);
    for (const char* key : {"specular_reflectance", "specular_transmittance"})
      if (p.Has(key)) {
        p.Color(key, {1, 1, 1});
        Warn(p.WhereIs(key), std::string("dielectric:") + key, what + ": " + key + " is not supported: ignored");
      }
    if (type == "roughdielectric") {
      rough_surface();
    }
  } else if (type == "plastic" || type == "roughplastic") {
    class_name = type;
    reflectance("diffuse_reflectance", "diffuse_reflectance", {0.5, 0.5, 0.5});
    ior("int_ior", kPolypropylene);
    ior("ext_ior", kAir);
    if (type == "roughplastic") {
      distribution();
      alpha("alpha");
    }
    if (p.Has("specular_reflectance")) reflectance("specular_reflectance", "specular_reflectance", {1, 1, 1});
    if (p.Has("nonlinear")) SetBool(props, "nonlinear", p.Boolean("nonlinear", false));
  } else if (type == "pplastic") {
    // Its RGB rendering: the coating and the base reflect apart.
    class_name = type;
    reflectance("diffuse_reflectance", "diffuse_reflectance", {0.5, 0.5, 0.5});
    if (p.Has("specular_reflectance")) reflectance("specular_reflectance", "specular_reflectance", {1, 1, 1});
    ior("int_ior", kPolypropylene);
    ior("ext_ior", kAir);
    rough_surface();
  } else if (type == "phong") {
    class_name = "phong";
    reflectance("diffuse_reflectance", "diffuse_reflectance", {0.5, 0.5, 0.5});
    reflectance("specular_reflectance", "specular_reflectance", {0.2, 0.2, 0.2});
    SetFloat(props, "exponent", p.Float("exponent", 30));
  } else if (type == "principled") {
    class_name = "principled";
    reflectance("base_color", "base_color", {0.5, 0.5, 0.5});
    for (const char* key : {"roughness", "anisotropic", "metallic", "spec_trans", "specular", "spec_tint", "sheen",
                            "sheen_tint", "flatness", "clearcoat", "clearcoat_gloss"})
      disney_weight(key, 1);
    if (p.Has("eta") && p.Has("specular"))
      Fail(p.WhereIs("specular"), what + ": give eta or specular (the same index of refraction), not both");
    if (p.Has("eta")) {
      const double eta = p.Float("eta", 1.5);
      if (!(eta > 0 && eta < 100)) Fail(p.WhereIs("eta"), what + ": eta must lie in (0, 100)");
      SetFloat(props, "eta", eta);
    }
    for (const char* key : {"diffuse_reflectance_sampling_rate", "main_specular_sampling_rate",
                            "clearcoat_sampling_rate"})
      sampling_rate(key);
  } else if (type == "hair") {
    class_name = "hair";
    // Mitsuba's names for pbrt's parameters, and its own defaults (0.2 of
    // pheomelanin beside the eumelanin unless an absorption is given).
    if (p.Has("sigma_a")) {
      const Textured sigma_a = p.TexturedColor("sigma_a", {0, 0, 0});
      if (sigma_a.IsTexture()) Fail(p.WhereIs("sigma_a"), what + ": a textured sigma_a is not supported");
      SetRgb(props, "sigma_a", sigma_a.constant);
    } else {
      SetFloat(props, "eumelanin", p.Float("eumelanin", 1.3));
      SetFloat(props, "pheomelanin", p.Float("pheomelanin", 0.2));
    }
    SetFloat(props, "beta_m", p.Float("longitudinal_roughness", 0.3));
    SetFloat(props, "beta_n", p.Float("azimuthal_roughness", 0.3));
    SetFloat(props, "alpha", p.Float("scale_tilt", 2));
    SetFloat(props, "eta", p.Float("eta", 1.55));
  } else if (type == "principledthin") {
    class_name = "principledthin";
    reflectance("base_color", "base_color", {0.5, 0.5, 0.5});
    for (const char* key : {"roughness", "anisotropic", "spec_trans", "spec_tint", "sheen", "sheen_tint", "flatness"})
      disney_weight(key, 1);
    // 2 gives all of the diffuse lobe to the other side.
    disney_weight("diff_trans", 2);
    // The sheet's index may vary over it (a texture), as in Mitsuba.
    if (p.Has("eta")) {
      const Textured eta = p.TexturedColor("eta", {1.5, 1.5, 1.5});
      if (!eta.IsTexture() && !(eta.constant.r > 0 && eta.constant.r < 100))
        Fail(p.WhereIs("eta"), what + ": eta must lie in (0, 100)");
      SetFloatOrTexture(props, "eta", eta);
    }
    for (const char* key : {"specular_reflectance_sampling_rate", "specular_transmittance_sampling_rate",
                            "diffuse_reflectance_sampling_rate", "diffuse_transmittance_sampling_rate"})
      sampling_rate(key);
  } else {
    static const std::vector<std::string> kKnown = {
        "diffuse", "roughdiffuse", "twosided", "mask", "bumpmap", "normalmap", "blendbsdf", "null",
        "conductor", "roughconductor", "dielectric", "thindielectric", "roughdielectric", "plastic",
        "roughplastic", "pplastic", "phong", "principled", "principledthin", "hair"};
    Warn(e.where, "bsdf:" + type,
         "bsdf '" + type + "' is not supported: a grey Lambertian used" + DidYouMean(type, kKnown));
    return assembly_.DefaultMaterial();
  }
  p.WarnUnused();
  return assembly_.AddMaterial(name, class_name, std::move(props));
}

}  // namespace yarf::importers
