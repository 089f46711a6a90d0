// Mitsuba emitters: area lights on shapes, point and spot lights,
// directional lights, uniform environments and environment maps.
#include "importers/colour_checks.h"
#include "importers/properties_util.h"
#include "importers/xml_importer.h"

namespace yarf::importers {

v1::ComponentSpec MitsubaImporter::AreaEmitter(const XmlElement& e) {
  XmlPlugin p(e, *this);
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
    Warn(e.where, "environment:" + type, "environment maps are not supported yet: emitter '" + type + "' ignored");
    return;
  }
  Warn(e.where, "emitter:" + type, "emitter '" + type + "' is not supported: ignored");
}

}  // namespace yarf::importers
