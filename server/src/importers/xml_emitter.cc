// Mitsuba emitters: area lights on shapes, point and spot lights; the
// infinite ones yarf has not yet.
#include "importers/colour_checks.h"
#include "importers/properties_util.h"
#include "importers/xml_importer.h"

namespace yarf::importers {

v1::ComponentSpec MitsubaImporter::AreaEmitter(const XmlElement& e) {
  XmlPlugin p(e, *this);
  const Rgb radiance = ClampColour(p.Color("radiance", {1, 1, 1}), 0, 1e30, [&] {
    Warn(p.WhereIs("radiance"), "negative-radiance", "area emitter: negative radiance (out of gamut) clamped to 0");
  });
  p.Accept({"sampling_weight"});
  p.WarnUnused();
  v1::Properties props;
  SetRgb(props, "radiance", radiance);
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
  if (type == "constant" || type == "envmap" || type == "directional" || type == "sunsky" || type == "sky" ||
      type == "sun" || type == "skysphere") {
    Warn(e.where, "infinite:" + type, "yarf has no infinite lights yet: emitter '" + type + "' ignored");
    return;
  }
  Warn(e.where, "emitter:" + type, "emitter '" + type + "' is not supported: ignored");
}

}  // namespace yarf::importers
