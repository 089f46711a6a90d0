// pbrt lights: point and spot lights, area lights on shapes, distant
// lights, uniform infinite lights and image infinite lights.
#include <algorithm>
#include <cmath>

#include "importers/colour_checks.h"
#include "importers/pbrt_importer.h"
#include "importers/properties_util.h"
#include "importers/texture_mean.h"
#include "yarf/support/warps.h"

namespace yarf::importers {
namespace {

// pbrt-v4 divides a light's spectrum by its luminance before "scale":
// RGB values stay as they are, other spectra become unit luminance.
constexpr SpectrumUse kLight = SpectrumUse::kUnitLuminance;

// A point3 parameter, or `fallback` when absent.
Vec3d Point(PbrtParams& params, const std::string& key, Vec3d fallback, const SourceLocation& where) {
  const std::vector<double> v = params.Numbers(key, {"point3"});
  if (v.empty()) return fallback;
  if (v.size() != 3) Fail(params.WhereIs(key, where), "'" + key + "' needs one point");
  return {v[0], v[1], v[2]};
}

}  // namespace

void PbrtImporter::AreaLightSource(const std::string& type, PbrtParams& params, const SourceLocation& where) {
  if (type != "diffuse") {
    Warn(where, "arealight:" + type, "area light '" + type + "' is not supported: ignored");
    return;
  }
  const double scale = params.Float("scale", 1);
  const bool two_sided = params.Bool("twosided", false);
  const double power = params.Float("power", -1);
  if (!std::isfinite(power) || power > 1e30) Fail(params.WhereIs("power", where), "area light power out of range");
  AreaLight light{{}, two_sided, power, where, params.WhereIs("power", where), {}};
  if (params.Has("filename")) {
    // pbrt-v4's image area light: L = scale · image(u, 1 − v), bilinear,
    // the image's RGB as it is; with `power`, normalised by the image's
    // mean luminance in place of L's.
    if (params.Has("L")) Fail(params.WhereIs("L", where), "both \"L\" and \"filename\" given for an area light");
    const SourceLocation file_where = params.WhereIs("filename", where);
    light.image = folder_.Resolve(params.String("filename", ""), origin_.file, file_where);
    const double mean = Luminance(ImageMeanColour(light.image, ImageEncoding::kAuto, 1, file_where));
    if (power > 0 && !(mean > 0)) Fail(light.power_where, "area light: a black image cannot emit a power");
    const double s = power > 0 ? scale / mean : scale;
    light.radiance = {s, s, s};
  } else {
    light.radiance = ClampColour(Colour(params, "L", {1, 1, 1}, kLight, where) * scale, 0, 1e30, [&] {
      Warn(where, "negative-radiance", "negative radiance clamped to 0");
    });
  }
  params.WarnUnused(diagnostics_, "area light 'diffuse'");
  state_.area_light = std::move(light);
}

// pbrt-v4's DiffuseAreaLight::Create: with `power` Φ the radiance is
// multiplied by Φ / (π · (two-sided ? 2 : 1) · A), A the area of the pbrt
// shape the light is made for. pbrt-v4 makes one light per shape, and a
// triangle mesh is a shape per triangle (a bilinear mesh one per patch):
// each triangle emits Φ, its radiance set by its own area. L has been made unit luminance already
// (RGB values stay as given), as pbrt-v4 divides by its luminance first.
Rgb PbrtImporter::AreaLightRadiance(const std::vector<double>& areas, const std::string& shape) {
  const AreaLight& light = *state_.area_light;
  if (!(light.power > 0)) return light.radiance;
  if (areas.empty()) {
    Warn(light.power_where, "light-power", "area light power on " + shape + " is not supported: L and scale used");
    return light.radiance;
  }
  const auto [least, most] = std::minmax_element(areas.begin(), areas.end());
  double area = 0;
  for (double a : areas) area += a;
  area /= double(areas.size());
  if (*most - *least > 1e-4 * *most)
    Warn(light.power_where, "light-power-mesh",
         "area light power: pbrt-v4 gives each triangle (or patch) of " + shape +
             " the power, a radiance for its own area; yarf gives one radiance to the shape: that of the mean "
             "triangle (or patch) area");
  if (!(area > 0)) {
    Warn(light.power_where, "light-power-area", "area light power on " + shape + " of zero area: no emission");
    return {0, 0, 0};
  }
  return light.radiance * (light.power / (M_PI * (light.two_sided ? 2 : 1) * area));
}

void PbrtImporter::LightSource(const std::string& type, PbrtParams& params, const SourceLocation& where) {
  if (type != "point" && type != "spot" && type != "distant" && type != "infinite" && type != "goniometric" &&
      type != "projection") {
    Warn(where, "light:" + type, "LightSource \"" + type + "\" is not supported: ignored");
    return;
  }
  if (!object_.empty()) {
    Warn(where, "instanced-light", "lights inside object definitions are not supported (as in pbrt): ignored");
    return;
  }
  if (type == "distant") return DistantLight(params, where);
  if (type == "infinite") return InfiniteLight(params, where);
  if (type == "goniometric" || type == "projection") return ImageLight(type, params, where);
  Rgb intensity = ClampColour(Colour(params, "I", {1, 1, 1}, kLight, where) * params.Float("scale", 1), 0, 1e30,
                              [&] { Warn(where, "negative-intensity", "negative intensity clamped to 0"); });
  // pbrt-v4's `power` Φ scales I by Φ over the light's solid-angle
  // integral of its falloff: 4π for a point light; for a spot light 2π of
  // (1 − cos start) in full and half of (cos start − cos end) in the
  // falloff (the smoothstep's mean).
  const double power = params.Float("power", -1);
  const auto scale_to_power = [&](double integral) {
    if (power > 0) intensity = intensity * (power / integral);
  };
  const Vec3d from = Point(params, "from", {0, 0, 0}, where);
  v1::Properties props;
  Matrix4 to_world = state_.ctm * Matrix4::Translate(from);
  if (type == "point") scale_to_power(4 * M_PI);
  if (type == "spot") {
    const Vec3d to = Point(params, "to", {0, 0, 1}, where);
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
    const double beam = std::max(cone - delta, 0.0);
    SetFloat(props, "cutoff_angle", cone);
    SetFloat(props, "beam_width", beam);
    SetString(props, "falloff", "smoothstep");
    const double cos_end = std::cos(cone * M_PI / 180), cos_start = std::cos(beam * M_PI / 180);
    scale_to_power(2 * M_PI * ((1 - cos_start) + (cos_start - cos_end) / 2));
  }
  SetRgb(props, "intensity", intensity);
  params.WarnUnused(diagnostics_, "light '" + type + "'");
  v1::Light light;
  *light.mutable_emitter() = Spec(type, std::move(props));
  assembly_.AddLight(std::move(light), to_world, where);
}

// pbrt-v4's GoniometricLight and ProjectionLight, as the goniometric and
// projector emitters (which take the light's frame as to_world too).
void PbrtImporter::ImageLight(const std::string& type, PbrtParams& params, const SourceLocation& where) {
  const double scale = params.Float("scale", 1), power = params.Float("power", -1);
  if (!(scale >= 0) || !std::isfinite(scale)) Fail(params.WhereIs("scale", where), type + " light: scale must be >= 0");
  if (!params.Has("filename")) {
    // pbrt-v4 refuses a projection light without an image and lights a
    // goniometric one nowhere.
    if (type == "projection") Fail(where, "projection light: \"filename\" is required");
    Warn(where, "goniometric-no-image", "goniometric light without \"filename\": it emits nothing: ignored");
    params.WarnUnused(diagnostics_, "light '" + type + "'");
    return;
  }
  const std::string filename = params.String("filename", "");
  const SourceLocation file_where = params.WhereIs("filename", where);
  const auto file = folder_.Resolve(filename, origin_.file, file_where);
  v1::Properties props;
  SetString(props, "filename", folder_.Relative(file));
  Matrix4 frame = state_.ctm;
  double power_scale = 1;
  if (type == "goniometric") {
    const Rgb intensity = ClampColour(Colour(params, "I", {1, 1, 1}, kLight, where), 0, 1e30, [&] {
      Warn(where, "negative-intensity", "negative intensity clamped to 0");
    });
    SetRgb(props, "intensity", intensity);
    // pbrt-v4 turns the map's +z toward the light's +y.
    frame = state_.ctm * Matrix4({1, 0, 0, 0, 0, 0, 1, 0, 0, 1, 0, 0, 0, 0, 0, 1});
    if (power > 0) {
      // Φ = 4π · scale · mean of the texels' channel means.
      const Rgb mean = ImageMeanColour(file, ImageEncoding::kAuto, 1, file_where);
      const double k_e = 4 * M_PI * (mean.r + mean.g + mean.b) / 3;
      if (!(k_e > 0)) Fail(params.WhereIs("power", where), "goniometric light: a black image cannot emit a power");
      power_scale = power / k_e;
    }
  } else {
    const double fov = params.Float("fov", 90);
    if (!(fov > 0 && fov < 180)) Fail(params.WhereIs("fov", where), "projection light: fov must lie in (0, 180)");
    // pbrt-v4: fov spans the image's shorter side; u grows along the
    // light's +x and v along its −y, where the projector's u grows along
    // −x: mirrored in x.
    SetFloat(props, "fov", fov);
    SetString(props, "fov_axis", "smaller");
    SetString(props, "image", "intensity");
    SetString(props, "filter_type", "nearest");
    SetString(props, "wrap_mode", "clamp");
    frame = state_.ctm * Matrix4::Scale({-1, 1, 1});
    if (power > 0) {
      // Φ = scale · A · mean over the texels of luminance × cos³θ, A the
      // image plane's area at unit distance (pbrt-v4's ProjectionLight::Create).
      const double t = std::tan(fov * M_PI / 360);
      const auto cos_cubed = [t](uint64_t x, uint64_t y, uint64_t width, uint64_t height) {
        const double aspect = double(width) / double(height);
        const double sx = (aspect > 1 ? aspect : 1) * (2 * (double(x) + 0.5) / double(width) - 1);
        const double sy = (aspect > 1 ? 1 : 1 / aspect) * (2 * (double(y) + 0.5) / double(height) - 1);
        // The plane's area, 4 t² · max(aspect, 1 / aspect), times cos³θ.
        return 4 * t * t * std::max(aspect, 1 / aspect) * std::pow(1 + t * t * (sx * sx + sy * sy), -1.5);
      };
      const Rgb sum = ImageWeightedSumPerPixel(file, ImageEncoding::kAuto, 1, file_where, cos_cubed);
      const double k_e = Luminance(sum);
      if (!(k_e > 0)) Fail(params.WhereIs("power", where), "projection light: a black image cannot emit a power");
      power_scale = power / k_e;
    }
  }
  SetFloat(props, "scale", scale * power_scale);
  SetTransform(props, "to_world", frame);
  params.WarnUnused(diagnostics_, "light '" + type + "'");
  v1::Light light;
  *light.mutable_emitter() = Spec(type == "goniometric" ? "goniometric" : "projector", std::move(props));
  assembly_.AddLight(std::move(light), frame, where);
}

void PbrtImporter::DistantLight(PbrtParams& params, const SourceLocation& where) {
  Rgb irradiance = Colour(params, "L", {1, 1, 1}, kLight, where) * params.Float("scale", 1);
  // pbrt-v4: the unit-luminance spectrum times the illuminance asked for.
  if (const double illuminance = params.Float("illuminance", -1); illuminance > 0)
    irradiance = irradiance * illuminance;
  irradiance = ClampColour(irradiance, 0, 1e30, [&] {
    Warn(where, "negative-irradiance", "negative irradiance clamped to 0");
  });
  // The light arrives travelling from `from` toward `to`; the transform
  // turns that direction as it turns vectors.
  const Vec3d from = Point(params, "from", {0, 0, 0}, where), to = Point(params, "to", {0, 0, 1}, where);
  if (!Normalized(to - from)) Fail(where, "distant light: 'from' equals 'to'");
  params.WarnUnused(diagnostics_, "light 'distant'");
  assembly_.AddDirectionalLight("", irradiance, state_.ctm.Vector(to - from), where);
}

void PbrtImporter::InfiniteLight(PbrtParams& params, const SourceLocation& where) {
  const double scale = params.Float("scale", 1), illuminance = params.Float("illuminance", -1);
  if (!(scale >= 0) || !std::isfinite(scale)) Fail(params.WhereIs("scale", where), "infinite light: scale must be >= 0");
  using Added = SceneAssembly::EnvironmentAdded;
  Added added = Added::kAdded;
  if (params.Has("filename")) {
    if (params.Has("L")) Fail(params.WhereIs("L", where), "infinite light: give \"L\" or \"filename\", not both");
    // pbrt-v4's maps are square, in its equal-area octahedral mapping.
    const std::string filename = params.String("filename", "");
    const auto file = folder_.Resolve(filename, origin_.file, params.WhereIs("filename", where));
    double map_scale = scale;
    if (illuminance > 0) {
      // The illuminance the map gives a point facing +z (the map's up):
      // each of its N texels stands for 4π / N sr, so E = 4π / N · Σ over
      // the texels above the horizon of luminance × cos θ. pbrt-v4's
      // ImageInfiniteLight::Create sums the same but with 2π / N, which
      // makes the illuminance it renders twice that asked for; this is
      // the illuminance asked for, as pbrt-v4's uniform infinite light
      // (E / π for a constant map) and distant light give it.
      const auto up_cosine = [](uint64_t x, uint64_t y, uint64_t width, uint64_t height) {
        const Vec3 w = EqualAreaSquareToSphere(float((double(x) + 0.5) / double(width)),
                                               float((double(y) + 0.5) / double(height)));
        return std::max(0.0, double(w.z));
      };
      const Rgb sum = ImageWeightedSumPerPixel(file, ImageEncoding::kAuto, 1, params.WhereIs("filename", where),
                                               up_cosine);
      const double map_illuminance = 4 * M_PI * Luminance(sum);
      if (!(map_illuminance > 0))
        Fail(params.WhereIs("illuminance", where), "infinite light: the map is black above the horizon: it cannot "
                                                   "give an illuminance");
      map_scale = scale * illuminance / map_illuminance;
    }
    params.Accept({"portal"});
    if (params.Has("portal"))
      Warn(params.WhereIs("portal", where), "infinite-portal", "infinite light: portals are not supported: ignored");
    v1::Properties props;
    SetString(props, "filename", folder_.Relative(file));
    SetFloat(props, "scale", map_scale);
    SetString(props, "mapping", "equal_area");
    params.WarnUnused(diagnostics_, "light 'infinite'");
    added = assembly_.AddEnvironmentMap("", std::move(props), state_.ctm, where);
  } else {
    Rgb radiance = Colour(params, "L", {1, 1, 1}, kLight, where) * scale;
    // pbrt-v4: a uniform unit-luminance sky gives illuminance π.
    if (illuminance > 0) radiance = radiance * (illuminance / M_PI);
    radiance =
        ClampColour(radiance, 0, 1e30, [&] { Warn(where, "negative-radiance", "negative radiance clamped to 0"); });
    params.WarnUnused(diagnostics_, "light 'infinite'");
    added = assembly_.AddUniformEnvironment("", radiance);
  }
  if (added == Added::kIgnored)
    Warn(where, "second-infinite", "infinite light: yarf renders one environment map per scene: this one ignored");
  if (added == Added::kReplacedUniform)
    Warn(where, "infinite-replaces-uniform",
         "infinite light: yarf renders one environment per scene: this map replaces the uniform one before it");
}

}  // namespace yarf::importers
