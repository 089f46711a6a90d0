#include "importers/import.h"

#include <algorithm>

#include "importers/scene_folder.h"

namespace yarf::importers {

namespace fs = std::filesystem;

ImportResult ImportSceneFile(const fs::path& file, const ImportOptions& options) {
  // scene.pbrt.gz: a compressed scene.pbrt (ReadTextFile inflates it).
  const fs::path named = file.extension() == ".gz" ? file.stem() : file;
  std::string extension = named.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(), ::tolower);
  const SourceLocation where{file.string(), 0};
  if (extension == ".xml") return ImportMitsuba(ReadTextFile(file, where), file, options);
  if (extension == ".pbrt") return ImportPbrt(ReadTextFile(file, where), file, options);
  Fail(where, "unknown scene format '" + extension + "' (expected .xml for Mitsuba 3 or .pbrt for pbrt-v4)");
}

}  // namespace yarf::importers
