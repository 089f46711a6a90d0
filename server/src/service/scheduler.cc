#include "service/scheduler.h"

#include <algorithm>
#include <chrono>

namespace yarf {

void Scheduler::Start(uint32_t workers) {
  for (uint32_t i = 0; i < std::max(workers, 1u); ++i)
    workers_.emplace_back([this](std::stop_token stop) { Work(stop); });
}

Scheduler::~Scheduler() {
  Stop();
  for (auto& worker : workers_) worker.request_stop();
  workers_.clear();  // joins
}

void Scheduler::Enqueue(std::shared_ptr<Job> job) {
  {
    std::lock_guard lock(mutex_);
    if (stopped_) return;
    const Place place = PlaceOf(job->Priority(), job->number());
    queue_[place] = std::move(job);
  }
  // All: a worker may wait for a job to run alone that this one now precedes.
  queued_.notify_all();
}

void Scheduler::SetPriority(Job& job, uint32_t priority) {
  std::lock_guard lock(mutex_);
  // The head may change.
  queued_.notify_all();
  // The place is taken under this lock, so it matches the priority the
  // job had when it was queued.
  auto it = queue_.find(PlaceOf(job.Priority(), job.number()));
  job.SetPriority(priority);
  if (it == queue_.end()) return;
  std::shared_ptr<Job> queued = std::move(it->second);
  queue_.erase(it);
  queue_[PlaceOf(priority, job.number())] = std::move(queued);
}

void Scheduler::Remove(const Job& job) {
  {
    std::lock_guard lock(mutex_);
    queue_.erase(PlaceOf(job.Priority(), job.number()));
  }
  // The head may have been a job to run alone that the others waited for.
  queued_.notify_all();
}

void Scheduler::Stop() {
  {
    std::lock_guard lock(mutex_);
    stopped_ = true;
    queue_.clear();
  }
  queued_.notify_all();
}

void Scheduler::Join() {
  Stop();
  for (auto& worker : workers_)
    if (worker.joinable()) worker.join();
}

bool Scheduler::HeadMayStart() const {
  if (queue_.empty() || (alone_ && alone_->RunsAlone())) return false;
  return running_ == 0 || !queue_.begin()->second->RunsAlone();
}

void Scheduler::Work(std::stop_token stop) {
  for (;;) {
    std::shared_ptr<Job> job;
    {
      std::unique_lock lock(mutex_);
      // A job running alone that gets on tells no one: looked at again
      // every second.
      while (!queued_.wait_for(lock, stop, std::chrono::seconds(1), [&] { return stopped_ || HeadMayStart(); }))
        if (stop.stop_requested()) return;
      if (stopped_ || stop.stop_requested()) return;
      auto next = queue_.begin();
      job = std::move(next->second);
      queue_.erase(next);
      ++running_;
      if (job->RunsAlone()) alone_ = job;
    }
    run_(job);
    {
      std::lock_guard lock(mutex_);
      --running_;
      if (alone_ == job) alone_.reset();
    }
    queued_.notify_all();
  }
}

}  // namespace yarf
