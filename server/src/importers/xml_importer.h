// The Mitsuba 3 importer's state, shared by the files that map each kind
// of plugin (xml_sensor.cc, xml_bsdf.cc, xml_shape.cc, xml_emitter.cc,
// xml_texture.cc, xml_medium.cc).
#pragma once

#include <map>
#include <set>
#include <string>

#include "importers/diagnostics.h"
#include "importers/import.h"
#include "importers/recursion_guard.h"
#include "importers/scene_assembly.h"
#include "importers/scene_folder.h"
#include "importers/xml_document.h"
#include "importers/xml_plugin.h"

namespace yarf::importers {

class MitsubaImporter {
 public:
  MitsubaImporter(const SceneFolder& folder, Diagnostics& diagnostics)
      : folder_(folder), diagnostics_(diagnostics) {}

  ImportResult Run(const XmlElement& scene);

  // The element an id names (through aliases); fails at `where` when none.
  const XmlElement& Lookup(const std::string& id, const SourceLocation& where) const;
  void Warn(const SourceLocation& where, const std::string& key, const std::string& message) {
    diagnostics_.Warn(where, key, message);
  }
  const SceneFolder& folder() const { return folder_; }

  // xml_texture.cc: what a textured or spectral value becomes. A texture
  // yarf has a class for is added to the scene once per element (its
  // name returned); "" for one it has none for.
  std::string TextureReference(const XmlElement& texture);
  Rgb TextureMean(const XmlElement& texture);
  Rgb SpectrumValue(const XmlElement& spectrum, bool within_emitter);
  bool WithinEmitter(const XmlElement& element) const { return emitter_elements_.count(&element) > 0; }

 private:
  void IndexIds(const XmlElement& element, bool within_emitter);
  void TopLevel(const XmlElement& element);

  // xml_sensor.cc
  void Integrator(const XmlElement& element);
  void Sensor(const XmlElement& element);
  void RadianceMeter(XmlPlugin& plugin);
  // An irradiancemeter nested in the <shape> whose world shape is named
  // `shape`.
  void IrradianceMeter(const XmlElement& element, const std::string& shape);
  // A meter's film (1x1, box filter), sampler and medium, then the camera.
  void Meter(XmlPlugin& plugin, v1::Camera camera);
  // The sampler and medium nested in a sensor.
  void SensorSamplerAndMedium(XmlPlugin& plugin);
  void SetFieldOfView(XmlPlugin& plugin, v1::Camera& camera, int64_t width, int64_t height,
                      const SourceLocation& where);
  void Film(const XmlElement& element);
  void Sampler(const XmlElement& element);

  // xml_bsdf.cc: the material a <bsdf> becomes, made once per element.
  std::string Material(const XmlElement& element);
  // `two_sided`: inside Mitsuba's twosided, whose back side reflects like
  // the front (Mitsuba's diffuse is otherwise black from behind).
  std::string MakeMaterial(const XmlElement& element, const std::string& name, bool two_sided = false);
  // A `mask` BSDF's opacity as the scene texture a shape's alpha names; ""
  // for any other BSDF (or an opaque mask).
  std::string MaskAlpha(const XmlElement& bsdf);
  std::string KnownMetal(const std::string& name, const SourceLocation& where);

  // xml_medium.cc: the medium a <medium> becomes, made once per element:
  // its name in Scene.media, or "" for one left out (vacuum).
  std::string Medium(const XmlElement& element);
  std::string MakeMedium(const XmlElement& element);

  // xml_shape.cc
  void Shape(const XmlElement& element, const std::string& group);
  void ShapeGroup(const XmlElement& element);
  void Instance(XmlPlugin& plugin);

  // xml_emitter.cc
  void Emitter(const XmlElement& element);
  v1::ComponentSpec AreaEmitter(const XmlElement& element);

  const SceneFolder& folder_;
  Diagnostics& diagnostics_;
  SceneAssembly assembly_;
  uint32_t sample_count_ = 0;
  std::string crop_;  // ImportResult::crop
  bool has_integrator_ = false;
  std::map<std::string, const XmlElement*> ids_;
  std::set<const XmlElement*> emitter_elements_;  // elements inside an <emitter>
  std::set<const XmlElement*> attached_emitters_;
  std::map<const XmlElement*, std::string> materials_;
  std::map<const XmlElement*, std::string> textures_;
  std::map<const XmlElement*, std::string> media_;
  std::string integrator_type_ = "path";  // Mitsuba's, for media
  SourceLocation integrator_where_;
  std::set<std::string> groups_made_;

 public:
  int nesting = 0;  // depth of reference resolution (RecursionGuard)
};

}  // namespace yarf::importers
