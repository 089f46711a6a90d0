// Each user's folder in the state folder (<state-dir>/files/<user>/): the
// only place a job's components may keep files between jobs (Properties::File).
#pragma once

#include <filesystem>
#include <string>

namespace yarf {

// The name that stands for `user` in the file system: the name itself when
// it is plain (letters, digits, '_', '-'; at most 64), else "~" and the hex
// SHA-256 of the name, so that no name can reach outside a folder or into
// another user's.
std::string UserFolderName(const std::string& user);

// The folder of `user` under `root`, made (mode 0700) if missing.
std::filesystem::path UserFileFolder(const std::filesystem::path& root, const std::string& user);

}  // namespace yarf
