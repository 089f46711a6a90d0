// Each user's folder in the state folder (<state-dir>/files/<user>/): the
// only place a job's components may keep files between jobs (Properties::File).
#pragma once

#include <filesystem>
#include <string>

namespace yarf {

// The folder of `user` under `root`, made (mode 0700) if missing. A user
// name that is not a plain name (letters, digits, '_', '-'; at most 64)
// gets "~" and the hex SHA-256 of the name instead, so that no name can
// reach outside `root` or into another user's folder.
std::filesystem::path UserFileFolder(const std::filesystem::path& root, const std::string& user);

}  // namespace yarf
