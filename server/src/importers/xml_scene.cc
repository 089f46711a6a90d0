// Mitsuba 3 XML scenes: the entry point and the walk over the <scene>.
#include "importers/properties_util.h"
#include "importers/xml_importer.h"

namespace yarf::importers {

ImportResult ImportMitsuba(std::string_view text, const std::filesystem::path& file, const ImportOptions& options) {
  SceneFolder folder(file, options.confine_to_folder);
  Diagnostics diagnostics;
  const XmlElement scene = LoadMitsubaDocument(text, file, folder, options.parameters, diagnostics);
  MitsubaImporter importer(folder, diagnostics);
  return importer.Run(scene);
}

const XmlElement& MitsubaImporter::Lookup(const std::string& id, const SourceLocation& where) const {
  const auto it = ids_.find(id);
  if (it == ids_.end()) Fail(where, "reference to an unknown id '" + id + "'");
  return *it->second;
}

void MitsubaImporter::IndexIds(const XmlElement& element, bool within_emitter) {
  within_emitter = within_emitter || element.tag == "emitter";
  if (within_emitter) emitter_elements_.insert(&element);
  if (const std::string* id = element.Attribute("id"); id && element.tag != "ref" && element.tag != "alias") {
    if (id->empty()) Fail(element.where, "empty id");
    if (!ids_.emplace(*id, &element).second) Fail(element.where, "id '" + *id + "' is used twice");
  }
  for (const XmlElement& child : element.children) IndexIds(child, within_emitter);
}

ImportResult MitsubaImporter::Run(const XmlElement& scene) {
  IndexIds(scene, false);
  // Aliases name an element a second time, in document order.
  for (const XmlElement& e : scene.children)
    if (e.tag == "alias") {
      const XmlElement& target = Lookup(e.Required("id"), e.where);
      if (!ids_.emplace(e.Required("as"), &target).second)
        Fail(e.where, "alias '" + e.Get("as") + "' names an id already used");
    }

  for (const XmlElement& e : scene.children) TopLevel(e);

  for (const XmlElement& e : scene.children)
    if (e.tag == "emitter" && e.Get("type") == "area" && !attached_emitters_.count(&e))
      Warn(e.where, "unattached-area", "area emitter not attached to any shape: ignored");
  if (!assembly_.HasCamera()) {
    Warn(scene.where, "no-sensor", "the scene has no sensor: Mitsuba's default perspective camera used");
    XmlElement sensor;
    sensor.tag = "sensor";
    sensor.attributes = {{"type", "perspective"}};
    sensor.where = scene.where;
    sensor.file = scene.file;
    Sensor(sensor);
  }
  if (!has_integrator_) {
    v1::Properties p;
    SetInt(p, "max_depth", -1);
    *assembly_.scene().mutable_transport() = Spec("path", std::move(p));
    integrator_where_ = scene.where;
  }
  if (assembly_.HasMedia()) {
    if (integrator_type_ == "volpath" || integrator_type_ == "volpathmis")
      assembly_.scene().mutable_transport()->set_class_name("volpath");
    else
      Warn(integrator_where_, "integrator-media",
           "integrator '" + integrator_type_ +
               "' does not render participating media: they are ignored (Mitsuba's \"volpath\" renders them)");
  }
  // Mitsuba 3 chooses lights uniformly. On its own MIS scene that is what
  // keeps the small lamps' light samples: by power, the far fill light
  // takes nearly all of them.
  assembly_.scene().set_light_sampler(v1::Scene::LIGHT_SAMPLER_UNIFORM);
  ImportResult result;
  result.scene = assembly_.Finish();
  result.sample_count = sample_count_;
  result.crop = crop_;
  result.warnings = diagnostics_.Lines();
  return result;
}

void MitsubaImporter::TopLevel(const XmlElement& e) {
  const std::string type = e.Get("type");
  if (e.tag == "integrator") {
    Integrator(e);
  } else if (e.tag == "sensor") {
    if (assembly_.HasCamera())
      Warn(e.where, "second-sensor", "a second <sensor> ignored: yarf renders the first");
    else
      Sensor(e);
  } else if (e.tag == "shape") {
    if (type == "shapegroup")
      ShapeGroup(e);
    else
      Shape(e, "");
  } else if (e.tag == "emitter") {
    if (type != "area") Emitter(e);
  } else if (e.tag == "bsdf" || e.tag == "texture" || e.tag == "spectrum" || e.tag == "rgb" || e.tag == "medium" ||
             e.tag == "phase" || e.tag == "volume") {
    // Made where they are referred to.
    if (!e.Attribute("id"))
      Warn(e.where, "unused:" + e.tag, "<" + e.tag + "> without an id is never used: ignored");
  } else if (e.tag == "alias") {
    // indexed in Run
  } else {
    Warn(e.where, "tag:" + e.tag, "<" + e.tag + "> ignored here");
  }
}

}  // namespace yarf::importers
