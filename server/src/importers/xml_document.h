// A Mitsuba 3 scene document as one tree: <include> files spliced in,
// <default> values and $name parameters substituted, every element
// knowing its file and line.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "importers/diagnostics.h"
#include "importers/scene_folder.h"

namespace yarf::importers {

struct XmlElement {
  std::string tag;
  std::vector<std::pair<std::string, std::string>> attributes;  // substituted
  std::vector<XmlElement> children;
  SourceLocation where;
  std::filesystem::path file;  // the file it was read from

  // The attribute's value, or nullptr.
  const std::string* Attribute(std::string_view name) const;
  // The attribute's value, failing at `where` when it is missing.
  const std::string& Required(std::string_view name) const;
  std::string Get(std::string_view name, const std::string& fallback = "") const;
};

// Reads `text` (the file `file`) into its <scene> element. `parameters`
// override <default>s; <path> elements add search folders to `folder`. Malformed XML, a missing version, an include cycle
// or an undefined $name fail with the file and line.
XmlElement LoadMitsubaDocument(std::string_view text, const std::filesystem::path& file,
                               SceneFolder& folder, const std::map<std::string, std::string>& parameters,
                               Diagnostics& diagnostics);

}  // namespace yarf::importers
