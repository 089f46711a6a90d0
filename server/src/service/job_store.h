// The durable job table: one SQLite database in the state folder (WAL,
// synchronous FULL), so that an accepted job survives a crash of the
// server. Every call commits before it returns. A database that looks
// lost, damaged or cut off from its log is refused before SQLite touches
// it, rather than opened with fewer jobs than it acknowledged.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "yarf/v1/render.pb.h"

struct sqlite3;

namespace yarf {

// The database could not be opened, read or written: a fault of the
// server's machine, not of a caller's request.
class StorageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// One job's row.
struct JobRecord {
  // The job's number: its id is "job-<number>". Never reused.
  uint64_t number = 0;
  // The accepted v1::SubmitRequest, serialized; LoadAll reads it only for
  // jobs that have not ended.
  std::string request;
  std::string name, owner, error;
  v1::JobState state = v1::QUEUED;
  uint32_t priority = 50;
  uint32_t max_retries = 0;
  // Runs started, runs that failed, and runs in a row the server died
  // under while this job ran alone.
  uint32_t attempts = 0, failures = 0, crashes = 0;
  // The server died while this job ran beside others: it runs alone until
  // it gets on (a checkpoint) or its run ends, so that the next crash, if
  // it comes, is told apart from its neighbours'.
  bool run_alone = false;
  // Samples per pixel of the last checkpoint (of the final image once ended).
  uint32_t samples_done = 0, samples_total = 0;
  // Seconds since the Unix epoch; finished_at is 0 until the job ends.
  double submitted_at = 0, finished_at = 0;
  double elapsed_seconds = 0;
  uint64_t closest_hit_rays = 0, shadow_rays = 0;
  // Cancel was asked while the job ran: a restart ends it CANCELLED.
  bool cancel_requested = false;
};

class JobStore {
 public:
  // Opens or creates the database; throws StorageError (naming the file
  // and what to do) when it cannot be written or is not a sound job
  // database, and, changing nothing, when it is missing or empty although
  // `job_files` says what files of jobs the state folder holds (empty when
  // none), when its write-ahead log is damaged, or when the log is missing
  // although the last server did not close the database.
  explicit JobStore(const std::filesystem::path& file, const std::string& job_files = "");
  ~JobStore();
  JobStore(const JobStore&) = delete;
  JobStore& operator=(const JobStore&) = delete;

  // Stores a new job (record.number is ignored); returns its number.
  uint64_t Insert(const JobRecord& record);
  // Writes every field but the request.
  void Update(const JobRecord& record);
  // Every job, oldest first.
  std::vector<JobRecord> LoadAll() const;
  // Deletes ended jobs that finished before `finished_before`, and all but
  // the `keep` most recently finished; returns the numbers deleted.
  std::vector<uint64_t> DeleteEnded(double finished_before, uint64_t keep);
  // The highest number ever handed out (0 before the first job).
  uint64_t HighestNumber() const;
  // The schema version the file had when it was opened: 0 for a new one.
  int OpenedVersion() const { return opened_version_; }
  // Present from the opening of the database until it is closed cleanly.
  static std::filesystem::path OpenMarker(const std::filesystem::path& file);

 private:
  struct Close {
    void operator()(sqlite3* db) const;
  };
  std::filesystem::path file_;
  int opened_version_ = 0;
  mutable std::mutex mutex_;
  std::unique_ptr<sqlite3, Close> db_;
};

}  // namespace yarf
