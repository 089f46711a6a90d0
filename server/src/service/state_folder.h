// The folder a server keeps its jobs in (--state-dir): the job database,
// checkpoints of running jobs' films and finished jobs' images. One server
// at a time: it holds an exclusive lock on <state_dir>/lock while it lives.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>

namespace yarf {

class StateFolder {
 public:
  // Creates the folder and its subfolders and takes the lock; throws Error
  // when the folder cannot be written or another server holds it.
  explicit StateFolder(std::filesystem::path root);
  ~StateFolder();
  StateFolder(const StateFolder&) = delete;
  StateFolder& operator=(const StateFolder&) = delete;

  const std::filesystem::path& root() const { return root_; }
  std::filesystem::path Database() const { return root_ / "jobs.sqlite"; }
  std::filesystem::path Checkpoints() const { return root_ / "checkpoints"; }
  std::filesystem::path Results() const { return root_ / "results"; }
  std::filesystem::path Checkpoint(const std::string& job_id) const { return Checkpoints() / (job_id + ".film"); }
  std::filesystem::path Result(const std::string& job_id) const { return Results() / (job_id + ".image"); }
  // What files of jobs (results and checkpoints, not temporaries) the
  // folder holds, for a message: "3 files in <results> and 1 in
  // <checkpoints>"; empty when there are none.
  std::string DescribeJobFiles() const;

 private:
  std::filesystem::path root_;
  int lock_fd_ = -1;
};

// Syncs the entries of `folder` (names created, renamed or removed in it)
// to disk, so that they survive a power loss; returns why it could not.
std::error_code SyncFolder(const std::filesystem::path& folder);
// Replaces `path` with `bytes` so that a crash leaves either the old file
// or the new one, never a torn one: a synced temporary file, renamed.
void WriteFileAtomically(const std::filesystem::path& path, std::string_view bytes);
// The file's bytes; nullopt when it does not exist. Throws Error when it
// exists but cannot be read.
std::optional<std::string> ReadWholeFile(const std::filesystem::path& path);

}  // namespace yarf
