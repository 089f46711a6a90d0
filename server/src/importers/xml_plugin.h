// One Mitsuba plugin element (<bsdf type="...">, <shape>...) seen as a
// typed property map, remembering what was read so that everything else
// can be reported as ignored.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "importers/matrix.h"
#include "importers/properties_util.h"
#include "importers/spectrum.h"
#include "importers/xml_document.h"

namespace yarf::importers {

class MitsubaImporter;

class XmlPlugin {
 public:
  // `use` says how spectra convert: as emission inside emitters (Mitsuba's
  // rule), else as reflectance.
  XmlPlugin(const XmlElement& element, MitsubaImporter& importer);

  const XmlElement& element() const { return element_; }
  const std::string& type() const { return type_; }
  const SourceLocation& where() const { return element_.where; }
  // "<bsdf type=\"plastic\">", for messages.
  std::string Describe() const;

  // Whether the property is given; the name asked for is remembered, so
  // that a misspelt one can be told what it was meant to be.
  bool Has(const std::string& name) const {
    asked_.insert(name);
    return named_.count(name) > 0;
  }
  // Where the named property is written (the plugin's place when absent).
  SourceLocation WhereIs(const std::string& name) const;
  double Float(const std::string& name, double fallback);
  std::optional<double> OptionalFloat(const std::string& name);
  int64_t Integer(const std::string& name, int64_t fallback);
  bool Boolean(const std::string& name, bool fallback);
  std::string String(const std::string& name, const std::string& fallback);
  // rgb, spectrum, float (grey) or a texture (its mean colour).
  Rgb Color(const std::string& name, Rgb fallback);
  std::optional<Rgb> OptionalColor(const std::string& name);
  // A colour or float that may vary over the surface: a texture yarf has
  // a class for (added to the scene), else a constant as Color gives it.
  Textured TexturedColor(const std::string& name, Rgb fallback);
  Vec3d Point(const std::string& name, Vec3d fallback);
  Matrix4 Transform(const std::string& name);
  // An index of refraction: a number or a named medium ("bk7", "air").
  double Ior(const std::string& name, double fallback);

  // Nested plugins with this tag (written inline or by <ref>), in order;
  // named ones too.
  std::vector<const XmlElement*> Objects(const std::string& tag);
  // The nested plugin (<medium>, <volume>...) given under this name, or
  // nullptr when the name is absent or holds a value (<float>, <rgb>...).
  const XmlElement* Object(const std::string& name);
  // Marks a property as read without reading it (accepted, no effect).
  void Accept(std::initializer_list<const char*> names);

  // Warns once per (plugin type, name) for what was never read.
  void WarnUnused();

 private:
  const XmlElement& Named(const std::string& name, std::initializer_list<const char*> tags);

  const XmlElement& element_;
  MitsubaImporter& importer_;
  std::string type_;
  bool within_emitter_;
  // name → element (resolved through <ref>), and unnamed nested objects.
  std::map<std::string, const XmlElement*> named_;
  std::vector<const XmlElement*> unnamed_;
  std::set<std::string> used_;
  mutable std::set<std::string> asked_;  // names the importer looked for
  std::set<const XmlElement*> used_objects_;
};

}  // namespace yarf::importers
