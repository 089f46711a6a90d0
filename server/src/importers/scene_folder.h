// The folder of a scene file, where the files a scene names (includes,
// meshes, textures) are looked for. The importer runs as its user, who may
// name any file they can read (Mitsuba's "../textures/wood.png"): the
// client uploads what it reads by hash, and confining the paths a server is
// sent is the server's rule (the kernel's scene builder). A confined folder
// is for a scene from someone else: it finds only files inside it.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "importers/import_error.h"

namespace yarf::importers {

class SceneFolder {
 public:
  // `scene_file` as the user named it; its folder is the root.
  explicit SceneFolder(const std::filesystem::path& scene_file, bool confined = false);

  // The file `name` refers to from `from_file`: relative to from_file's
  // folder, else to the root, else to the folders added by AddSearchFolder
  // (in order). Fails (at `where`) when, with must_exist, none is a
  // regular file. Confined, a file outside the root is never found, and
  // the message is the same whether it exists or not.
  std::filesystem::path Resolve(const std::string& name, const std::filesystem::path& from_file,
                                const SourceLocation& where, bool must_exist = true) const;

  // Looks for files in `folder` too (Mitsuba's <path value="..."/>).
  void AddSearchFolder(const std::filesystem::path& folder);

  // `file` relative to the root, '/'-separated (with "../" for a file
  // outside it): what Mesh.file holds.
  std::string Relative(const std::filesystem::path& file) const;

  // How messages name `file`: the user's path to the scene folder joined
  // with the file's path inside it.
  std::string Display(const std::filesystem::path& file) const;

  const std::filesystem::path& root() const { return root_; }

 private:
  bool Inside(const std::filesystem::path& canonical) const;

  bool confined_ = false;
  std::filesystem::path root_;        // canonical
  std::filesystem::path user_root_;   // as given
  std::vector<std::filesystem::path> search_;  // absolute
};

// The bytes of a scene file (at most 1 GiB), inflated when it is a gzip
// file (to at most 1 GiB); fails at `where` otherwise.
std::string ReadTextFile(const std::filesystem::path& file, const SourceLocation& where);

// The first `bytes` bytes of a file, inflated first when it is a gzip file
// (a header's worth: a mesh file's, say); fails at `where` if the file
// cannot be read or inflated.
std::string ReadFileHead(const std::filesystem::path& file, size_t bytes, const SourceLocation& where);

}  // namespace yarf::importers
