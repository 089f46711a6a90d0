// The durable job table: one SQLite database in the state folder (WAL,
// synchronous FULL), so that an accepted job survives a crash of the
// server. Every call commits before it returns.
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
  // Runs started, runs that failed, and runs in a row the server died under.
  uint32_t attempts = 0, failures = 0, crashes = 0;
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
  // Opens or creates the database; throws StorageError (naming the file) when it
  // cannot be written or is not a sound job database.
  explicit JobStore(const std::filesystem::path& file);
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

 private:
  struct Close {
    void operator()(sqlite3* db) const;
  };
  std::filesystem::path file_;
  mutable std::mutex mutex_;
  std::unique_ptr<sqlite3, Close> db_;
};

}  // namespace yarf
