// pbrt materials as yarf SurfaceModel classes.
#include <google/protobuf/text_format.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <tuple>
#include <vector>

#include "importers/colour_checks.h"
#include "importers/measured_media.h"
#include "importers/named_ior.h"
#include "importers/pbrt_importer.h"
#include "importers/properties_util.h"
#include "importers/recursion_guard.h"
#include "yarf/support/named_metals.h"

namespace yarf::importers {
namespace {

// "metal-Cu-eta" and "metal-Cu-k" name copper's spectra: "Cu".
std::optional<std::string> MetalName(const PbrtParam* p) {
  if (!p || p->type != "spectrum" || p->strings.size() != 1) return std::nullopt;
  const std::string& s = p->strings[0];
  if (s.rfind("metal-", 0) != 0) return std::nullopt;
  const size_t dash = s.rfind('-');
  if (dash <= 6) return std::nullopt;
  const std::string suffix = s.substr(dash + 1);
  if (suffix != "eta" && suffix != "k") return std::nullopt;
  return s.substr(6, dash - 6);
}

// The single-scattering albedo of a thick homogeneous medium whose
// multiple scattering reflects `reflectance` of the light (Christensen and
// Burley's fit for a random walk in a medium, as Cycles inverts its
// random-walk subsurface colour): pbrt-v4 inverts its diffusion profile's
// table instead, whose albedo differs by a few percent.
double SingleScatteringAlbedo(double reflectance) {
  const double a = std::clamp(reflectance, 0.0, 1.0);
  const double root = 4.09712 + 4.20863 * a - std::sqrt(9.59217 + 41.6808 * a + 17.7126 * a * a);
  return std::clamp(1 - root * root, 0.0, 1.0);
}

// pbrt-v4 maps roughness to the microfacet alpha by a square root.
double Alpha(double roughness, bool remap) { return remap ? std::sqrt(std::max(roughness, 0.0)) : roughness; }

}  // namespace

std::string PbrtImporter::MakeMaterial(const std::string& type, PbrtParams& params, const SourceLocation& where,
                                       const std::string& name) {
  const RecursionGuard guard(nesting_, where);
  const std::string what = "material '" + type + "'";
  params.Accept({"type"});
  // A displacement texture bumps the material made below (bumpmap); a
  // constant displacement moves the surface without tilting it.
  std::string bump_map;
  if (params.Has("displacement")) {
    const Textured displacement = TexturedFloat(params, "displacement", 0);
    if (displacement.IsTexture()) bump_map = displacement.texture;
  }
  // A normal map: the material made below, seen through it (normalmap).
  std::string normal_map;
  if (params.Has("normalmap")) {
    const auto file = folder_.Resolve(params.String("normalmap", ""), origin_.file, params.WhereIs("normalmap", where));
    v1::Properties image;
    SetString(image, "filename", folder_.Relative(file));
    SetString(image, "encoding", "linear");
    // pbrt's images have v = 0 at their bottom row, yarf's at the top.
    SetTransform(image, "to_uv", Matrix4({1, 0, 0, 0, 0, -1, 0, 1, 0, 0, 1, 0, 0, 0, 0, 1}));
    normal_map = assembly_.AddTexture("normalmap", Spec("bitmap", std::move(image)));
  }
  v1::Properties props;
  // A subsurface material's medium inside (empty for other materials).
  v1::Properties medium;
  // A reflectance: a texture (clamped into [0, 1] by the model; `scale`
  // only for constants), or a constant clamped here.
  auto reflectance = [&](const std::string& key, const std::string& out, double fallback, double scale = 1) {
    Textured value = TexturedColour(params, key, {fallback, fallback, fallback}, SpectrumUse::kReflectance, where);
    if (value.IsTexture() && scale != 1) {
      Warn(params.WhereIs(key, where), "texture-scale:" + key, what + ": a scaled texture " + key + ": its mean used");
      value.texture.clear();
    }
    if (!value.IsTexture())
      value.constant = ClampColour(value.constant * scale, 0, 1, [&] {
        Warn(params.WhereIs(key, where), "clamp:" + key, what + ": " + key + " clamped into [0, 1]");
      });
    SetColour(props, out, value);
  };
  // eta as a number, a named glass or (approximately) a spectrum.
  auto eta = [&](const std::string& key, double fallback) {
    const PbrtParam* p = params.Find(key);
    double v = fallback;
    if (p && p->type == "spectrum" && p->strings.size() == 1) {
      const auto glass = PbrtNamedGlassIor(p->strings[0]);
      if (!glass) Fail(p->where, "unknown named spectrum '" + p->strings[0] + "' for " + key);
      v = *glass;
      Warn(p->where, "glass-dispersion", "dispersive glass replaced by its index at 587.6 nm");
    } else if (p && p->type == "spectrum") {
      const Rgb c = Colour(params, key, {v, v, v}, SpectrumUse::kReflectance, where);
      v = c.g;
      Warn(p->where, "eta-spectrum", "a spectrally varying eta replaced by its green value");
    } else if (p) {
      v = FloatOrTexture(params, key, fallback);
    }
    if (!(v > 0 && v < 100)) Fail(params.WhereIs(key, where), what + ": " + key + " must lie in (0, 100)");
    return v;
  };
  // Isotropic or anisotropic alpha from pbrt's roughness parameters; true
  // when rough.
  auto roughness = [&](const std::string& prefix) {
    const bool remap = params.Bool("remaproughness", true);
    const double r = FloatOrTexture(params, prefix + "roughness", 0);
    const double u = Alpha(FloatOrTexture(params, prefix + "uroughness", r), remap);
    const double v = Alpha(FloatOrTexture(params, prefix + "vroughness", r), remap);
    if (!(u >= 0 && u <= 10 && v >= 0 && v <= 10)) Fail(where, what + ": roughness out of range");
    // A microfacet model needs α > 0 along both axes once either is rough.
    if (u > 0 || v > 0) return std::pair{std::max(u, 1e-4), std::max(v, 1e-4)};
    return std::pair{u, v};
  };
  auto conductor = [&](const std::string& prefix) {
    const auto [u, v] = roughness(prefix);
    const PbrtParam* refl = params.Find("reflectance");
    const PbrtParam* eta_param = params.Find(prefix + "eta");
    const PbrtParam* k_param = params.Find(prefix + "k");
    const Textured given = refl ? TexturedColour(params, "reflectance", {}, SpectrumUse::kReflectance, where)
                                : Textured{};
    if (refl && !given.IsTexture()) {
      // pbrt-v4's conductor of that reflectance at normal incidence: η = 1
      // and k = 2√r / √(1 − r), so that ((η − 1)² + k²) / ((η + 1)² + k²) = r.
      const Rgb r = ClampColour(given.constant, 0, 0.9999, [] {});
      const auto k = [](double v) { return 2 * std::sqrt(v) / std::sqrt(1 - v); };
      SetRgb(props, "eta", {1, 1, 1});
      SetRgb(props, "k", {k(r.r), k(r.g), k(r.b)});
    } else if (refl) {
      Warn(refl->where, "conductor-reflectance",
           "conductor given by a reflectance texture: a perfect conductor tinted by it (Fresnel falloff differs)");
      SetString(props, "material", "none");
      reflectance("reflectance", "specular_reflectance", 1);
    } else if (MetalName(eta_param) || MetalName(k_param) || (!eta_param && !k_param)) {
      std::string metal = MetalName(eta_param).value_or(MetalName(k_param).value_or("Cu"));
      if ((eta_param && MetalName(eta_param) != metal) || (k_param && MetalName(k_param) != metal))
        Warn(where, "conductor-mixed", what + ": eta and k of different metals: '" + metal + "' used");
      // The metals yarf's conductors know (yarf/support/named_metals.h).
      if (!metals::IsNamed(metal)) {
        Warn(where, "metal:" + metal, "metal '" + metal + "' is not among yarf's named metals: a perfect mirror used");
        metal = "none";
      }
      SetString(props, "material", metal);
    } else {
      SetColour(props, "eta", TexturedColour(params, prefix + "eta", {0.2, 0.92, 1.1}, SpectrumUse::kReflectance, where));
      SetColour(props, "k", TexturedColour(params, prefix + "k", {3.9, 2.45, 2.14}, SpectrumUse::kReflectance, where));
    }
    if (u == 0 && v == 0) return std::string("conductor");
    if (u == v)
      SetFloat(props, "alpha", u);
    else
      SetFloat(props, "alpha_u", u), SetFloat(props, "alpha_v", v);
    return std::string("roughconductor");
  };

  std::string class_name;
  if (type == "interface" || type == "none" || type == "") {
    // Medium boundaries that do not scatter ("null"); shapes that bound
    // no medium are left out (pbrt-v4 skips them).
    params.WarnUnused(diagnostics_, what);
    return kInterface;
  } else if (type == "diffuse" || type == "matte") {
    class_name = "lambertian";
    reflectance(type == "matte" ? "Kd" : "reflectance", "reflectance", 0.5);
    // pbrt-v3's matte with a slope deviation σ (degrees) is Oren and
    // Nayar's qualitative model, roughdiffuse's fast one with α = √2 σ.
    const double sigma = type == "matte" ? FloatOrTexture(params, "sigma", 0) : 0;
    if (!(sigma >= 0 && sigma <= 90))
      Fail(params.WhereIs("sigma", where), what + ": sigma must lie in [0, 90] degrees");
    if (sigma > 0) {
      class_name = "roughdiffuse";
      SetFloat(props, "alpha", std::sqrt(2.0) * sigma * M_PI / 180);
      SetBool(props, "use_fast_approx", true);
    }
  } else if (type == "coateddiffuse" || type == "coatedconductor") {
    // pbrt-v4's layered materials: the plugins of the same names take
    // pbrt's parameter names; only what was given is passed on, so the
    // plugins' defaults (pbrt's) apply to the rest.
    class_name = type;
    const bool diffuse = type == "coateddiffuse";
    auto float_or_texture = [&](const std::string& key) {
      if (params.Has(key)) SetFloatOrTexture(props, key, TexturedFloat(params, key, 0));
    };
    const std::vector<std::string> layers = diffuse ? std::vector<std::string>{""}
                                                    : std::vector<std::string>{"interface.", "conductor."};
    for (const std::string& prefix : layers)
      for (const char* key : {"roughness", "uroughness", "vroughness"}) float_or_texture(prefix + key);
    if (params.Has("remaproughness")) SetBool(props, "remaproughness", params.Bool("remaproughness", true));
    const std::string eta_key = diffuse ? "eta" : "interface.eta";
    if (params.Has(eta_key)) SetFloat(props, eta_key, eta(eta_key, 1.5));
    for (const char* key : {"thickness", "g"}) float_or_texture(key);
    if (params.Has("albedo")) reflectance("albedo", "albedo", 0);
    for (const char* key : {"maxdepth", "nsamples"})
      if (params.Has(key)) SetInt(props, key, params.Integer(key, 1));
    if (diffuse) {
      reflectance("reflectance", "reflectance", 0.5);
    } else if (params.Has("reflectance")) {
      if (params.Has("conductor.eta") || params.Has("conductor.k"))
        Fail(where, what + ": give the conductor by \"reflectance\" or by \"conductor.eta\" and \"conductor.k\", not both");
      reflectance("reflectance", "reflectance", 1);
    } else {
      // A named metal's spectra become yarf's RGB of it (yarf/support/named_metals.h).
      for (const char* key : {"conductor.eta", "conductor.k"}) {
        const PbrtParam* p = params.Find(key);
        if (!p) continue;
        if (const auto metal = MetalName(p)) {
          const auto known = std::find_if(std::begin(metals::kMetals), std::end(metals::kMetals),
                                          [&](const metals::NamedMetal& m) { return *metal == m.name; });
          if (known == std::end(metals::kMetals)) {
            Warn(p->where, "metal:" + *metal, "metal '" + *metal + "' is not among yarf's named metals: copper used");
            continue;
          }
          const Vec3 v = std::string(key) == "conductor.eta" ? known->ior.eta : known->ior.k;
          SetColour(props, key, Textured{Rgb{v.x, v.y, v.z}, ""});
        } else {
          SetColour(props, key, TexturedColour(params, key, {1, 1, 1}, SpectrumUse::kReflectance, where));
        }
      }
    }
  } else if (type == "conductor") {
    class_name = conductor("");
  } else if (type == "dielectric" || type == "thindielectric" || type == "subsurface") {
    // pbrt-v4's subsurface material is a dielectric boundary over what its
    // BSSRDF approximates by diffusion: a scattering medium inside, which
    // here is that medium itself, walked through by volpath.
    const bool subsurface = type == "subsurface";
    SetFloat(props, "int_ior", eta("eta", subsurface ? 1.33 : 1.5));
    SetFloat(props, "ext_ior", 1.0);
    class_name = subsurface ? "dielectric" : type;
    if (type != "thindielectric") {
      const auto [u, v] = roughness("");
      if (u != 0 || v != 0) {
        class_name = "roughdielectric";
        if (u == v)
          SetFloat(props, "alpha", u);
        else
          SetFloat(props, "alpha_u", u), SetFloat(props, "alpha_v", v);
      }
    }
    if (subsurface) medium = SubsurfaceMedium(params, where);
  } else if (type == "diffusetransmission") {
    class_name = "diffusetransmission";
    const double scale = FloatOrTexture(params, "scale", 1);
    reflectance("reflectance", "reflectance", 0.25, scale);
    reflectance("transmittance", "transmittance", 0.25, scale);
  } else if (type == "hair") {
    class_name = "hair";
    // pbrt-v4's choice of absorption: sigma_a, else a colour, else melanin.
    if (params.Has("sigma_a")) {
      const Rgb sigma_a = Colour(params, "sigma_a", {0, 0, 0}, SpectrumUse::kReflectance, where);
      if (!(sigma_a.r >= 0 && sigma_a.g >= 0 && sigma_a.b >= 0 && sigma_a.r < 1e4 && sigma_a.g < 1e4 && sigma_a.b < 1e4))
        Fail(params.WhereIs("sigma_a", where), what + ": sigma_a must lie in [0, 10000)");
      SetRgb(props, "sigma_a", sigma_a);
    } else if (params.Has("reflectance")) {
      SetRgb(props, "reflectance",
             ClampColour(Colour(params, "reflectance", {0.5, 0.5, 0.5}, SpectrumUse::kReflectance, where), 1e-4, 1,
                         [&] { Warn(params.WhereIs("reflectance", where), "clamp:reflectance",
                                    what + ": reflectance clamped into [0.0001, 1]"); }));
    }
    for (const char* key : {"eumelanin", "pheomelanin", "eta", "beta_m", "beta_n", "alpha"})
      if (params.Has(key)) SetFloat(props, key, FloatOrTexture(params, key, 0));
  } else if (type == "mix") {
    const PbrtParam* materials = params.Find("materials");
    if (!materials || materials->strings.size() != 2) Fail(where, "mix needs \"string materials\" with two names");
    // pbrt-v4 picks materials[1] with probability `amount` at each point:
    // on average, the blend (1 − amount)·f₀ + amount·f₁.
    const Textured amount = TexturedFloat(params, "amount", 0.5);
    if (!amount.IsTexture() && !(amount.constant.r >= 0 && amount.constant.r <= 1))
      Fail(params.WhereIs("amount", where), "mix: amount must lie in [0, 1]");
    class_name = "blend";
    for (int i = 0; i < 2; ++i) {
      const auto it = named_materials_.find(materials->strings[i]);
      if (it == named_materials_.end()) Fail(where, "mix: named material '" + materials->strings[i] + "' is not defined");
      SetReference(props, "bsdf_" + std::to_string(i), it->second);
    }
    SetFloatOrTexture(props, "weight", amount);
  } else {
    static const std::vector<std::string> kKnown = {
        "interface", "none", "diffuse", "matte", "coateddiffuse", "conductor", "coatedconductor", "dielectric",
        "thindielectric", "diffusetransmission", "mix", "measured", "hair", "subsurface"};
    Warn(where, "material:" + type,
         "material '" + type + "' is not supported: a grey diffuse used" + DidYouMean(type, kKnown));
    return assembly_.DefaultMaterial();
  }
  params.WarnUnused(diagnostics_, what);
  // Anonymous materials with equal parameters share one yarf material.
  std::string key, medium_key;
  google::protobuf::TextFormat::PrintToString(props, &key);
  google::protobuf::TextFormat::PrintToString(medium, &medium_key);
  key = class_name + "\n" + key + "\n" + medium_key;
  if (name.empty()) {
    const auto it = material_cache_.find(key);
    if (it != material_cache_.end()) return it->second;
  }
  if (!normal_map.empty() || !bump_map.empty()) {
    // As pbrt-v4, a normal map wins over a displacement.
    if (!normal_map.empty() && !bump_map.empty())
      Warn(params.WhereIs("displacement", where), "material:displacement-normalmap",
           what + ": a normal map and a displacement: the displacement is ignored");
    v1::Properties wrapper;
    SetReference(wrapper, "bsdf", assembly_.AddMaterial((name.empty() ? type : name) + "-nested", class_name, std::move(props)));
    const char* wrapper_class = normal_map.empty() ? "bumpmap" : "normalmap";
    SetReference(wrapper, wrapper_class, normal_map.empty() ? bump_map : normal_map);
    return assembly_.AddMaterial(name.empty() ? type : name, wrapper_class, std::move(wrapper));
  }
  const std::string made = assembly_.AddMaterial(name.empty() ? type : name, class_name, std::move(props));
  if (name.empty()) material_cache_[key] = made;
  if (!medium.values().empty()) {
    // Keyed apart from MakeNamedMedium's names, which cannot hold a quote.
    const std::string inside = "\"subsurface\" " + made;
    media_[inside] = assembly_.AddMedium(made + "-inside", Spec("homogeneous", std::move(medium)), std::nullopt, where);
    subsurface_media_[made] = inside;
  }
  return made;
}

v1::Properties PbrtImporter::SubsurfaceMedium(PbrtParams& params, const SourceLocation& where) {
  const std::string what = "material 'subsurface'";
  v1::Properties medium;
  auto coefficients = [&](Rgb sigma_a, Rgb sigma_s) {
    for (const Rgb& c : {sigma_a, sigma_s})
      if (!(std::min({c.r, c.g, c.b}) >= 0 && std::max({c.r, c.g, c.b}) < 1e30))
        Fail(where, what + ": sigma_a and sigma_s must be finite and non-negative");
    SetRgb(medium, "sigma_a", sigma_a);
    SetRgb(medium, "sigma_s", sigma_s);
  };
  const double scale = params.Float("scale", 1);
  if (!(scale > 0 && scale < 1e30))
    Fail(params.WhereIs("scale", where), what + ": scale must be positive and below 1e30");
  double g = params.Float("g", 0);
  if (!(g > -1 && g < 1)) Fail(params.WhereIs("g", where), what + ": g must lie in (-1, 1)");
  // pbrt-v4's four ways, in its order: a measured medium's name, σ_a and
  // σ_s, a reflectance with a mean free path, or its default (skin-like,
  // per millimetre); `scale` multiplies the coefficients, or the path.
  if (const std::string preset = params.String("name", ""); !preset.empty()) {
    const auto measured = PbrtMeasuredMedium(preset);
    if (!measured)
      Fail(params.WhereIs("name", where), what + ": \"" + preset + "\" is not one of pbrt-v4's measured media" +
                                              DidYouMean(preset, PbrtMeasuredMediumNames()));
    if (g != 0)
      Warn(params.WhereIs("g", where), "subsurface-g", what + ": g ignored with a measured medium (as pbrt-v4)");
    g = 0;  // the measurements' σ_s are reduced ones
    coefficients(measured->sigma_a * scale, measured->sigma_prime_s * scale);
  } else if (params.Has("sigma_a") || params.Has("sigma_s")) {
    if (!params.Has("sigma_a") || !params.Has("sigma_s")) Fail(where, what + ": give sigma_a and sigma_s together");
    coefficients(Colour(params, "sigma_a", {}, SpectrumUse::kReflectance, where) * scale,
                 Colour(params, "sigma_s", {}, SpectrumUse::kReflectance, where) * scale);
  } else if (params.Has("reflectance")) {
    const Rgb reflectance = Colour(params, "reflectance", {}, SpectrumUse::kReflectance, where);
    const Rgb mfp = Colour(params, "mfp", {1, 1, 1}, SpectrumUse::kReflectance, where) * scale;
    if (!(std::min({mfp.r, mfp.g, mfp.b}) > 0)) Fail(params.WhereIs("mfp", where), what + ": mfp must be positive");
    Rgb sigma_a, sigma_s;
    for (auto [r, path, a, s] : {std::tuple{reflectance.r, mfp.r, &sigma_a.r, &sigma_s.r},
                                 std::tuple{reflectance.g, mfp.g, &sigma_a.g, &sigma_s.g},
                                 std::tuple{reflectance.b, mfp.b, &sigma_a.b, &sigma_s.b}}) {
      const double albedo = SingleScatteringAlbedo(r);
      *s = albedo / path;
      *a = (1 - albedo) / path;
    }
    coefficients(sigma_a, sigma_s);
  } else {
    coefficients(Rgb{0.0011, 0.0024, 0.014} * scale, Rgb{2.55, 3.21, 3.77} * scale);
  }
  if (g != 0) SetFloat(medium, "g", g);
  params.Accept({"mfp"});
  return medium;
}

}  // namespace yarf::importers
