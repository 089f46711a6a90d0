// Which queued job runs next, and the workers that run them: at most
// `workers` jobs at once; the highest priority first, first come first
// served within a priority. A job to run alone (Job::RunsAlone: the server
// died while it ran beside others) starts only when no other runs, and no
// other starts while it runs, until it gets on (a checkpoint clears it);
// until it can start, the jobs behind it wait too, so that it is not put
// off for ever.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <stop_token>
#include <thread>
#include <utility>
#include <vector>

#include "service/job.h"

namespace yarf {

class Scheduler {
 public:
  using RunJob = std::function<void(const std::shared_ptr<Job>&)>;

  // Runs each job it starts with `run`.
  explicit Scheduler(RunJob run) : run_(std::move(run)) {}
  // Stop(), then waits for the jobs being run to return.
  ~Scheduler();
  Scheduler(const Scheduler&) = delete;
  Scheduler& operator=(const Scheduler&) = delete;

  // Starts `workers` threads, each running one job at a time. Jobs queued
  // before wait until then.
  void Start(uint32_t workers);
  void Enqueue(std::shared_ptr<Job> job);
  // Changes the job's priority, moving it in the queue if it waits there.
  void SetPriority(Job& job, uint32_t priority);
  // Takes the job out of the queue (a cancel while it waits).
  void Remove(const Job& job);
  // No job starts any more.
  void Stop();
  // Stop(), then waits for the jobs being run to return. Not from a job's run.
  void Join();

 private:
  // Highest priority first, then the lowest job number (the oldest).
  using Place = std::pair<int64_t, uint64_t>;
  static Place PlaceOf(uint32_t priority, uint64_t number) { return {-int64_t(priority), number}; }
  void Work(std::stop_token stop);
  // Whether the job at the head of the queue may start now; under mutex_.
  bool HeadMayStart() const;

  const RunJob run_;
  std::mutex mutex_;
  std::condition_variable_any queued_;
  bool stopped_ = false;
  std::map<Place, std::shared_ptr<Job>> queue_;
  // Jobs being run, and the one among them that runs alone, if any.
  uint32_t running_ = 0;
  std::shared_ptr<Job> alone_;
  // Last: the workers use the members above.
  std::vector<std::jthread> workers_;
};

}  // namespace yarf
