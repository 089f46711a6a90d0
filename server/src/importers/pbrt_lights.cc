// pbrt lights: point and spot lights, area lights on shapes; infinite and
// distant lights yarf has not yet.
#include <cmath>

#include "importers/colour_checks.h"
#include "importers/pbrt_importer.h"
#include "importers/properties_util.h"

namespace yarf::importers {
namespace {

// pbrt-v4 divides a light's spectrum by its luminance before "scale":
// RGB values stay as they are, other spectra become unit luminance.
constexpr SpectrumUse kLight = SpectrumUse::kUnitLuminance;

}  // namespace

void PbrtImporter::AreaLightSource(const std::string& type, PbrtParams& params, const SourceLocation& where) {
  if (type != "diffuse") {
    Warn(where, "arealight:" + type, "area light '" + type + "' is not supported: ignored");
    return;
  }
  const Rgb radiance = Colour(params, "L", {1, 1, 1}, kLight, where) * params.Float("scale", 1);
  if (params.Bool("twosided", false))
    Warn(params.WhereIs("twosided", where), "twosided-light",
         "two-sided area lights are not supported: they emit from the front (normal) side only");
  if (params.Has("power")) {
    params.Find("power");
    Warn(params.WhereIs("power", where), "light-power", "light power is not supported: L and scale used");
  }
  if (params.Has("filename")) {
    params.Find("filename");
    Warn(params.WhereIs("filename", where), "arealight-image", "image area lights are not supported: L used");
  }
  params.WarnUnused(diagnostics_, "area light 'diffuse'");
  state_.area_light = AreaLight{ClampColour(radiance, 0, 1e30, [&] {
                                  Warn(where, "negative-radiance", "negative radiance clamped to 0");
                                }),
                                where};
}

void PbrtImporter::LightSource(const std::string& type, PbrtParams& params, const SourceLocation& where) {
  if (type == "distant" || type == "infinite" || type == "goniometric" || type == "projection") {
    Warn(where, "light:" + type,
         std::string(type == "distant" || type == "infinite" ? "yarf has no infinite lights yet: "
                                                             : "unsupported light: ") +
             "LightSource \"" + type + "\" ignored");
    return;
  }
  if (type != "point" && type != "spot") {
    Warn(where, "light:" + type, "LightSource \"" + type + "\" is not supported: ignored");
    return;
  }
  if (!object_.empty()) {
    Warn(where, "instanced-light", "lights inside object definitions are not supported (as in pbrt): ignored");
    return;
  }
  const Rgb intensity = ClampColour(Colour(params, "I", {1, 1, 1}, kLight, where) * params.Float("scale", 1), 0,
                                    1e30, [&] { Warn(where, "negative-intensity", "negative intensity clamped to 0"); });
  if (params.Has("power")) {
    params.Find("power");
    Warn(params.WhereIs("power", where), "light-power", "light power is not supported: I and scale used");
  }
  const auto read = [&](const std::string& key, Vec3d fallback) {
    const std::vector<double> v = params.Numbers(key, {"point3"});
    if (v.empty()) return fallback;
    if (v.size() != 3) Fail(params.WhereIs(key, where), "'" + key + "' needs one point");
    return Vec3d{v[0], v[1], v[2]};
  };
  const Vec3d from = read("from", {0, 0, 0});
  v1::Properties props;
  SetRgb(props, "intensity", intensity);
  Matrix4 to_world = state_.ctm * Matrix4::Translate(from);
  if (type == "spot") {
    const Vec3d to = read("to", {0, 0, 1});
    const auto dir = Normalized(to - from);
    if (!dir) Fail(where, "spot light: 'from' equals 'to'");
    // Any frame whose z axis points from `from` to `to`.
    const Vec3d up = std::abs(dir->y) < 0.9 ? Vec3d{0, 1, 0} : Vec3d{1, 0, 0};
    to_world = state_.ctm * *Matrix4::LookAt(from, to, up);
    double cone = params.Float("coneangle", 30), delta = params.Float("conedelta", 5);
    if (!(cone > 0 && cone < 180) || !(delta >= 0 && delta < 180)) Fail(where, "spot light angles out of range");
    if (cone > 90) {
      Warn(params.WhereIs("coneangle", where), "spot-cone", "spot light coneangle above 90 degrees clamped to 90");
      cone = 90;
    }
    SetFloat(props, "cutoff_angle", cone);
    SetFloat(props, "beam_width", std::max(cone - delta, cone * 1e-3));
    Warn(where, "spot-falloff", "spot light falloff is linear in angle in yarf (pbrt's is smooth in cosine)");
  }
  params.WarnUnused(diagnostics_, "light '" + type + "'");
  v1::Light light;
  *light.mutable_emitter() = Spec(type, std::move(props));
  assembly_.AddLight(std::move(light), to_world, where);
}

}  // namespace yarf::importers
