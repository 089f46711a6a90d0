// One accepted render job: its durable row, its progress and, while it
// renders, its film. Every change of the row is written to the job store
// (through `persist`) before watchers see it.
#pragma once

#include <atomic>
#include <chrono>
#include <deque>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "components/remote_instance.h"
#include "kernel/film.h"
#include "kernel/film_target.h"
#include "kernel/image_io.h"
#include "service/job_components.h"
#include "service/job_events.h"
#include "service/job_files.h"
#include "service/job_store.h"
#include "yarf/v1/render.pb.h"

namespace yarf {

bool Ended(v1::JobState state);

class Job {
 public:
  using Persist = std::function<void(const JobRecord&)>;
  // The job's files in the state folder.
  struct Files {
    std::filesystem::path checkpoint, result;
  };
  struct RunSettings {
    // Least time between two checkpoints of the film.
    double checkpoint_seconds = 5;
  };
  enum class Outcome { kSucceeded, kFailed, kCancelled, kStopped };
  struct RunResult {
    Outcome outcome;
    std::string error;
  };

  // `request` is null for a job that has ended. `observer`, if any,
  // outlives the job and hears of each change of its state once stored.
  Job(std::string id, JobRecord record, std::shared_ptr<const v1::SubmitRequest> request, Files files,
      Persist persist, JobObserver* observer = nullptr);

  const std::string& id() const { return id_; }
  uint64_t number() const { return number_; }
  const std::string& owner() const { return owner_; }
  v1::JobStatus Status() const;
  // The job as an event of `kind` would tell it now.
  JobEvent Describe(JobEventKind kind) const;
  // Tells the observer, and the job's own log, an event of `kind`.
  void Tell(JobEventKind kind);
  // GetJob's answer: status, options, scene summary and log.
  v1::JobDetails Details() const;
  // Bumped on every change, for watchers.
  uint64_t Version() const;
  bool Finished() const;
  // The mesh assets the job's request names, while it has not ended.
  std::vector<std::string> Assets() const;
  uint32_t Priority() const;
  // The server died while this job ran beside others: the scheduler runs
  // it alone until it gets on or a run of it ends.
  bool RunsAlone() const;
  // Only the scheduler calls this, under its lock: the priority places
  // the job in its queue.
  void SetPriority(uint32_t priority);
  // A queued job ends CANCELLED at once (returns true); a running one
  // stops within a second; its row records the cancel at once, so that a
  // crash before then still ends it CANCELLED.
  bool RequestCancel();
  // The server is going down: a running job stops and waits, with its
  // checkpoint, for the next start.
  void RequestStop();
  // Pixels and variances so far: of the film while it renders, of the
  // stored image once the job has ended; false when there are none.
  bool Snapshot(std::vector<float>& pixels, std::vector<float>& variances, uint32_t& width,
                uint32_t& height) const;
  // The width and height Snapshot would give, without copying the pixels;
  // false when there is no image.
  bool ImageSize(uint32_t& width, uint32_t& height) const;
  // The arbitrary output variables of an image that is done (RenderOptions.aovs):
  // name and pixels [height, width, 3], in the order of kAovNames; none
  // while the image renders.
  std::vector<ImageLayer> AovSnapshot() const;

  // A run, on a worker thread: Begin marks the job RUNNING for one more
  // attempt (false if it no longer waits; throws StorageError, the job
  // still QUEUED, when that cannot be stored), Render renders it, EndRun
  // records how the run ended and returns true when the job is to be
  // queued again (it failed and has retries left). When the end of the run
  // cannot be stored, EndRun ends the job FAILED in memory only: its stored
  // row still says RUNNING, so the next start resumes it.
  bool Begin();
  RunResult Render(const JobResources& resources, const RunSettings& settings);
  bool EndRun(const RunResult& result);

