// What happens to jobs, told to whoever watches the server (the job log,
// the metrics): one event per change of a job's state, and the progress of
// the renders between them.
#pragma once

#include <cstdint>
#include <mutex>
#include <ostream>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

namespace yarf {

enum class JobEventKind {
  kSubmitted,   // stored and queued
  kStarted,     // a run began (attempt counts them)
  kCheckpoint,  // the film was saved; a restart goes on from here
  kRequeued,    // a run ended and the job waits again: a failure with retries left, or the server stopping
  kFinished,    // SUCCEEDED
  kFailed,      // FAILED for good
  kCancelled,   // CANCELLED, queued or running
};

// "submitted", "started", ...: the `event` field of a log line.
std::string_view EventName(JobEventKind kind);

// What the job knows at the event. Times are in seconds.
struct JobEvent {
  JobEventKind kind = JobEventKind::kSubmitted;
  std::string job;    // its id
  std::string owner;
  uint32_t attempt = 0;
  uint32_t spp_done = 0, spp_total = 0;
  // Of the current run (0 before the first starts); for an ended job, its
  // last run's.
  double seconds = 0;
  // How long the job waited in the queue before this run (kStarted only).
  double queue_seconds = 0;
  uint64_t rays = 0;  // closest-hit and shadow rays, all runs
  std::string error;  // why it failed or runs again
};

// One value of an event's line.
using JobEventValue = std::variant<std::string, uint64_t, double>;
// The fields of `event`'s line, in order, without the empty ones that do
// not apply: the one definition both formats write.
std::vector<std::pair<std::string_view, JobEventValue>> JobEventFields(const JobEvent& event);
// `event=started job=job-000001 owner=local ...`; a value with spaces,
// quotes or `=` is quoted with JSON's escapes.
std::string FormatKeyValue(const JobEvent& event);
// `{"event":"started","job":"job-000001",...}` on one line.
std::string FormatJson(const JobEvent& event);

// Told of job events and of render progress, on the thread that makes the
// change: it must be quick and safe to call from several threads at once.
class JobObserver {
 public:
  virtual ~JobObserver() = default;
  virtual void OnJobEvent(const JobEvent& event) = 0;
  // Pixel samples and rays a running job rendered since its last call.
  virtual void OnProgress(uint64_t pixel_samples, uint64_t rays) = 0;
};

// One line per event on `out` (yarfd's stderr), key=value or JSON.
class JobLog final : public JobObserver {
 public:
  JobLog(std::ostream& out, bool json) : out_(out), json_(json) {}
  void OnJobEvent(const JobEvent& event) override;
  void OnProgress(uint64_t, uint64_t) override {}

 private:
  std::ostream& out_;
  const bool json_;
  std::mutex mutex_;  // one whole line at a time
};

// Tells each of several observers, in order.
class JobObservers final : public JobObserver {
 public:
  explicit JobObservers(std::vector<JobObserver*> observers) : observers_(std::move(observers)) {}
  void OnJobEvent(const JobEvent& event) override {
    for (JobObserver* observer : observers_) observer->OnJobEvent(event);
  }
  void OnProgress(uint64_t pixel_samples, uint64_t rays) override {
    for (JobObserver* observer : observers_) observer->OnProgress(pixel_samples, rays);
  }

 private:
  const std::vector<JobObserver*> observers_;
};

}  // namespace yarf
