#include "service/job_store.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>

#include "service/job.h"
#include "service/job_files.h"
#include "service/state_folder.h"
#include "yarf/error.h"

namespace yarf {
namespace {

// A fresh folder, removed at the end.
class TempFolder {
 public:
  TempFolder() {
    std::string pattern = (std::filesystem::temp_directory_path() / "yarf-store-XXXXXX").string();
    path_ = ::mkdtemp(pattern.data());
  }
  ~TempFolder() { std::filesystem::remove_all(path_); }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

JobRecord Ended(double finished_at) {
  JobRecord r;
  r.request = "request bytes";
  r.state = v1::SUCCEEDED;
  r.finished_at = finished_at;
  return r;
}

TEST(JobStore, RowsSurviveReopeningAndNumbersAreNeverReused) {
  TempFolder folder;
  const auto file = folder.path() / "jobs.sqlite";
  uint64_t first = 0, second = 0;
  {
    JobStore store(file);
    JobRecord r;
    r.request = std::string("\0binary\xff", 8);
    r.name = "a job";
    r.owner = "ann";
    r.priority = 70;
    r.max_retries = 2;
    r.samples_total = 64;
    r.submitted_at = 1234.5;
    first = store.Insert(r);
    second = store.Insert(r);
    r.number = first;
    r.state = v1::RUNNING;
    r.attempts = 1;
    r.samples_done = 16;
    r.cancel_requested = true;
    store.Update(r);
    EXPECT_EQ(store.DeleteEnded(1e18, 0), std::vector<uint64_t>{});  // none has ended
    r.number = second;
    r.state = v1::FAILED;
    r.finished_at = 2000;
    store.Update(r);
    EXPECT_EQ(store.DeleteEnded(0, 0), std::vector<uint64_t>{second});
  }
  JobStore store(file);
  const std::vector<JobRecord> rows = store.LoadAll();
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].number, first);
  EXPECT_EQ(rows[0].request, std::string("\0binary\xff", 8));
  EXPECT_EQ(rows[0].name, "a job");
  EXPECT_EQ(rows[0].owner, "ann");
  EXPECT_EQ(rows[0].state, v1::RUNNING);
  EXPECT_EQ(rows[0].priority, 70u);
  EXPECT_EQ(rows[0].attempts, 1u);
  EXPECT_EQ(rows[0].samples_done, 16u);
  EXPECT_TRUE(rows[0].cancel_requested);
  EXPECT_DOUBLE_EQ(rows[0].submitted_at, 1234.5);
  EXPECT_GT(store.Insert(JobRecord{}), second);
  EXPECT_FALSE(store.LoadAll().back().cancel_requested);
}

TEST(JobStore, RetentionDeletesTheOldestEndedJobsBeyondTheLimits) {
  TempFolder folder;
  JobStore store(folder.path() / "jobs.sqlite");
  const uint64_t a = store.Insert(Ended(100)), b = store.Insert(Ended(300)), c = store.Insert(Ended(200));
  store.Insert(JobRecord{});  // queued: never deleted
  EXPECT_EQ(store.DeleteEnded(0, 2), std::vector<uint64_t>{a});
  EXPECT_EQ(store.DeleteEnded(250, 10), std::vector<uint64_t>{c});
  EXPECT_EQ(store.LoadAll().size(), 2u);
  EXPECT_EQ(store.LoadAll()[0].number, b);
  EXPECT_TRUE(store.LoadAll()[0].request.empty());  // an ended job's request stays on disk
}

TEST(JobStore, AFileThatIsNotADatabaseIsRefusedNamingIt) {
  TempFolder folder;
  const auto file = folder.path() / "jobs.sqlite";
  std::ofstream(file) << std::string(4096, 'x');
  try {
    JobStore store(file);
    FAIL() << "a damaged database was opened";
  } catch (const StorageError& e) {
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
  }
}

TEST(StateFolder, ASecondHolderOfTheSameFolderIsRefused) {
  TempFolder folder;
  StateFolder first(folder.path() / "state");
  EXPECT_TRUE(std::filesystem::is_directory(first.Checkpoints()));
  try {
    StateFolder second(folder.path() / "state");
    FAIL() << "two holders of one state folder";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("another yarfd"), std::string::npos) << e.what();
  }
}

