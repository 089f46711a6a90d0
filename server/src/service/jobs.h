// The job table: accepted render jobs, kept in the state folder's job
// store so that they survive a restart, and run by the scheduler a few at
// a time while the server stays responsive.
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "service/job.h"
#include "service/job_store.h"
#include "service/limits.h"
#include "service/scheduler.h"
#include "service/state_folder.h"
#include "yarf/v1/render.pb.h"

namespace yarf {

struct JobQueueOptions {
  // Jobs that render at once.
  uint32_t max_running_jobs = 2;
  // Least time between two checkpoints of a rendering film.
  double checkpoint_seconds = 5;
  // Ended jobs (and their images) are deleted after this many hours...
  double keep_finished_hours = 168;
  // ...and beyond this many, the oldest first.
  uint64_t max_finished_jobs = 1000;
  // Jobs not ended one user may have.
  uint64_t max_queued_jobs_per_user = 1000;
  // The most memory one job may be estimated to need (job_memory.h).
  uint64_t max_job_bytes = uint64_t(8) << 30;
  // Uploaded assets no job still to run names, unused this long, are deleted.
  double asset_grace_hours = 24;
};


class JobManager {
 public:
  // Opens the job store of `folder` (locked by the caller, and outliving
  // this) and takes back the jobs a previous server left: queued ones wait
  // again, those it was running resume (or fail, if the server died under
  // them too often; or end CANCELLED, if a cancel was asked). Throws Error
  // or StorageError when the folder or the store is unusable. `observer`,
  // if any, outlives this and hears of every job's events (job_events.h).
  JobManager(JobResources resources, JobQueueOptions options, const StateFolder& folder,
             JobObserver* observer = nullptr);
  // StopAll().
  ~JobManager();
  JobManager(const JobManager&) = delete;
  JobManager& operator=(const JobManager&) = delete;

  // Starts running jobs: call once the server listens, since a job's
  // components in other processes may call it back.
  void Start();
  // Starts no more jobs and stops the running ones (they wait, QUEUED, for
  // the next start), then waits for their runs to end. Call it before the
  // server shuts down: a job's components in other processes may call it
  // back until their run ends.
  void StopAll();
  // Validates and stores a job of `owner`, then queues it; throws Error
  // for a scene or options it refuses, StorageError when it cannot store it.
  // What the job runs as asked but not at its best goes to `warnings`
  // (SubmitWarnings), when given.
  std::string Submit(const v1::SubmitRequest& request, const std::string& owner,
                     std::vector<std::string>* warnings = nullptr);
  std::shared_ptr<Job> Find(const std::string& id) const;
  // Newest first.
  std::vector<std::shared_ptr<Job>> List() const;
  void Cancel(Job& job);
  // False for a job that has ended; throws Error for a priority outside 1..100.
  bool SetPriority(Job& job, uint32_t priority);

 private:
  void Restore();
  // Ends the row of a job cancelled before a crash.
  void EndCancelled(JobRecord& row) const;
  // Binds the image an older yarfd left for an ended job to that job.
  void AdoptLegacyResult(const JobRecord& row) const;
  void RunJob(const std::shared_ptr<Job>& job);
  // Deletes ended jobs past the retention limits, with their files.
  void ApplyRetention();
  void CollectAssets();
  void RemoveStrayFiles() const;
  std::shared_ptr<Job> MakeJob(JobRecord record, std::shared_ptr<const v1::SubmitRequest> request);

  const JobResources resources_;
  const JobQueueOptions options_;
  const StateFolder& folder_;
  JobObserver* const observer_;
  JobStore store_;
  mutable std::mutex mutex_;
  // Asset collection: one sweep at a time, and when the last one was.
  std::mutex collection_mutex_;
  std::optional<std::chrono::steady_clock::time_point> last_collection_;
  std::map<uint64_t, std::shared_ptr<Job>> jobs_;
  // Last: its workers use the members above.
  Scheduler scheduler_;
};

}  // namespace yarf