 private:
  // Applies `change` to a copy of the row, stores it and publishes it, then
  // tells the observer what changed; nothing changes when `change` returns
  // false or the store fails.
  bool Commit(const std::function<bool(JobRecord&)>& change);
  // Commit, tried again a few times, with growing pauses, while the store
  // fails; then throws the last StorageError.
  bool CommitRetrying(const std::function<bool(JobRecord&)>& change);
  // The end of a run could not be stored: the job ends FAILED in memory
  // (so watchers stop waiting) and frees its film; its row and checkpoint
  // stay as they are for the next start to resume.
  void EndUnstored(const StorageError& error);
  // Progress of the render, shown to watchers but not stored.
  void Progress(uint32_t samples_done, uint64_t closest_hit_rays, uint64_t shadow_rays);
  // Render's work, in the job's task arena; throws what fails it.
  void RenderRun(const JobResources& resources, const RunSettings& settings);
  // EndRun's work; throws StorageError when the store keeps failing.
  bool StoreEndOfRun(const RunResult& result);
  void Finish(v1::JobState state, const std::string& error);
  // The checkpoint a resumable render goes on from, if there is a sound one
  // (of at most `spp` samples per pixel).
  std::optional<FilmCheckpoint> UsableCheckpoint(const v1::Film& film, uint32_t spp) const;
  void WriteCheckpoint(uint32_t samples_done);
  // Renders RenderOptions.aovs, each into a film of its own, once the image is done.
  void RenderAovs(JobComponents& parts, const KernelScene& kernel, const FilmTarget::Share& share);
  // Drops the films of a run (the image's and its aovs'): nothing renders
  // into them any more.
  void DropFilms();
  // Who the job's files belong to: this job, as of its current attempt.
  JobFileOwner FileOwner() const;
  // Tells the observer, and the job's own log, `event`; without mutex_ held.
  void Tell(const JobEvent& event);
  // Describe, with mutex_ held.
  JobEvent DescribeLocked(JobEventKind kind) const;
  // The event a change of the row from `before` to row_ makes, if any;
  // with mutex_ held.
  std::optional<JobEvent> EventOfChange(const JobRecord& before) const;

  const std::string id_;
  const uint64_t number_;
  const std::string owner_;
  const Files files_;
  const Persist persist_;
  JobObserver* const observer_;
  // Read by the worker thread; dropped, under mutex_, once the job ends.
  // Other threads copy the pointer under mutex_ before they read (Assets).
  std::shared_ptr<const v1::SubmitRequest> request_;
  // What GetJob tells of the request, kept after it is dropped; unset for
  // a job that had ended before this server started.
  const std::optional<v1::RenderOptions> options_;
  const std::optional<v1::SceneSummary> scene_summary_;
  // halt_ stops the render; cancel_ and stop_ say why.
  std::atomic<bool> halt_{false}, cancel_{false}, stop_{false};
  // Calls to components in other processes, ended at once by a halt.
  const std::shared_ptr<RemoteCalls> remote_calls_ = std::make_shared<RemoteCalls>();

  mutable std::mutex mutex_;
  JobRecord row_;
  uint32_t samples_done_ = 0, run_first_sample_ = 0;
  uint64_t closest_hit_rays_ = 0, shadow_rays_ = 0;
  std::chrono::steady_clock::time_point started_;
  // Since when the job waits in the queue: made, or last put back.
  std::chrono::steady_clock::time_point queued_since_ = std::chrono::steady_clock::now();
  // Pixels the current run renders (its crop, else the film), for the
  // pixel samples told to the observer.
  uint64_t run_pixels_ = 0;
  uint64_t version_ = 0;
  // The job's event lines since this server started, the last kMaxLogLines.
  std::deque<std::string> log_;

  // The film while rendering; once the job ends its image is on disk.
  std::unique_ptr<Film> film_;
  // The aovs' films, from the end of the image's render to the job's.
  std::vector<std::pair<std::string, std::unique_ptr<Film>>> aov_films_;
  // Shared by the render's threads as they add samples; held alone by
  // readers of the films and by whoever replaces them.
  mutable FilmLock film_mutex_;
  bool checkpoint_failed_ = false;
};

}  // namespace yarf