TEST(JobFiles, CheckpointsAndImagesRoundTrip) {
  TempFolder folder;
  v1::ReconstructionFilter filter;
  Film film(2, 2, filter);
  film.Add(0.5f, 0.5f, {1, 2, 3});
  film.EndPass();
  WriteCheckpoint(folder.path() / "a.film", 12, film.Save());
  const auto checkpoint = ReadCheckpoint(folder.path() / "a.film");
  ASSERT_TRUE(checkpoint);
  EXPECT_EQ(checkpoint->samples_done, 12u);
  EXPECT_EQ(checkpoint->film.Pixels(), film.Pixels());
  EXPECT_FALSE(ReadCheckpoint(folder.path() / "missing.film"));

  const JobImage image{2, 1, {1, 2, 3, 4, 5, 6}, {0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.6f}};
  WriteJobImage(folder.path() / "a.image", image);
  const auto read = ReadJobImage(folder.path() / "a.image");
  ASSERT_TRUE(read);
  EXPECT_EQ(read->width, 2u);
  EXPECT_EQ(read->pixels, image.pixels);
  EXPECT_EQ(read->variances, image.variances);
  std::ofstream(folder.path() / "b.image") << "YARFIMG1 truncated";
  EXPECT_THROW(ReadJobImage(folder.path() / "b.image"), Error);
}

// A job whose stored rows are recorded with whether its checkpoint file
// existed when each was stored.
class RecordedJob {
 public:
  explicit RecordedJob(const std::filesystem::path& folder, JobRecord row = {})
      : files_{folder / "job-000001.film", folder / "job-000001.image"} {
    row.number = 1;
    job_ = std::make_unique<Job>("job-000001", row, std::make_shared<v1::SubmitRequest>(), files_,
                                 [this](const JobRecord& stored) {
                                   ++stores;
                                   if (failures_left != 0) {
                                     if (failures_left > 0) --failures_left;
                                     throw StorageError("database or disk is full");
                                   }
                                   rows.push_back(stored);
                                   had_checkpoint.push_back(std::filesystem::exists(files_.checkpoint));
                                 });
  }
  Job& operator*() { return *job_; }
  Job* operator->() { return job_.get(); }
  void Checkpoint() const { std::ofstream(files_.checkpoint) << "a film"; }
  bool HasCheckpoint() const { return std::filesystem::exists(files_.checkpoint); }

  std::vector<JobRecord> rows;
  std::vector<bool> had_checkpoint;
  // Stores tried, and how many of the next ones fail (-1: all of them).
  int stores = 0, failures_left = 0;

 private:
  Job::Files files_;
  std::unique_ptr<Job> job_;
};

TEST(Job, AFailedRunDropsItsCheckpointBeforeItIsQueuedAgain) {
  TempFolder folder;
  JobRecord row;
  row.max_retries = 1;
  RecordedJob job(folder.path(), row);
  job.Checkpoint();
  ASSERT_TRUE(job->Begin());
  EXPECT_TRUE(job->EndRun({Job::Outcome::kFailed, "broken"}));
  EXPECT_EQ(job.rows.back().state, v1::QUEUED);
  EXPECT_FALSE(job.had_checkpoint.back()) << "a crash now would resume from the failed run's film";
}

TEST(Job, AnEndedRunKeepsItsCheckpointUntilTheEndIsStored) {
  TempFolder folder;
  for (const auto& [outcome, state] : {std::pair(Job::Outcome::kSucceeded, v1::SUCCEEDED),
                                      std::pair(Job::Outcome::kCancelled, v1::CANCELLED)}) {
    RecordedJob job(folder.path());
    job.Checkpoint();
    ASSERT_TRUE(job->Begin());
    EXPECT_FALSE(job->EndRun({outcome, ""}));
    EXPECT_EQ(job.rows.back().state, state);
    EXPECT_TRUE(job.had_checkpoint.back()) << "a crash before the end was stored would redo the run";
    EXPECT_FALSE(job.HasCheckpoint());
  }
}

