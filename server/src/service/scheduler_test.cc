#include "service/scheduler.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <set>

namespace yarf {
namespace {

std::shared_ptr<Job> QueuedJob(uint64_t number, uint32_t priority, bool run_alone = false) {
  JobRecord row;
  row.number = number;
  row.priority = priority;
  row.run_alone = run_alone;
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

// Runs each job until the test lets it end, and tells which jobs run.
class Gate {
 public:
  void Run(const std::shared_ptr<Job>& job) {
    std::unique_lock lock(mutex_);
    running_.insert(job->number());
    changed_.notify_all();
    changed_.wait(lock, [&] { return open_ || released_.contains(job->number()); });
    running_.erase(job->number());
    changed_.notify_all();
  }
  void Release(uint64_t number) {
    std::lock_guard lock(mutex_);
    released_.insert(number);
    changed_.notify_all();
  }
  // Lets every run end, now and later: call it before the scheduler goes.
  void Open() {
    std::lock_guard lock(mutex_);
    open_ = true;
    changed_.notify_all();
  }
  // Waits until exactly `expected` run, then a little longer to see that
  // nothing else starts; returns what runs then.
  std::set<uint64_t> Running(const std::set<uint64_t>& expected) {
    std::unique_lock lock(mutex_);
    changed_.wait_for(lock, std::chrono::seconds(10), [&] { return running_ == expected; });
    changed_.wait_for(lock, std::chrono::milliseconds(100), [&] { return running_ != expected; });
    return running_;
  }

 private:
  std::mutex mutex_;
  std::condition_variable changed_;
  std::set<uint64_t> running_, released_;
  bool open_ = false;
};

TEST(Scheduler, AJobToRunAloneStartsWhenNoneRunsAndNoneStartsBesideIt) {
  Gate gate;
  Scheduler scheduler([&](const std::shared_ptr<Job>& job) { gate.Run(job); });
  scheduler.Start(3);
  scheduler.Enqueue(QueuedJob(1, 50));
  EXPECT_EQ(gate.Running({1}), std::set<uint64_t>{1});
  // Job 2 is next but must run alone: neither it nor job 3 behind it
  // starts while job 1 runs, though workers are free.
  scheduler.Enqueue(QueuedJob(2, 50, true));
  scheduler.Enqueue(QueuedJob(3, 50));
  EXPECT_EQ(gate.Running({1}), std::set<uint64_t>{1});
  gate.Release(1);
  EXPECT_EQ(gate.Running({2}), std::set<uint64_t>{2});
  // Nothing starts beside it, whatever its priority.
  scheduler.Enqueue(QueuedJob(4, 100));
  EXPECT_EQ(gate.Running({2}), std::set<uint64_t>{2});
  gate.Release(2);
  EXPECT_EQ(gate.Running({3, 4}), (std::set<uint64_t>{3, 4}));
  gate.Open();
}

TEST(Scheduler, AJobRunningAloneThatGetsOnLetsOthersStartBesideIt) {
  Gate gate;
  Scheduler scheduler([&](const std::shared_ptr<Job>& job) {
    if (job->RunsAlone()) {
      // Its run gets on (here: a stop, which clears it as a checkpoint does).
      job->Begin();
      job->EndRun({Job::Outcome::kStopped, ""});
    }
    gate.Run(job);
  });
  const auto alone = QueuedJob(1, 50, true);
  scheduler.Enqueue(alone);
  scheduler.Start(2);
  scheduler.Enqueue(QueuedJob(2, 50));
  EXPECT_EQ(gate.Running({1, 2}), (std::set<uint64_t>{1, 2}));
  gate.Open();
}

TEST(Scheduler, AJobToRunAloneDoesNotHoldBackTheJobsAheadOfIt) {
  Gate gate;
  Scheduler scheduler([&](const std::shared_ptr<Job>& job) { gate.Run(job); });
  scheduler.Enqueue(QueuedJob(1, 10, true));
  scheduler.Enqueue(QueuedJob(2, 90));
  scheduler.Enqueue(QueuedJob(3, 90));
  scheduler.Start(2);
  EXPECT_EQ(gate.Running({2, 3}), (std::set<uint64_t>{2, 3}));
  gate.Release(2);
  EXPECT_EQ(gate.Running({3}), std::set<uint64_t>{3});
  gate.Release(3);
  EXPECT_EQ(gate.Running({1}), std::set<uint64_t>{1});
  gate.Open();
}

TEST(Scheduler, RemovingAJobToRunAloneLetsTheOthersStart) {
  Gate gate;
  Scheduler scheduler([&](const std::shared_ptr<Job>& job) { gate.Run(job); });
  scheduler.Start(2);
  scheduler.Enqueue(QueuedJob(1, 50));
  EXPECT_EQ(gate.Running({1}), std::set<uint64_t>{1});
  const auto alone = QueuedJob(2, 50, true);
  scheduler.Enqueue(alone);
  scheduler.Enqueue(QueuedJob(3, 50));
  EXPECT_EQ(gate.Running({1}), std::set<uint64_t>{1});
  scheduler.Remove(*alone);  // cancelled while it waits
  EXPECT_EQ(gate.Running({1, 3}), (std::set<uint64_t>{1, 3}));
  gate.Open();
}

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
