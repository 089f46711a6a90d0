#include "importers/scene_folder.h"

#include <algorithm>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <system_error>
#include <vector>

#include "kernel/inflate.h"

namespace yarf::importers {

namespace fs = std::filesystem;

SceneFolder::SceneFolder(const fs::path& scene_file, bool confined)
    : confined_(confined), user_root_(scene_file.parent_path()) {
  std::error_code error;
  const fs::path folder = user_root_.empty() ? fs::path(".") : user_root_;
  root_ = fs::weakly_canonical(fs::absolute(folder, error), error);
  if (error) root_ = fs::absolute(folder).lexically_normal();
}

bool SceneFolder::Inside(const fs::path& canonical) const {
  const auto [end, _] = std::mismatch(root_.begin(), root_.end(), canonical.begin(), canonical.end());
  return end == root_.end();
}

fs::path SceneFolder::Resolve(const std::string& name, const fs::path& from_file,
                              const SourceLocation& where, bool must_exist) const {
  if (name.empty()) Fail(where, "empty file name");
  if (name.find('\0') != std::string::npos) Fail(where, "file name contains a NUL character");
  const fs::path relative(name);
  std::vector<fs::path> candidates;
  if (relative.is_absolute()) {
    candidates.push_back(relative);
  } else {
    candidates.push_back(fs::absolute(from_file).parent_path() / relative);
    candidates.push_back(root_ / relative);
  }
  for (const fs::path& folder : search_)
    if (!relative.is_absolute()) candidates.push_back(folder / relative);
  for (const fs::path& candidate : candidates) {
    std::error_code error;
    const fs::path canonical = fs::weakly_canonical(candidate, error);
    if (error || (confined_ && !Inside(canonical))) continue;
    if (!must_exist || fs::is_regular_file(canonical, error)) return canonical;
  }
  if (confined_) Fail(where, "file '" + name + "' not found inside the scene's folder, the only one it may name");
  Fail(where, "file '" + name + "' not found (looked in the including file's folder, " + root_.string() +
                  (search_.empty() ? std::string() : " and the scene's <path> folders") + ")");
}

void SceneFolder::AddSearchFolder(const fs::path& folder) {
  std::error_code error;
  const fs::path canonical = fs::weakly_canonical(fs::absolute(folder, error), error);
  search_.push_back(error ? fs::absolute(folder).lexically_normal() : canonical);
}

std::string SceneFolder::Relative(const fs::path& file) const {
  return file.lexically_relative(root_).generic_string();
}

std::string SceneFolder::Display(const fs::path& file) const {
  std::error_code error;
  const fs::path canonical = fs::weakly_canonical(fs::absolute(file, error), error);
  if (error || !Inside(canonical)) return file.string();
  return (user_root_ / canonical.lexically_relative(root_)).lexically_normal().string();
}

// Scene text beyond this size is refused (meshes belong in their own files).
constexpr std::uintmax_t kMaxSceneBytes = std::uintmax_t(1) << 30;

namespace {

// The first `limit` bytes of a file, or of what it inflates to when it
// is a gzip file; `complete` when nothing is left out. At most 1 GiB is
// read, and inflated (a gzip file's header may need any share of its
// compressed bytes: all of them).
Inflated ReadUpTo(const fs::path& file, std::uintmax_t limit, const SourceLocation& where) {
  std::error_code error;
  if (!fs::is_regular_file(file, error)) Fail(where, "file '" + file.string() + "' not found");
  const std::uintmax_t size = fs::file_size(file, error);
  if (error) Fail(where, "cannot read '" + file.string() + "'");
  std::ifstream in(file, std::ios::binary);
  std::string bytes;
  // Reads on to `end` bytes from the start.
  const auto read_to = [&](std::uintmax_t end) {
    if (end > kMaxSceneBytes) Fail(where, "file '" + file.string() + "' is larger than 1 GiB");
    const size_t from = bytes.size();
    bytes.resize(size_t(end));
    if (!in.read(bytes.data() + from, std::streamsize(bytes.size() - from)))
      Fail(where, "cannot read '" + file.string() + "'");
  };
  read_to(std::min(size, limit));
  if (!IsGzip(bytes)) {
    const bool complete = bytes.size() == size;
    return {std::move(bytes), complete};
  }
  read_to(size);
  try {
    return Inflate(bytes, std::min(limit, kMaxSceneBytes));
  } catch (const std::runtime_error& e) {
    Fail(where, "gzip file '" + file.string() + "': " + e.what());
  }
}

}  // namespace

std::string ReadFileHead(const fs::path& file, size_t bytes, const SourceLocation& where) {
  return ReadUpTo(file, bytes, where).bytes;
}

std::string ReadTextFile(const fs::path& file, const SourceLocation& where) {
  Inflated text = ReadUpTo(file, std::numeric_limits<std::uintmax_t>::max(), where);
  if (!text.complete) Fail(where, "file '" + file.string() + "' inflates to more than 1 GiB");
  return std::move(text.bytes);
}

}  // namespace yarf::importers
