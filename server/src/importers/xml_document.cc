#include "importers/xml_document.h"

#include <pugixml.hpp>

#include <algorithm>
#include <cctype>

namespace yarf::importers {

namespace fs = std::filesystem;

const std::string* XmlElement::Attribute(std::string_view name) const {
  for (const auto& [key, value] : attributes)
    if (key == name) return &value;
  return nullptr;
}

const std::string& XmlElement::Required(std::string_view name) const {
  const std::string* value = Attribute(name);
  if (!value) Fail(where, "<" + tag + "> needs a '" + std::string(name) + "' attribute");
  return *value;
}

std::string XmlElement::Get(std::string_view name, const std::string& fallback) const {
  const std::string* value = Attribute(name);
  return value ? *value : fallback;
}

namespace {

// Deep nesting and long include chains are refused before they exhaust
// the stack.
constexpr int kMaxDepth = 200;
constexpr int kMaxIncludeDepth = 32;
// Files included in all (a file may be included many times, not in a cycle).
constexpr int kMaxIncludes = 10000;
// Substitution may not grow a value beyond this.
constexpr size_t kMaxValueLength = size_t(1) << 20;

// Mitsuba 0.6 scenes spell parameters in camelCase; Mitsuba 3 reads them
// as snake_case.
std::string SnakeCase(const std::string& name) {
  std::string out;
  for (char c : name) {
    if (std::isupper(static_cast<unsigned char>(c))) {
      out += '_';
      out += char(std::tolower(static_cast<unsigned char>(c)));
    } else {
      out += c;
    }
  }
  return out;
}

class Loader {
 public:
  Loader(const fs::path& file, SceneFolder& folder, const std::map<std::string, std::string>& parameters,
         Diagnostics& diagnostics)
      : folder_(folder), parameters_(parameters), diagnostics_(diagnostics) {
    std::error_code error;
    stack_.push_back(fs::weakly_canonical(fs::absolute(file), error));
  }

  // Parses one file; appends the children of its <scene> to `out`.
  void LoadFile(std::string_view text, const fs::path& file, std::vector<XmlElement>& out, int include_depth) {
    const std::string display = folder_.Display(file);
    pugi::xml_document doc;
    const pugi::xml_parse_result parsed =
        doc.load_buffer(text.data(), text.size(), pugi::parse_default, pugi::encoding_utf8);
    const LineIndex lines(text);
    if (!parsed)
      Fail({display, lines.Line(parsed.offset)}, std::string("malformed XML: ") + parsed.description());
    const pugi::xml_node root = doc.document_element();
    const SourceLocation root_where{display, lines.Line(root.offset_debug())};
    if (std::string(root.name()) != "scene")
      Fail(root_where, "the root element is <" + std::string(root.name()) + ">, expected <scene>");
    const pugi::xml_attribute version = root.attribute("version");
    if (!version) Fail(root_where, "<scene> needs a version attribute (e.g. version=\"3.0.0\")");
    const int major = std::atoi(version.value());
    if (major < 0 || major > 3) Fail(root_where, "unsupported scene version '" + std::string(version.value()) + "'");
    const bool legacy = major < 2;
    if (legacy)
      diagnostics_.Warn(root_where, "legacy-version",
                        "scene version " + std::string(version.value()) +
                            " is Mitsuba 0.6's: camelCase names are read as snake_case");
    File context{file, display, &lines, legacy, include_depth};
    for (pugi::xml_node child : root.children())
      if (child.type() == pugi::node_element) Convert(child, context, out, 1);
  }

 private:
  struct LineIndex {
    explicit LineIndex(std::string_view text) {
      starts.push_back(0);
      for (size_t i = 0; i < text.size(); ++i)
        if (text[i] == '\n') starts.push_back(i + 1);
    }
    int Line(ptrdiff_t offset) const {
      if (offset < 0) return 0;
      return int(std::upper_bound(starts.begin(), starts.end(), size_t(offset)) - starts.begin());
    }
    std::vector<size_t> starts;
  };

  struct File {
    fs::path path;
    std::string display;
    const LineIndex* lines;
    bool legacy;
    int include_depth;
  };