TEST(Job, ACleanStopEndsTheRunOfCrashes) {
  TempFolder folder;
  JobRecord row;
  row.crashes = 2;
  RecordedJob job(folder.path(), row);
  ASSERT_TRUE(job->Begin());
  EXPECT_FALSE(job->EndRun({Job::Outcome::kStopped, ""}));
  EXPECT_EQ(job.rows.back().state, v1::QUEUED);
  EXPECT_EQ(job.rows.back().crashes, 0u);
}

TEST(Job, ACancelOfARunningJobIsStoredAtOnce) {
  TempFolder folder;
  RecordedJob job(folder.path());
  ASSERT_TRUE(job->Begin());
  EXPECT_FALSE(job->RequestCancel());  // it ends through its run
  EXPECT_EQ(job.rows.back().state, v1::RUNNING);
  EXPECT_TRUE(job.rows.back().cancel_requested);
  EXPECT_FALSE(job->EndRun({Job::Outcome::kCancelled, ""}));
  EXPECT_EQ(job.rows.back().state, v1::CANCELLED);
}

TEST(Job, AnEndOfRunTheStoreKeepsRefusingEndsTheJobInMemoryForARestartToResume) {
  TempFolder folder;
  JobRecord retried;
  retried.max_retries = 1;
  for (const auto& [outcome, row] :
       {std::pair(Job::Outcome::kSucceeded, JobRecord{}), std::pair(Job::Outcome::kCancelled, JobRecord{}),
        std::pair(Job::Outcome::kFailed, JobRecord{}), std::pair(Job::Outcome::kFailed, retried),
        std::pair(Job::Outcome::kStopped, JobRecord{})}) {
    RecordedJob job(folder.path(), row);
    ASSERT_TRUE(job->Begin());
    job.Checkpoint();
    const uint64_t version = job->Version();
    job.failures_left = -1;
    EXPECT_FALSE(job->EndRun({outcome, "broken"})) << "queued again without a stored row";
    EXPECT_GT(job.stores, 2) << "not tried again";
    // Watchers see it end...
    EXPECT_TRUE(job->Finished());
    EXPECT_GT(job->Version(), version);
    const v1::JobStatus status = job->Status();
    EXPECT_EQ(status.state(), v1::FAILED);
    EXPECT_NE(status.error().find("could not be stored"), std::string::npos) << status.error();
    EXPECT_NE(status.error().find("database or disk is full"), std::string::npos) << status.error();
    // ...while the store still says RUNNING: a restart resumes the run.
    EXPECT_EQ(job.rows.back().state, v1::RUNNING);
    if (outcome != Job::Outcome::kFailed) {
      EXPECT_TRUE(job.HasCheckpoint()) << "nothing left to resume from";
    }
    EXPECT_FALSE(job->RequestCancel());
  }
}

TEST(Job, AStoreThatFailsBrieflyIsTriedAgain) {
  TempFolder folder;
  RecordedJob job(folder.path());
  job.failures_left = 2;
  ASSERT_TRUE(job->Begin());
  job.failures_left = 2;
  EXPECT_FALSE(job->EndRun({Job::Outcome::kSucceeded, ""}));
  EXPECT_EQ(job.rows.back().state, v1::SUCCEEDED);
  EXPECT_EQ(job->Status().state(), v1::SUCCEEDED);
  EXPECT_EQ(job.stores, 6);
}

TEST(Job, AStartTheStoreRefusesLeavesTheJobQueued) {
  TempFolder folder;
  RecordedJob job(folder.path());
  job.failures_left = -1;
  EXPECT_THROW(job->Begin(), StorageError);
  EXPECT_EQ(job->Status().state(), v1::QUEUED);
  EXPECT_EQ(job->Status().attempts(), 0u);
  EXPECT_FALSE(job->Finished());
  job.failures_left = 0;
  ASSERT_TRUE(job->Begin()) << "the job no longer waits";
  EXPECT_EQ(job.rows.back().state, v1::RUNNING);
  EXPECT_EQ(job.rows.back().attempts, 1u);
}

}  // namespace
}  // namespace yarf
