// The folder of a scene file: every file the scene names (includes, meshes,
// textures) must lie inside it, so that a scene cannot reach elsewhere.
#pragma once

#include <filesystem>
#include <string>

#include "importers/import_error.h"

namespace yarf::importers {

class SceneFolder {
 public:
  // `scene_file` as the user named it; its folder is the root.
  explicit SceneFolder(const std::filesystem::path& scene_file);

  // The file `name` refers to from `from_file`: relative to from_file's
  // folder, else to the root. Fails (at `where`) when it is outside the
  // root or, with must_exist, not a regular file.
  std::filesystem::path Resolve(const std::string& name, const std::filesystem::path& from_file,
                                const SourceLocation& where, bool must_exist = true) const;

  // `file` (inside the root) relative to the root, '/'-separated: what
  // Mesh.file holds.
  std::string Relative(const std::filesystem::path& file) const;

  // How messages name `file`: the user's path to the scene folder joined
  // with the file's path inside it.
  std::string Display(const std::filesystem::path& file) const;

  const std::filesystem::path& root() const { return root_; }

 private:
  bool Inside(const std::filesystem::path& canonical) const;

  std::filesystem::path root_;        // canonical
  std::filesystem::path user_root_;   // as given
};

// The bytes of a scene file (at most 1 GiB); fails at `where` otherwise.
std::string ReadTextFile(const std::filesystem::path& file, const SourceLocation& where);

}  // namespace yarf::importers
