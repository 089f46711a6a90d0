// pbrt-v4's participating media (MakeNamedMedium) as yarf Medium classes,
// and the media shapes and the camera sit between (MediumInterface).
//
// homogeneous → homogeneous; uniformgrid and rgbgrid → grid (their voxels
// inline), its unit cube placed on the box [p0, p1] by the CTM at
// MakeNamedMedium; cloud → cloud with pbrt's parameters; nanovdb files
// cannot be read: left out.
#include <algorithm>
#include <cmath>

#include "importers/colour_checks.h"
#include "importers/measured_media.h"
#include "importers/pbrt_importer.h"
#include "importers/properties_util.h"

namespace yarf::importers {
namespace {

// Voxels of an inline grid at most (a grid of 1024³ is 4 GiB as floats).
constexpr int64_t kMaxVoxels = int64_t(1) << 28;

double MaxOf(const Rgb& c) { return std::max({c.r, c.g, c.b}); }
double MinOf(const Rgb& c) { return std::min({c.r, c.g, c.b}); }

Vec3d Point(PbrtParams& params, const std::string& key, Vec3d fallback, const SourceLocation& where) {
  const std::vector<double> v = params.Numbers(key, {"point3"});
  if (v.empty()) return fallback;
  if (v.size() != 3) Fail(params.WhereIs(key, where), "'" + key + "' needs one point");
  return {v[0], v[1], v[2]};
}

// The grid's resolution (nx, ny, nz), which must hold `count` voxels.
int64_t Resolution(PbrtParams& params, v1::Properties& props, size_t count, const std::string& what,
                   const SourceLocation& where) {
  int64_t voxels = 1;
  for (const char* axis : {"nx", "ny", "nz"}) {
    const int64_t n = params.Integer(axis, 1);
    if (n < 1 || n > kMaxVoxels) Fail(params.WhereIs(axis, where), what + ": " + axis + " must be at least 1");
    voxels *= n;
    if (voxels > kMaxVoxels) Fail(where, what + ": more than 2^28 voxels");
    SetInt(props, axis, n);
  }
  if (int64_t(count) != voxels)
    Fail(where, what + ": " + std::to_string(count) + " voxel values given; nx*ny*nz = " + std::to_string(voxels));
  return voxels;
}

void CheckVoxels(const std::vector<double>& values, const std::string& what, const SourceLocation& where) {
  for (double v : values)
    if (!(v >= 0 && v < 1e30)) Fail(where, what + " must be finite and non-negative");
}

}  // namespace

void PbrtImporter::MakeNamedMedium(const std::string& name, PbrtParams& params, const SourceLocation& where) {
  if (name.empty()) Fail(where, "MakeNamedMedium needs a name (\"\" is vacuum)");
  if (media_.count(name)) Fail(where, "named medium '" + name + "' defined twice");
  media_[name] = "";  // left out unless made below
  const std::string type = params.String("type", "");
  if (type.empty()) Fail(where, "MakeNamedMedium \"" + name + "\" needs a \"string type\"");
  const std::string what = "medium '" + type + "'";
  v1::Properties props;

  // σ_a and σ_s per unit length, 1 by default as in pbrt-v4.
  auto coefficient = [&](const std::string& key) {
    const Rgb c = Colour(params, key, {1, 1, 1}, SpectrumUse::kReflectance, where);
    if (!(MinOf(c) >= 0 && MaxOf(c) < 1e30))
      Fail(params.WhereIs(key, where), what + ": " + key + " must be finite and non-negative");
    SetRgb(props, key, c);
  };
  auto scale = [&] {
    const double s = params.Float("scale", 1);
    if (!(s >= 0 && s < 1e30)) Fail(params.WhereIs("scale", where), what + ": scale must be finite and non-negative");
    if (s != 1) SetFloat(props, "scale", s);
  };
  auto phase = [&] {
    const double g = params.Float("g", 0);
    if (!(g > -1 && g < 1)) Fail(params.WhereIs("g", where), what + ": g must lie in (-1, 1)");
    if (g != 0) SetFloat(props, "g", g);
  };
  // pbrt-v4's Le, divided by its luminance unless it is RGB (as lights'
  // spectra), times Lescale: yarf's emission.
  auto emission = [&](double le_scale) {
    const Rgb le = Colour(params, "Le", {0, 0, 0}, SpectrumUse::kUnitLuminance, where) * le_scale;
    const Rgb clamped = ClampColour(le, 0, 1e30, [&] {
      Warn(params.WhereIs("Le", where), "medium-negative-Le", what + ": negative Le clamped to 0");
    });
    if (MaxOf(clamped) > 0) SetRgb(props, "emission", clamped);
  };
  // The unit cube's to_world: the box [p0, p1] of the medium's space, placed by the CTM.
  auto box = [&] {
    const Vec3d p0 = Point(params, "p0", {0, 0, 0}, where), p1 = Point(params, "p1", {1, 1, 1}, where);
    const Vec3d lo{std::min(p0.x, p1.x), std::min(p0.y, p1.y), std::min(p0.z, p1.z)};
    const Vec3d hi{std::max(p0.x, p1.x), std::max(p0.y, p1.y), std::max(p0.z, p1.z)};
    if (!(hi.x > lo.x && hi.y > lo.y && hi.z > lo.z))
      Fail(params.WhereIs("p0", where), what + ": p0 and p1 must bound a box of nonzero volume");
    return state_.ctm * Matrix4::Translate(lo) * Matrix4::Scale(hi - lo);
  };

  std::string class_name;
  std::optional<Matrix4> to_world;
  if (type == "homogeneous") {
    class_name = "homogeneous";
    if (const std::string preset = params.String("preset", ""); !preset.empty()) {
      if (const auto measured = PbrtMeasuredMedium(preset)) {
        // As pbrt-v4: the preset replaces σ_a and σ_s (in mm⁻¹; "scale"
        // converts to the scene's units).
        SetRgb(props, "sigma_a", measured->sigma_a);
        SetRgb(props, "sigma_s", measured->sigma_prime_s);
      } else {
        Warn(params.WhereIs("preset", where), "medium-preset:" + preset,
             what + ": preset \"" + preset + "\" is not one of pbrt-v4's measured media: sigma_a and sigma_s used" +
                 DidYouMean(preset, PbrtMeasuredMediumNames()));
      }
    }
    if (!props.values().count("sigma_a")) coefficient("sigma_a"), coefficient("sigma_s");
    scale();
    phase();
    emission(params.Float("Lescale", 1));
  } else if (type == "uniformgrid") {
    // σ_a and σ_s scaled by a density grid.
    class_name = "grid";
    to_world = box();
    SetString(props, "edge", "zero");  // pbrt-v4's grids fade to 0 past their outer voxel centres
    const std::vector<double> density = params.Numbers("density", {"float"});
    if (density.empty()) Fail(where, what + " needs \"float density\" values");
    CheckVoxels(density, what + ": density", params.WhereIs("density", where));
    const int64_t voxels = Resolution(params, props, density.size(), what, where);
    SetFloats(props, "density", density);
    coefficient("sigma_a");
    coefficient("sigma_s");
    scale();
    phase();
    // Le, scaled per voxel by a Lescale grid when given; blackbody
    // emission by a temperature grid yarf has not.
    const std::vector<double> le_scale = params.Numbers("Lescale", {"float"});
    if (!le_scale.empty() && int64_t(le_scale.size()) != voxels)
      Fail(params.WhereIs("Lescale", where), what + ": Lescale needs nx*ny*nz values");
    CheckVoxels(le_scale, what + ": Lescale", params.WhereIs("Lescale", where));
    if (params.Has("temperature")) {
      params.Accept({"temperature", "temperatureoffset", "temperaturecutoff", "temperaturescale", "Le", "Lescale"});
      Warn(params.WhereIs("temperature", where), "medium-temperature",
           what + ": temperature grids (blackbody emission) are not supported: the medium does not emit");
    } else if (le_scale.size() > 1) {
      emission(1);
      const auto le = props.values().find("emission");
      if (le != props.values().end()) {
        const v1::Rgb c = le->second.rgb_value();
        std::vector<double> voxels_le;
        voxels_le.reserve(3 * le_scale.size());
        for (double k : le_scale) voxels_le.insert(voxels_le.end(), {c.r() * k, c.g() * k, c.b() * k});
        SetFloats(props, "emission", voxels_le);
      }
    } else {
      emission(le_scale.empty() ? 1 : le_scale.front());
    }
  } else if (type == "rgbgrid") {
    // σ_a and σ_s grids of their own (1 where not given, as pbrt-v4).
    class_name = "grid";
    to_world = box();
    SetString(props, "edge", "zero");
    const std::vector<double> sigma_a = params.Numbers("sigma_a", {"rgb"});
    const std::vector<double> sigma_s = params.Numbers("sigma_s", {"rgb"});
    if (sigma_a.empty() && sigma_s.empty()) Fail(where, what + " needs \"rgb sigma_a\" or \"rgb sigma_s\" values");
    CheckVoxels(sigma_a, what + ": sigma_a", params.WhereIs("sigma_a", where));
    CheckVoxels(sigma_s, what + ": sigma_s", params.WhereIs("sigma_s", where));
    if (sigma_a.size() % 3 != 0 || sigma_s.size() % 3 != 0 ||
        (!sigma_a.empty() && !sigma_s.empty() && sigma_a.size() != sigma_s.size()))
      Fail(where, what + ": sigma_a and sigma_s need one rgb per voxel each");
    const size_t voxels = std::max(sigma_a.size(), sigma_s.size()) / 3;
    Resolution(params, props, voxels, what, where);
    for (const auto& [key, values] : {std::pair{"sigma_a", &sigma_a}, {"sigma_s", &sigma_s}}) {
      if (values->empty())
        SetRgb(props, key, {1, 1, 1});
      else
        SetFloats(props, key, *values);
    }
    scale();
    phase();
    // Le per voxel, times Lescale; pbrt-v4 emits only where sigma_a is given.
    if (params.Has("Le")) {
      std::vector<double> le = params.Numbers("Le", {"rgb"});
      if (le.size() != 3 * voxels) Fail(params.WhereIs("Le", where), what + ": Le needs one rgb per voxel");
      if (sigma_a.empty()) Fail(params.WhereIs("Le", where), what + ": Le needs sigma_a");
      CheckVoxels(le, what + ": Le", params.WhereIs("Le", where));
      const double le_scale = params.Float("Lescale", 1);
      if (!(le_scale >= 0 && le_scale < 1e30))
        Fail(params.WhereIs("Lescale", where), what + ": Lescale must be finite and non-negative");
      for (double& v : le) v *= le_scale;
      SetFloats(props, "emission", le);
    }
  } else if (type == "cloud") {
    // pbrt-v4's procedural cloud, its parameters (and defaults) as pbrt's
    // (scale as its earlier CuboidMedium read it); to_world places the
    // medium's space.
    class_name = "cloud";
    to_world = state_.ctm;
    for (const auto& [key, fallback] : {std::pair{"density", 1.0}, {"wispiness", 1.0}, {"frequency", 5.0}})
      SetFloat(props, key, params.Float(key, fallback));
    coefficient("sigma_a");
    coefficient("sigma_s");
    scale();
    phase();
    SetVec3(props, "p0", Point(params, "p0", {0, 0, 0}, where));
    SetVec3(props, "p1", Point(params, "p1", {1, 1, 1}, where));
  } else if (type == "nanovdb") {
    params.Accept({"filename", "gridname", "temperaturename", "Lescale", "temperatureoffset", "temperaturecutoff",
                   "temperaturescale", "g", "sigma_a", "sigma_s", "scale"});
    Warn(where, "nanovdb",
         "medium '" + name + "': NanoVDB files (.nvdb) cannot be read (yarf's grid reads OpenVDB .vdb and "
         "Mitsuba .vol files; convert it with nanovdb_convert): the medium is left out, and shapes bounding it "
         "see vacuum");
    return;
  } else {
    static const std::vector<std::string> kKnown = {"homogeneous", "uniformgrid", "rgbgrid", "cloud", "nanovdb"};
    params.Accept({"type"});
    Warn(where, "medium:" + type,
         "medium type '" + type + "' is not supported: medium '" + name + "' is left out (vacuum)" +
             DidYouMean(type, kKnown));
    return;
  }
  params.Accept({"type"});
  params.WarnUnused(diagnostics_, what);
  media_[name] = assembly_.AddMedium(name, Spec(class_name, std::move(props)), to_world, where);
}

void PbrtImporter::SetMedia(v1::SceneShape& shape) {
  // pbrt-v4: a surface with the same medium on both sides is no
  // transition; rays keep the medium they are in. A subsurface material
  // encloses its own, unless the MediumInterface names another inside.
  const auto subsurface = subsurface_media_.find(shape.material());
  if (subsurface != subsurface_media_.end() && state_.inside_medium == state_.outside_medium) {
    shape.set_interior(subsurface->second);
    shape.set_exterior(state_.outside_medium);
    if (!state_.outside_medium.empty()) medium_uses_.emplace_back(state_.outside_medium, state_.medium_where);
    return;
  }
  if (state_.inside_medium == state_.outside_medium) return;
  shape.set_interior(state_.inside_medium);
  shape.set_exterior(state_.outside_medium);
  for (const std::string* medium : {&state_.inside_medium, &state_.outside_medium})
    if (!medium->empty()) medium_uses_.emplace_back(*medium, state_.medium_where);
}

void PbrtImporter::ResolveMedia() {
  std::vector<std::string> known;
  for (const auto& [name, made] : media_) known.push_back(name);
  for (const auto& [name, where] : medium_uses_)
    if (!media_.count(name)) Fail(where, "medium '" + name + "' is not defined" + DidYouMean(name, known));
  // A medium left out is vacuum.
  const auto made = [&](const std::string& name) { return name.empty() ? name : media_.at(name); };
  const auto resolve = [&](google::protobuf::RepeatedPtrField<v1::SceneShape>& shapes) {
    for (v1::SceneShape& shape : shapes) {
      shape.set_interior(made(shape.interior()));
      shape.set_exterior(made(shape.exterior()));
    }
  };
  v1::Scene& scene = assembly_.scene();
  resolve(*scene.mutable_shapes());
  for (v1::Group& group : *scene.mutable_groups()) resolve(*group.mutable_shapes());
  scene.set_camera_medium(made(scene.camera_medium()));
}

void PbrtImporter::ChooseVolumetricTransport() {
  if (!assembly_.HasMedia()) return;
  if (integrator_type_ == "volpath") {
    v1::ComponentSpec& transport = *assembly_.scene().mutable_transport();
    transport.set_class_name("volpath");
    // pbrt's subsurface scattering is one bounce of its paths, however
    // often the light scatters under the surface: the walks through the
    // media that stand for it are bounded apart (roulette ends them).
    if (!subsurface_media_.empty()) SetInt(*transport.mutable_properties(), "max_medium_depth", -1);
  } else {
    Warn(integrator_where_, "integrator-media",
         "integrator '" + integrator_type_ +
             "' does not render participating media: they are ignored (pbrt's \"volpath\" renders them)");
  }
}

}  // namespace yarf::importers
