// Mitsuba emitters: area lights on shapes, point, spot and projector
// lights, directional lights, uniform environments and environment maps.
#include <cmath>
#include <string>

#include "importers/colour_checks.h"
#include "importers/numbers.h"
#include "importers/properties_util.h"
#include "importers/xml_importer.h"

namespace yarf::importers {
namespace {

// Mitsuba's `projector`: a point light projecting its `irradiance` (a
// bitmap, or a constant) through a perspective frustum. The plugin takes
// to_world too, for the frustum's x and y (a point light's Light keeps
// only its axis). Known gap: that copy is not mirrored with the world
// (SceneAssembly::Finish mirrors only Light.to_world, for a sensor whose
// to_world mirrors), so a projector in such a scene aims wrongly.
v1::ComponentSpec Projector(MitsubaImporter& importer, XmlPlugin& p, const Matrix4& to_world) {
  const XmlElement& e = p.element();
  v1::Properties props;
  const XmlElement* irradiance = nullptr;
  for (const XmlElement& child : e.children) {
    if (child.Get("name") != "irradiance") continue;
    irradiance = child.tag == "ref" ? &importer.Lookup(child.Required("id"), child.where) : &child;
  }
  if (!irradiance) Fail(e.where, "projector: give the image to project as an 'irradiance' bitmap texture");
  if (irradiance->tag == "texture") {
    if (irradiance->Get("type") != "bitmap")
      Fail(irradiance->where, "projector: 'irradiance' must be a bitmap texture or a constant, not a '" +
                                  irradiance->Get("type") + "' texture");
    p.Accept({"irradiance"});
    XmlPlugin bitmap(*irradiance, importer);
    if (!bitmap.Has("filename")) Fail(irradiance->where, "projector: the irradiance bitmap needs a filename");
    const auto file =
        importer.folder().Resolve(bitmap.String("filename", ""), irradiance->file, bitmap.WhereIs("filename"));
    SetString(props, "filename", importer.folder().Relative(file));
    if (bitmap.Has("raw")) SetBool(props, "raw", bitmap.Boolean("raw", false));
    if (bitmap.Has("filter_type")) {
      const std::string filter = bitmap.String("filter_type", "bilinear");
      if (filter != "bilinear" && filter != "nearest")
        Fail(bitmap.WhereIs("filter_type"), "projector: filter_type must be bilinear or nearest, not '" + filter + "'");
      SetString(props, "filter_type", filter);
    }
    if (bitmap.Has("wrap_mode")) {
      const std::string wrap = bitmap.String("wrap_mode", "repeat");
      if (wrap != "repeat" && wrap != "mirror" && wrap != "clamp")
        Fail(bitmap.WhereIs("wrap_mode"), "projector: wrap_mode must be repeat, mirror or clamp, not '" + wrap + "'");
      SetString(props, "wrap_mode", wrap);
    }
    if (bitmap.Has("to_uv")) Fail(bitmap.WhereIs("to_uv"), "projector: an irradiance bitmap's to_uv is not supported");
    bitmap.Accept({"format"});
    bitmap.WarnUnused();
  } else {
    const Rgb constant = ClampColour(p.Color("irradiance", {1, 1, 1}), 0, 1e30, [&] {
      importer.Warn(p.WhereIs("irradiance"), "negative-irradiance", "projector: negative irradiance clamped to 0");
    });
    SetRgb(props, "irradiance", constant);
  }
  const double scale = p.Float("scale", 1);
  if (!(scale >= 0) || !std::isfinite(scale)) Fail(p.WhereIs("scale"), "projector: scale must be finite and >= 0");
  SetFloat(props, "scale", scale);
  // fov along fov_axis, or a 35 mm focal length (which spans the diagonal).
  if (p.Has("fov") && p.Has("focal_length")) Fail(e.where, "projector: give fov or focal_length, not both");
  std::string axis = p.String("fov_axis", "x");
  double fov = 0;
  if (p.Has("fov")) {
    fov = p.Float("fov", 0);
  } else {
    std::string focal = p.String("focal_length", "50mm");
    if (focal.size() > 2 && focal.substr(focal.size() - 2) == "mm") focal.resize(focal.size() - 2);
    const auto f = ParseDouble(focal);
    if (!f || !(*f > 0))
      Fail(p.WhereIs("focal_length"), "projector: focal_length must be a positive length like \"50mm\"");
    fov = 2 * std::atan(std::hypot(36.0, 24.0) / (2 * *f)) * 180 / 3.14159265358979323846;
    axis = "diagonal";
  }
  if (!(fov > 0 && fov < 180)) Fail(p.WhereIs("fov"), "projector: fov must lie in (0, 180) degrees");
  if (axis != "x" && axis != "y" && axis != "diagonal" && axis != "smaller" && axis != "larger")
    Fail(p.WhereIs("fov_axis"), "projector: fov_axis must be x, y, smaller, larger or diagonal, not '" + axis + "'");
  SetFloat(props, "fov", fov);
  SetString(props, "fov_axis", axis);
  SetTransform(props, "to_world", to_world);
  p.Accept({"sampling_weight"});
  p.WarnUnused();
  return Spec("projector", std::move(props));
}

}  // namespace

v1::ComponentSpec MitsubaImporter::AreaEmitter(const XmlElement& e) {
  XmlPlugin p(e, *this);
  p.Objects("medium");  // where a light sits: yarf follows media from the camera
  Textured radiance = p.TexturedColor("radiance", {1, 1, 1});
  if (!radiance.IsTexture())
    radiance.constant = ClampColour(radiance.constant, 0, 1e30, [&] {
      Warn(p.WhereIs("radiance"), "negative-radiance", "area emitter: negative radiance (out of gamut) clamped to 0");
    });
  p.Accept({"sampling_weight"});
  p.WarnUnused();
  v1::Properties props;
  SetColour(props, "radiance", radiance);
  return Spec("diffuse_area", std::move(props));
}

void MitsubaImporter::Emitter(const XmlElement& e) {
  XmlPlugin p(e, *this);
  p.Objects("medium");  // where a light sits: yarf follows media from the camera
  const std::string& type = p.type();
  if (type == "point" || type == "spot") {
    const Rgb intensity = ClampColour(p.Color("intensity", {1, 1, 1}), 0, 1e30, [&] {
      Warn(p.WhereIs("intensity"), "negative-intensity", type + " light: negative intensity clamped to 0");
    });
    v1::Properties props;
    SetRgb(props, "intensity", intensity);
    Matrix4 to_world = p.Transform("to_world");
    if (p.Has("position")) {
      if (p.Has("to_world")) Fail(e.where, "give a point light position or to_world, not both");
      to_world = Matrix4::Translate(p.Point("position", {0, 0, 0}));
    }
    if (type == "spot") {
      double cutoff = p.Float("cutoff_angle", 20);
      double beam = p.Float("beam_width", cutoff * 0.75);
      if (!(cutoff > 0) || !(beam > 0)) Fail(e.where, "spot light angles must be positive");
      if (cutoff > 90) {
        Warn(p.WhereIs("cutoff_angle"), "spot-cutoff", "spot light cutoff_angle above 90 degrees clamped to 90");
        cutoff = 90;
      }
      beam = std::min(beam, cutoff);
      SetFloat(props, "cutoff_angle", cutoff);
      SetFloat(props, "beam_width", beam);
      if (p.Has("texture")) {
        p.Color("texture", {1, 1, 1});
        Warn(p.WhereIs("texture"), "spot-texture", "spot light textures are not supported: ignored");
      }
    }
    p.Accept({"sampling_weight"});
    p.WarnUnused();
    v1::Light light;
    light.set_name(e.Get("id"));
    *light.mutable_emitter() = Spec(type, std::move(props));
    assembly_.AddLight(std::move(light), to_world, e.where);
    return;
  }
  if (type == "projector") {
    v1::Light light;
    light.set_name(e.Get("id"));
    const Matrix4 to_world = p.Transform("to_world");
    *light.mutable_emitter() = Projector(*this, p, to_world);
    assembly_.AddLight(std::move(light), to_world, e.where);
    return;
  }
  if (type == "directional") {
    const Rgb irradiance = ClampColour(p.Color("irradiance", {1, 1, 1}), 0, 1e30, [&] {
      Warn(p.WhereIs("irradiance"), "negative-irradiance", "directional light: negative irradiance clamped to 0");
    });
    // The light travels along its frame's +z, or along `direction`.
    Vec3d direction = p.Transform("to_world").Vector({0, 0, 1});
    if (p.Has("direction")) {
      if (p.Has("to_world")) Fail(e.where, "give a directional light direction or to_world, not both");
      direction = p.Point("direction", {0, 0, 1});
    }
    p.Accept({"sampling_weight"});
    p.WarnUnused();
    assembly_.AddDirectionalLight(e.Get("id"), irradiance, direction, e.where);
    return;
  }
  if (type == "constant" || type == "envmap") {
    if (assembly_.HasEnvironment()) Fail(e.where, "only one environment emitter can be specified per scene");
    p.Accept({"sampling_weight"});
    if (type == "constant") {
      const Rgb radiance = ClampColour(p.Color("radiance", {1, 1, 1}), 0, 1e30, [&] {
        Warn(p.WhereIs("radiance"), "negative-radiance", "constant emitter: negative radiance clamped to 0");
      });
      p.WarnUnused();
      assembly_.AddUniformEnvironment(e.Get("id"), radiance);
      return;
    }
    if (!p.Has("filename")) Fail(e.where, "envmap needs a filename");
    const auto file = folder_.Resolve(p.String("filename", ""), e.file, p.WhereIs("filename"));
    const double scale = p.Float("scale", 1);
    if (!(scale >= 0) || !std::isfinite(scale)) Fail(p.WhereIs("scale"), "envmap: scale must be finite and >= 0");
    if (p.Has("filter_type") && p.String("filter_type", "bilinear") != "bilinear")
      Warn(p.WhereIs("filter_type"), "envmap-filter", "envmap: only bilinear lookups are supported: bilinear used");
    p.Accept({"mis_compensation"});
    v1::Properties props;
    SetString(props, "filename", folder_.Relative(file));
    SetFloat(props, "scale", scale);
    SetString(props, "mapping", "latlong");
    const Matrix4 to_world = p.Transform("to_world");
    p.WarnUnused();
    assembly_.AddEnvironmentMap(e.Get("id"), std::move(props), to_world, e.where);
    return;
  }
  if (type == "sunsky" || type == "sky" || type == "sun" || type == "skysphere") {
    Warn(e.where, "environment:" + type, "sun and sky models are not supported: emitter '" + type + "' ignored");
    return;
  }
  Warn(e.where, "emitter:" + type, "emitter '" + type + "' is not supported: ignored");
}

}  // namespace yarf::importers
