// A private folder under the system's temporary directory, removed with
// everything in it when its owner is destroyed (bitmap.cc keeps the
// MIP-mapped copy of its image there).
#pragma once

#include <stdlib.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <string>
#include <system_error>

#include "yarf/error.h"

namespace yarf::textures {

class TemporaryFolder {
 public:
  // `prefix`: the start of the folder's name, for whoever lists /tmp.
  explicit TemporaryFolder(const std::string& prefix) {
    std::string pattern = (std::filesystem::temp_directory_path() / (prefix + "-XXXXXX")).string();
    // mkdtemp makes a new folder only its user can enter, under a name
    // no other instance (or process) can have taken.
    if (!mkdtemp(pattern.data()))
      throw Error("cannot make a temporary folder in " + std::filesystem::temp_directory_path().string() + ": " +
                  std::strerror(errno));
    path_ = pattern;
  }
  TemporaryFolder(const TemporaryFolder&) = delete;
  TemporaryFolder& operator=(const TemporaryFolder&) = delete;
  ~TemporaryFolder() {
    std::error_code ignored;  // a destructor cannot report; the folder is in /tmp
    std::filesystem::remove_all(path_, ignored);
  }

  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace yarf::textures
