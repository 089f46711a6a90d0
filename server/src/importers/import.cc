#include "importers/import.h"

#include <algorithm>

#include "importers/scene_folder.h"

namespace yarf::importers {

namespace fs = std::filesystem;

ImportResult ImportSceneFile(const fs::path& file, const ImportOptions& options) {
  std::string extension = file.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(), ::tolower);
  const SourceLocation where{file.string(), 0};
  if (extension == ".xml") return ImportMitsuba(ReadTextFile(file, where), file, options);
  if (extension == ".pbrt") return ImportPbrt(ReadTextFile(file, where), file, options);
  Fail(where, "unknown scene format '" + extension + "' (expected .xml for Mitsuba 3 or .pbrt for pbrt-v4)");
}

}  // namespace yarf::importers
