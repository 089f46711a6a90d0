// Mitsuba media (<medium>), their phase functions (<phase>) and volumes
// (<volume>) as yarf Medium classes.
//
// Mitsuba gives a medium by its extinction σ_t and albedo; yarf by σ_a and
// σ_s: σ_s = albedo·σ_t, σ_a = σ_t − σ_s, per channel, `scale` as it is.
// homogeneous → homogeneous; heterogeneous → grid, whose unit cube the σ_t
// volume's to_world places (Mitsuba's media have no transform of their
// own), an albedo gridvolume its albedo_filename.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "importers/colour_checks.h"
#include "importers/numbers.h"
#include "importers/properties_util.h"
#include "importers/volume_file.h"
#include "importers/xml_importer.h"

namespace yarf::importers {
namespace {

double MaxOf(const Rgb& c) { return std::max({c.r, c.g, c.b}); }
double MinOf(const Rgb& c) { return std::min({c.r, c.g, c.b}); }

// What a medium reads from a value or a <volume>: a constant, or a grid.
struct MediumValue {
  Rgb constant;
  std::filesystem::path grid;  // a gridvolume's file; empty for a constant
  Matrix4 to_world;            // the grid's unit cube to the world
  SourceLocation where;
  bool IsGrid() const { return !grid.empty(); }
};

// The medium's property `name`: a float, rgb or spectrum, a constvolume or
// a gridvolume. nullopt (warned) for a volume yarf has no class for.
std::optional<MediumValue> ValueOf(MitsubaImporter& importer, XmlPlugin& medium, const std::string& name,
                                   Rgb fallback) {
  MediumValue value{fallback, {}, {}, medium.WhereIs(name)};
  const XmlElement* e = medium.Object(name);
  if (!e || e->tag != "volume") {
    value.constant = medium.Color(name, fallback);
    return value;
  }
  XmlPlugin volume(*e, importer);
  const std::string& type = volume.type();
  if (type == "constvolume") {
    value.constant = volume.Color("value", {1, 1, 1});
    value.to_world = volume.Transform("to_world");  // where a heterogeneous medium has it
  } else if (type == "gridvolume" || type == "grid") {
    if (!volume.Has("filename")) Fail(e->where, "volume '" + type + "' needs a filename");
    value.grid = importer.folder().Resolve(volume.String("filename", ""), e->file, volume.WhereIs("filename"));
    value.to_world = volume.Transform("to_world");
    // Mitsuba maps the unit cube to the file's bounding box first.
    if (volume.Boolean("use_grid_bbox", false)) {
      const VolHeader header = ReadVolHeader(value.grid, volume.WhereIs("filename"));
      value.to_world = value.to_world * Matrix4::Translate(header.min) * Matrix4::Scale(header.max - header.min);
    }
    if (volume.String("filter_type", "trilinear") != "trilinear")
      importer.Warn(volume.WhereIs("filter_type"), "gridvolume-filter",
                    "gridvolume: only trilinear lookups are supported: trilinear used");
    if (volume.String("wrap_mode", "clamp") != "clamp")
      importer.Warn(volume.WhereIs("wrap_mode"), "gridvolume-wrap",
                    "gridvolume: only the clamp wrap mode is supported: the grid is not repeated");
    volume.Accept({"raw", "accel", "max_value"});
  } else {
    importer.Warn(e->where, "volume:" + type,
                  "volume '" + type + "' is not supported: the medium using it is left out (vacuum)");
    return std::nullopt;
  }
  volume.WarnUnused();
  return value;
}

// A phase function as yarf's medium properties take it: Henyey–Greenstein
// (its g), Rayleigh's, or a table over the scattering angle's cosine.
struct PhaseSpec {
  std::string shape = "hg";
  double g = 0;
  std::vector<double> values;
};

// One of Mitsuba's phase functions; isotropic (with a warning) for one
// yarf has none for.
PhaseSpec PhaseOf(MitsubaImporter& importer, const XmlElement& e) {
  XmlPlugin p(e, importer);
  PhaseSpec spec;
  if (p.type() == "hg") {
    spec.g = p.Float("g", 0.8);
    if (!(spec.g > -1 && spec.g < 1)) Fail(p.WhereIs("g"), "phase 'hg': g must lie in (-1, 1)");
  } else if (p.type() == "rayleigh") {
    spec.shape = "rayleigh";
  } else if (p.type() == "tabphase") {
    // Values at evenly spaced cosines of the scattering angle, from -1
    // (back toward the light) to 1, as yarf's table.
    spec.shape = "tabulated";
    const auto values = ParseDoubleList(p.String("values", ""));
    if (!values || values->size() < 2 || values->size() > (size_t(1) << 20))
      Fail(p.WhereIs("values"), "phase 'tabphase': values needs 2 to 2^20 numbers");
    for (const double v : *values)
      if (!(v >= 0 && std::isfinite(v))) Fail(p.WhereIs("values"), "phase 'tabphase': values must be finite and >= 0");
    const double largest = *std::max_element(values->begin(), values->end());
    if (!(largest > 0)) Fail(p.WhereIs("values"), "phase 'tabphase': values must not all be zero");
    // Only their shape matters (the medium normalises them): scaled to a
    // largest of 1, whatever magnitude the file gave.
    for (const double v : *values) spec.values.push_back(v / largest);
  } else if (p.type() != "isotropic") {
    importer.Warn(e.where, "phase:" + p.type(),
                  "phase function '" + p.type() + "' is not supported: isotropic used");
    return spec;
  }
  p.WarnUnused();
  return spec;
}

// The medium's phase function as yarf's properties: isotropic, hg,
// rayleigh, a table, or a blendphase of two Henyey–Greenstein lobes.
void Phase(MitsubaImporter& importer, XmlPlugin& medium, v1::Properties& props) {
  const auto phases = medium.Objects("phase");
  if (phases.empty()) return;  // isotropic
  if (phases.size() > 1) Fail(phases[1]->where, "a medium takes one phase function");
  const XmlElement& e = *phases.front();
  if (e.Get("type") != "blendphase") {
    const PhaseSpec spec = PhaseOf(importer, e);
    if (spec.shape != "hg") SetString(props, "phase", spec.shape);
    if (spec.g != 0) SetFloat(props, "g", spec.g);
    if (!spec.values.empty()) SetFloats(props, "phase_values", spec.values);
    return;
  }
  // Mitsuba's blend: (1 − weight)·first + weight·second.
  XmlPlugin blend(e, importer);
  const auto lobes = blend.Objects("phase");
  if (lobes.size() != 2) Fail(e.where, "phase 'blendphase' needs two nested phase functions");
  const double weight = blend.Float("weight", 0.5);
  if (!(weight >= 0 && weight <= 1)) Fail(blend.WhereIs("weight"), "phase 'blendphase': weight must lie in [0, 1]");
  blend.WarnUnused();
  // yarf blends Henyey–Greenstein lobes only.
  const auto lobe_g = [&](const XmlElement& lobe) {
    const PhaseSpec spec = PhaseOf(importer, lobe);
    if (spec.shape == "hg") return spec.g;
    importer.Warn(lobe.where, "blendphase:" + spec.shape,
                  "phase 'blendphase': only Henyey-Greenstein lobes blend: isotropic used for '" + lobe.Get("type") +
                      "'");
    return 0.0;
  };
  const double g = lobe_g(*lobes[0]), g2 = lobe_g(*lobes[1]);
  if (g != 0) SetFloat(props, "g", g);
  if (weight > 0) {
    SetFloat(props, "g2", g2);
    SetFloat(props, "blend", weight);
  }
}

}  // namespace

std::string MitsubaImporter::Medium(const XmlElement& element) {
  const auto it = media_.find(&element);
  if (it != media_.end()) return it->second;
  const std::string name = MakeMedium(element);
  media_[&element] = name;
  return name;
}

// The medium's name in Scene.media, or "" when it is left out.
std::string MitsubaImporter::MakeMedium(const XmlElement& e) {
  const RecursionGuard guard(nesting, e.where);
  XmlPlugin p(e, *this);
  const std::string& type = p.type();
  const std::string what = "medium '" + type + "'";
  if (type != "homogeneous" && type != "heterogeneous") {
    static const std::vector<std::string> kKnown = {"homogeneous", "heterogeneous"};
    Warn(e.where, "medium:" + type,
         what + " is not supported: left out (vacuum)" + DidYouMean(type, kKnown));
    return "";
  }
  const std::optional<MediumValue> sigma_t = ValueOf(*this, p, "sigma_t", {1, 1, 1});
  const std::optional<MediumValue> albedo_value = ValueOf(*this, p, "albedo", {0.75, 0.75, 0.75});
  if (!sigma_t || !albedo_value) return "";
  const double scale = p.Float("scale", 1);
  if (!(scale >= 0 && scale < 1e30)) Fail(p.WhereIs("scale"), what + ": scale must be finite and non-negative");
  if (!p.Boolean("sample_emitters", true))
    Warn(p.WhereIs("sample_emitters"), "sample_emitters",
         what + ": sample_emitters false is not supported: emitters are sampled from the medium (the same image, "
                "other noise)");
  p.Accept({"has_spectral_extinction"});

  // A grid where yarf takes a constant: its mean.
  auto constant = [&](const MediumValue& v, const std::string& key) {
    if (!v.IsGrid()) return v.constant;
    Warn(v.where, "medium-grid-mean:" + key,
         what + ": a grid " + key + " where yarf's medium takes a constant: replaced by the grid's mean");
    return VolMean(v.grid, v.where);
  };
  auto albedo = [&](const Rgb& a) {
    return ClampColour(a, 0, 1, [&] {
      Warn(albedo_value->where, "medium-albedo", what + ": albedo clamped into [0, 1]");
    });
  };
  v1::Properties props;
  std::string class_name = "homogeneous";
  std::optional<Matrix4> to_world;
  if (type == "heterogeneous") {
    // A grid of σ_t (or Mitsuba's constant one, which fills its volume's
    // unit cube: a grid of one voxel) times `extinction`.
    class_name = "grid";
    Rgb extinction{1, 1, 1};
    to_world = sigma_t->to_world;
    if (sigma_t->IsGrid()) {
      SetString(props, "filename", folder_.Relative(sigma_t->grid));
    } else {
      extinction = sigma_t->constant;
      if (!(MinOf(extinction) >= 0 && MaxOf(extinction) < 1e30))
        Fail(sigma_t->where, what + ": sigma_t must be finite and non-negative");
      SetFloats(props, "density", {1.0});
      for (const char* axis : {"nx", "ny", "nz"}) SetInt(props, axis, 1);
    }
    if (albedo_value->IsGrid()) {
      // σ_t = scale·d·extinction; σ_s = σ_t·albedo(x).
      SetRgb(props, "sigma_a", {0, 0, 0});
      SetRgb(props, "sigma_s", extinction);
      SetString(props, "albedo_filename", folder_.Relative(albedo_value->grid));
      if (!(albedo_value->to_world == sigma_t->to_world))
        Warn(albedo_value->where, "albedo-placement",
             what + ": the albedo grid is placed as the sigma_t grid (yarf's grid has one to_world)");
    } else {
      const Rgb a = albedo(albedo_value->constant);
      SetRgb(props, "sigma_s", {a.r * extinction.r, a.g * extinction.g, a.b * extinction.b});
      SetRgb(props, "sigma_a",
             {(1 - a.r) * extinction.r, (1 - a.g) * extinction.g, (1 - a.b) * extinction.b});
    }
  } else {
    const Rgb t = constant(*sigma_t, "sigma_t");
    if (!(MinOf(t) >= 0 && MaxOf(t) < 1e30))
      Fail(sigma_t->where, what + ": sigma_t must be finite and non-negative");
    const Rgb a = albedo(constant(*albedo_value, "albedo"));
    const Rgb s{a.r * t.r, a.g * t.g, a.b * t.b};
    SetRgb(props, "sigma_s", s);
    SetRgb(props, "sigma_a", {t.r - s.r, t.g - s.g, t.b - s.b});
  }
  if (scale != 1) SetFloat(props, "scale", scale);
  Phase(*this, p, props);
  p.WarnUnused();
  return assembly_.AddMedium(e.Get("id", "medium"), Spec(class_name, std::move(props)), to_world, e.where);
}

}  // namespace yarf::importers
