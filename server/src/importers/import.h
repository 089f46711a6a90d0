// Scene interchange: reads what Mitsuba 3 (XML) and pbrt-v4 write and
// makes yarf's own Scene of it, with what could not be carried over said
// in warnings.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "importers/import_error.h"
#include "yarf/v1/scene.pb.h"

namespace yarf::importers {

struct ImportOptions {
  // Values of Mitsuba scene parameters ($name), overriding the file's
  // <default> elements (as `mitsuba -D name=value`).
  std::map<std::string, std::string> parameters;
  // The scene may name only files inside its folder (symbolic links
  // followed): for a scene from someone else, e.g. one uploaded to a web
  // page, which must not read the importing user's other files.
  bool confine_to_folder = false;
};

struct ImportResult {
  // Mesh files are named relative to the scene file's folder.
  v1::Scene scene;
  // Samples per pixel the file asks for; 0 when it does not say.
  uint32_t sample_count = 0;
  // The part of the film the file renders, when it renders only a part
  // (pbrt's cropwindow or pixelbounds, Mitsuba's crop_*), as `yarf render
  // --crop` takes it: "x0,x1,y0,y1" in pixels, or, written with decimal
  // points, in fractions of the film. Empty: the whole film.
  std::string crop;
  // "file:line: message", one per kind of construct ignored or approximated.
  std::vector<std::string> warnings;
};

// Imports a Mitsuba 3 (.xml) or pbrt-v4 (.pbrt) file, chosen by extension.
// Throws ImportError, whose message names the file and line.
ImportResult ImportSceneFile(const std::filesystem::path& file, const ImportOptions& options = {});

// The same from text already read; `file` names it in messages and
// anchors relative paths.
ImportResult ImportMitsuba(std::string_view text, const std::filesystem::path& file,
                           const ImportOptions& options = {});
ImportResult ImportPbrt(std::string_view text, const std::filesystem::path& file,
                        const ImportOptions& options = {});

}  // namespace yarf::importers
