#include "importers/xml_plugin.h"

#include <algorithm>
#include <array>
#include <cctype>

#include "importers/named_ior.h"
#include "importers/numbers.h"
#include "importers/xml_importer.h"

namespace yarf::importers {
namespace {

constexpr std::array kPropertyTags = {"float", "integer", "boolean", "string", "rgb",
                                      "spectrum", "point", "vector", "transform"};
constexpr std::array kObjectTags = {"bsdf", "emitter", "shape", "sensor", "film", "sampler", "rfilter",
                                    "integrator", "medium", "phase", "volume", "texture"};

template <size_t N>
bool Contains(const std::array<const char*, N>& tags, const std::string& tag) {
  return std::any_of(tags.begin(), tags.end(), [&](const char* t) { return tag == t; });
}

double NumberAttribute(const XmlElement& e, const char* attribute, double fallback) {
  const std::string* text = e.Attribute(attribute);
  if (!text) return fallback;
  const auto value = ParseDouble(*text);
  if (!value) Fail(e.where, "'" + *text + "' is not a finite number");
  return *value;
}

std::vector<double> Numbers(const XmlElement& e, const std::string& text) {
  const auto values = ParseDoubleList(text);
  if (!values) Fail(e.where, "'" + text + "' is not a list of finite numbers");
  return *values;
}

// A point or vector: value="x, y, z" or attributes x, y, z (default 0).
Vec3d ReadVector(const XmlElement& e, const char* value_attribute, double fallback) {
  if (const std::string* text = e.Attribute(value_attribute)) {
    const std::vector<double> v = Numbers(e, *text);
    if (v.size() == 1) return {v[0], v[0], v[0]};
    if (v.size() != 3) Fail(e.where, "expected 3 numbers, got " + std::to_string(v.size()));
    return {v[0], v[1], v[2]};
  }
  return {NumberAttribute(e, "x", fallback), NumberAttribute(e, "y", fallback), NumberAttribute(e, "z", fallback)};
}

Vec3d ReadPointAttribute(const XmlElement& e, const char* name) {
  const std::vector<double> v = Numbers(e, e.Required(name));
  if (v.size() != 3) Fail(e.where, std::string(name) + ": expected 3 numbers");
  return {v[0], v[1], v[2]};
}

// One operation of a <transform>: the matrix it multiplies on the left.
Matrix4 Operation(const XmlElement& op) {
  if (op.tag == "translate") return Matrix4::Translate(ReadVector(op, "value", 0));
  if (op.tag == "scale") return Matrix4::Scale(ReadVector(op, "value", 1));
  if (op.tag == "rotate") {
    const Vec3d axis = ReadVector(op, "value", 0);
    const auto m = Matrix4::Rotate(axis, NumberAttribute(op, "angle", 0));
    if (!m) Fail(op.where, "<rotate> needs a nonzero axis");
    return *m;
  }
  if (op.tag == "matrix") {
    const std::vector<double> v = Numbers(op, op.Required("value"));
    if (v.size() == 9) return Matrix4({v[0], v[1], v[2], 0, v[3], v[4], v[5], 0, v[6], v[7], v[8], 0, 0, 0, 0, 1});
    if (v.size() != 16) Fail(op.where, "<matrix> needs 9 or 16 values, got " + std::to_string(v.size()));
    std::array<double, 16> m{};
    std::copy(v.begin(), v.end(), m.begin());
    return Matrix4(m);
  }
  if (op.tag == "lookat") {
    const Vec3d origin = ReadPointAttribute(op, "origin"), target = ReadPointAttribute(op, "target");
    Vec3d up{0, 1, 0};
    if (op.Attribute("up")) {
      up = ReadPointAttribute(op, "up");
    } else if (const auto dir = Normalized(target - origin); dir && std::abs(dir->y) > 0.999) {
      up = {0, 0, 1};  // any direction not along the view, as Mitsuba picks one
    }
    const auto m = Matrix4::LookAt(origin, target, up);
    if (!m) Fail(op.where, "<lookat>: origin equals target, or up is parallel to the view");
    return *m;
  }
  Fail(op.where, "<" + op.tag + "> is not a transform operation");
}

}  // namespace

XmlPlugin::XmlPlugin(const XmlElement& element, MitsubaImporter& importer)
    : element_(element), importer_(importer), type_(element.Get("type")),
      within_emitter_(importer.WithinEmitter(element)) {
  for (const XmlElement& child : element.children) {
    const XmlElement* target = &child;
    if (child.tag == "ref") target = &importer.Lookup(child.Required("id"), child.where);
    const std::string* name = child.Attribute("name");
    const bool property = Contains(kPropertyTags, child.tag);
    if (!property && child.tag != "ref" && !Contains(kObjectTags, child.tag)) {
      importer.Warn(child.where, "tag:" + child.tag, "unknown element <" + child.tag + "> ignored");
      continue;
    }
    if (property && !name) Fail(child.where, "<" + child.tag + "> needs a name attribute");
    if (name) {
      if (!named_.emplace(*name, target).second)
        Fail(child.where, Describe() + ": property '" + *name + "' is given twice");
    } else {
      unnamed_.push_back(target);
    }
  }
}

std::string XmlPlugin::Describe() const {
  return "<" + element_.tag + (type_.empty() ? "" : " type=\"" + type_ + "\"") + ">";
}

SourceLocation XmlPlugin::WhereIs(const std::string& name) const {
  const auto it = named_.find(name);
  return it == named_.end() ? element_.where : it->second->where;
}

const XmlElement& XmlPlugin::Named(const std::string& name, std::initializer_list<const char*> tags) {
  const XmlElement& e = *named_.at(name);
  used_.insert(name);
  for (const char* tag : tags)
    if (e.tag == tag) return e;
  std::string expected;
  for (const char* tag : tags) expected += std::string(expected.empty() ? "" : " or ") + "<" + tag + ">";
  Fail(e.where, Describe() + ": property '" + name + "' must be " + expected + ", not <" + e.tag + ">");
}

std::optional<double> XmlPlugin::OptionalFloat(const std::string& name) {
  if (!Has(name)) return std::nullopt;
  const XmlElement& e = Named(name, {"float", "integer", "texture", "spectrum"});
  if (e.tag == "texture" || e.tag == "spectrum") {
    const Rgb c = e.tag == "texture" ? importer_.TextureMean(e) : importer_.SpectrumValue(e, within_emitter_);
    return (c.r + c.g + c.b) / 3;
  }
  const auto value = ParseDouble(e.Required("value"));
  if (!value) Fail(e.where, name + ": '" + e.Get("value") + "' is not a finite number");
  return *value;
}

double XmlPlugin::Float(const std::string& name, double fallback) { return OptionalFloat(name).value_or(fallback); }

int64_t XmlPlugin::Integer(const std::string& name, int64_t fallback) {
  if (!Has(name)) return fallback;
  const XmlElement& e = Named(name, {"integer"});
  const auto value = ParseInteger(e.Required("value"));
  if (!value) Fail(e.where, name + ": '" + e.Get("value") + "' is not an integer");
  return *value;
}

bool XmlPlugin::Boolean(const std::string& name, bool fallback) {
  if (!Has(name)) return fallback;
  const XmlElement& e = Named(name, {"boolean"});
  std::string value = e.Required("value");
  std::transform(value.begin(), value.end(), value.begin(), ::tolower);
  if (value == "true" || value == "1") return true;
  if (value == "false" || value == "0") return false;
  Fail(e.where, name + ": '" + e.Get("value") + "' is not true or false");
}

std::string XmlPlugin::String(const std::string& name, const std::string& fallback) {
  if (!Has(name)) return fallback;
  return Named(name, {"string"}).Required("value");
}

std::optional<Rgb> XmlPlugin::OptionalColor(const std::string& name) {
  if (!Has(name)) return std::nullopt;
  const XmlElement& e = Named(name, {"rgb", "spectrum", "float", "integer", "texture"});
  if (e.tag == "texture") return importer_.TextureMean(e);
  if (e.tag == "spectrum") return importer_.SpectrumValue(e, within_emitter_);
  const std::vector<double> v = Numbers(e, e.Required("value"));
  if (v.size() == 1) return Rgb{v[0], v[0], v[0]};
  if (v.size() != 3 || e.tag != "rgb") Fail(e.where, name + ": expected one value or three (r, g, b)");
  return Rgb{v[0], v[1], v[2]};
}

Rgb XmlPlugin::Color(const std::string& name, Rgb fallback) { return OptionalColor(name).value_or(fallback); }

Textured XmlPlugin::TexturedColor(const std::string& name, Rgb fallback) {
  if (Has(name) && named_.at(name)->tag == "texture") {
    const XmlElement& e = Named(name, {"texture"});
    if (std::string texture = importer_.TextureReference(e); !texture.empty()) return {{}, texture};
  }
  return {Color(name, fallback), ""};
}

Vec3d XmlPlugin::Point(const std::string& name, Vec3d fallback) {
  if (!Has(name)) return fallback;
  return ReadVector(Named(name, {"point", "vector"}), "value", 0);
}

Matrix4 XmlPlugin::Transform(const std::string& name) {
  if (!Has(name)) return Matrix4();
  const XmlElement& e = Named(name, {"transform"});
  Matrix4 m;
  for (const XmlElement& op : e.children) m = Operation(op) * m;
  if (!m.IsFinite()) Fail(e.where, name + ": the transform is not finite");
  return m;
}

double XmlPlugin::Ior(const std::string& name, double fallback) {
  if (!Has(name)) return fallback;
  const XmlElement& e = *named_.at(name);
  if (e.tag != "string") return Float(name, fallback);
  std::string medium = String(name, "");
  std::transform(medium.begin(), medium.end(), medium.begin(), ::tolower);
  const auto ior = MitsubaNamedIor(medium);
  if (!ior) Fail(e.where, name + ": unknown medium '" + medium + "' (give a number or a known name like \"bk7\")");
  return *ior;
}

std::vector<const XmlElement*> XmlPlugin::Objects(const std::string& tag) {
  std::vector<const XmlElement*> out;
  for (const XmlElement* e : unnamed_)
    if (e->tag == tag) out.push_back(e), used_objects_.insert(e);
  for (const auto& [name, e] : named_)
    if (e->tag == tag && !Contains(kPropertyTags, e->tag)) out.push_back(e), used_.insert(name);
  return out;
}

const XmlElement* XmlPlugin::Object(const std::string& name) {
  if (!Has(name)) return nullptr;
  const XmlElement* e = named_.at(name);
  if (Contains(kPropertyTags, e->tag)) return nullptr;
  used_.insert(name);
  return e;
}

void XmlPlugin::Accept(std::initializer_list<const char*> names) {
  for (const char* name : names) used_.insert(name), asked_.insert(name);
}

void XmlPlugin::WarnUnused() {
  const std::string what = element_.tag + " '" + type_ + "'";
  const std::vector<std::string> asked(asked_.begin(), asked_.end());
  for (const auto& [name, e] : named_)
    if (!used_.count(name))
      importer_.Warn(e->where, what + ":" + name,
                     what + ": parameter '" + name + "' ignored" + DidYouMean(name, asked));
  for (const XmlElement* e : unnamed_)
    if (!used_objects_.count(e))
      importer_.Warn(e->where, what + ":<" + e->tag + ">",
                     what + ": nested <" + e->tag + "> ignored");
}

}  // namespace yarf::importers
