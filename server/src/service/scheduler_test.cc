#include "service/scheduler.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>

namespace yarf {
namespace {

std::shared_ptr<Job> QueuedJob(uint64_t number, uint32_t priority) {
  JobRecord row;
  row.number = number;
  row.priority = priority;
  return std::make_shared<Job>("job-" + std::to_string(number), row, std::make_shared<v1::SubmitRequest>(),
                               Job::Files{}, [](const JobRecord&) {});
}

// The numbers of the jobs the scheduler ran, in the order it ran them.
class Recorder {
 public:
  void Run(const std::shared_ptr<Job>& job) {
    std::lock_guard lock(mutex_);
    order_.push_back(job->number());
    ran_.notify_all();
  }
  std::vector<uint64_t> WaitFor(size_t count) {
    std::unique_lock lock(mutex_);
    ran_.wait_for(lock, std::chrono::seconds(10), [&] { return order_.size() >= count; });
    return order_;
  }

 private:
  std::mutex mutex_;
  std::condition_variable ran_;
  std::vector<uint64_t> order_;
};

TEST(Scheduler, StartsTheHighestPriorityFirstAndTheOldestWithinAPriority) {
  Recorder recorder;
  Scheduler scheduler([&](const std::shared_ptr<Job>& job) { recorder.Run(job); });
  const uint32_t priorities[] = {10, 90, 50, 90, 10, 50};
  std::vector<std::shared_ptr<Job>> jobs;
  for (uint64_t n = 1; n <= 6; ++n) jobs.push_back(QueuedJob(n, priorities[n - 1]));
  for (const auto& job : jobs) scheduler.Enqueue(job);
  scheduler.SetPriority(*jobs[4], 95);  // job 5 moves to the front
  EXPECT_EQ(jobs[4]->Priority(), 95u);
  scheduler.Remove(*jobs[5]);  // job 6 leaves the queue
  scheduler.Start(1);
  EXPECT_EQ(recorder.WaitFor(5), (std::vector<uint64_t>{5, 2, 4, 3, 1}));
}

TEST(Scheduler, AStoppedSchedulerStartsNothingMore) {
  Recorder recorder;
  Scheduler scheduler([&](const std::shared_ptr<Job>& job) { recorder.Run(job); });
  scheduler.Enqueue(QueuedJob(1, 50));
  scheduler.Stop();
  scheduler.Enqueue(QueuedJob(2, 50));
  scheduler.Start(2);
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_TRUE(recorder.WaitFor(0).empty());
}

TEST(Scheduler, JoinWaitsForTheJobsBeingRun) {
  std::atomic<bool> started{false}, finished{false};
  Scheduler scheduler([&](const std::shared_ptr<Job>&) {
    started = true;
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    finished = true;
  });
  scheduler.Enqueue(QueuedJob(1, 50));
  scheduler.Enqueue(QueuedJob(2, 50));
  scheduler.Start(1);
  while (!started) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  scheduler.Join();
  EXPECT_TRUE(finished);
}

}  // namespace
}  // namespace yarf