  void Convert(const pugi::xml_node& node, const File& file, std::vector<XmlElement>& out, int depth) {
    XmlElement e;
    e.tag = node.name();
    e.where = {file.display, file.lines->Line(node.offset_debug())};
    e.file = file.path;
    if (depth > kMaxDepth) Fail(e.where, "elements nested deeper than " + std::to_string(kMaxDepth));
    if (file.legacy) e.tag = e.tag == "lookAt" ? "lookat" : e.tag;
    for (pugi::xml_attribute a : node.attributes()) {
      std::string value = Substitute(a.value(), e.where);
      if (file.legacy && std::string(a.name()) == "name") value = SnakeCase(value);
      e.attributes.emplace_back(a.name(), std::move(value));
    }
    if (e.tag == "default") {
      const std::string& name = e.Required("name");
      const std::string& value = e.Required("value");
      if (name.empty()) Fail(e.where, "<default> with an empty name");
      defaults_.emplace(name, value);  // the first definition wins, as in Mitsuba
      return;
    }
    if (e.tag == "include") {
      Include(e, file, out);
      return;
    }
    if (e.tag == "path") {
      // A folder files are looked for in, relative to this file's folder.
      const fs::path folder = fs::absolute(file.path).parent_path() / fs::path(e.Required("value"));
      std::error_code error;
      if (!fs::is_directory(folder, error)) Fail(e.where, "<path>: folder '" + e.Get("value") + "' not found");
      folder_.AddSearchFolder(folder);
      return;
    }
    for (pugi::xml_node child : node.children())
      if (child.type() == pugi::node_element) Convert(child, file, e.children, depth + 1);
    out.push_back(std::move(e));
  }

  void Include(const XmlElement& e, const File& file, std::vector<XmlElement>& out) {
    const fs::path target = folder_.Resolve(e.Required("filename"), file.path, e.where);
    if (file.include_depth >= kMaxIncludeDepth)
      Fail(e.where, "includes nested deeper than " + std::to_string(kMaxIncludeDepth));
    if (++includes_ > kMaxIncludes) Fail(e.where, "more than " + std::to_string(kMaxIncludes) + " includes");
    if (std::find(stack_.begin(), stack_.end(), target) != stack_.end())
      Fail(e.where, "include cycle: '" + e.Get("filename") + "' includes itself");
    const std::string text = ReadTextFile(target, e.where);
    stack_.push_back(target);
    LoadFile(text, target, out, file.include_depth + 1);
    stack_.pop_back();
  }

  // Replaces every $name by its value: a parameter given to the import,
  // else a <default> seen so far.
  std::string Substitute(const std::string& value, const SourceLocation& where) const {
    if (value.find('$') == std::string::npos) return value;
    std::string out;
    for (size_t i = 0; i < value.size();) {
      if (value[i] != '$') {
        out += value[i++];
        continue;
      }
      size_t end = i + 1;
      while (end < value.size() && (std::isalnum(static_cast<unsigned char>(value[end])) || value[end] == '_')) ++end;
      const std::string name = value.substr(i + 1, end - i - 1);
      if (name.empty()) Fail(where, "'$' without a parameter name in \"" + value + "\"");
      if (const auto given = parameters_.find(name); given != parameters_.end())
        out += given->second;
      else if (const auto fallback = defaults_.find(name); fallback != defaults_.end())
        out += fallback->second;
      else
        Fail(where, "undefined parameter $" + name + " (give it a <default> or a value)");
      if (out.size() > kMaxValueLength) Fail(where, "parameter substitution makes a value too long");
      i = end;
    }
    return out;
  }

  SceneFolder& folder_;
  const std::map<std::string, std::string>& parameters_;
  std::map<std::string, std::string> defaults_;
  Diagnostics& diagnostics_;
  std::vector<fs::path> stack_;  // the files being read, for cycles
  int includes_ = 0;
};

}  // namespace

XmlElement LoadMitsubaDocument(std::string_view text, const fs::path& file, SceneFolder& folder,
                               const std::map<std::string, std::string>& parameters, Diagnostics& diagnostics) {
  Loader loader(file, folder, parameters, diagnostics);
  XmlElement scene;
  scene.tag = "scene";
  scene.where = {folder.Display(file), 1};
  scene.file = file;
  loader.LoadFile(text, file, scene.children, 0);
  return scene;
}

}  // namespace yarf::importers
