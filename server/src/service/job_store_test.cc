#include "service/job_store.h"

#include <gtest/gtest.h>
#include <sqlite3.h>
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

std::string Bytes(const std::filesystem::path& file) { return ReadWholeFile(file).value(); }
void Overwrite(const std::filesystem::path& file, const std::string& bytes) {
  std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes;
}
// The message of the Error `read` throws, or "" if it throws none.
template <typename Read>
std::string RefusalOf(Read read) {
  try {
    read();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}
bool Says(const std::string& message, const std::string& part) { return message.find(part) != std::string::npos; }

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

// Runs `sql` on `file` with SQLite itself, as an older yarfd would have.
void RunSql(const std::filesystem::path& file, const std::string& sql) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(file.c_str(), &db), SQLITE_OK);
  char* message = nullptr;
  EXPECT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &message), SQLITE_OK) << (message ? message : "");
  sqlite3_free(message);
  sqlite3_close(db);
}

constexpr char kVersion1Table[] = R"sql(
CREATE TABLE jobs (
  number INTEGER PRIMARY KEY AUTOINCREMENT, request BLOB NOT NULL, name TEXT NOT NULL, owner TEXT NOT NULL,
  state INTEGER NOT NULL, priority INTEGER NOT NULL, max_retries INTEGER NOT NULL, attempts INTEGER NOT NULL,
  failures INTEGER NOT NULL, crashes INTEGER NOT NULL, samples_done INTEGER NOT NULL,
  samples_total INTEGER NOT NULL, error TEXT NOT NULL, submitted_at REAL NOT NULL, finished_at REAL NOT NULL,
  elapsed_seconds REAL NOT NULL, closest_hit_rays INTEGER NOT NULL, shadow_rays INTEGER NOT NULL)
)sql";

TEST(JobStore, DatabasesOfEarlierSchemasAreUpgradedKeepingTheirRows) {
  for (const int version : {1, 2}) {
    TempFolder folder;
    const auto file = folder.path() / "jobs.sqlite";
    std::string sql = std::string(kVersion1Table) + ";";
    if (version == 2) sql += "ALTER TABLE jobs ADD COLUMN cancel_requested INTEGER NOT NULL DEFAULT 0;";
    sql += "INSERT INTO jobs (number, request, name, owner, state, priority, max_retries, attempts, failures,"
           " crashes, samples_done, samples_total, error, submitted_at, finished_at, elapsed_seconds,"
           " closest_hit_rays, shadow_rays) VALUES (7, x'01', 'old', 'ann', 2, 50, 0, 1, 0, 2, 8, 16, '', 1, 0, 0,"
           " 0, 0); PRAGMA user_version = " +
           std::to_string(version) + ";";
    RunSql(file, sql);
    {
      JobStore store(file);
      EXPECT_EQ(store.OpenedVersion(), version);
      const std::vector<JobRecord> rows = store.LoadAll();
      ASSERT_EQ(rows.size(), 1u);
      EXPECT_EQ(rows[0].number, 7u);
      EXPECT_EQ(rows[0].state, v1::RUNNING);
      EXPECT_EQ(rows[0].crashes, 2u);
      EXPECT_FALSE(rows[0].cancel_requested);
      EXPECT_FALSE(rows[0].run_alone);
      JobRecord row = rows[0];
      row.run_alone = true;
      store.Update(row);
      EXPECT_EQ(store.HighestNumber(), 7u);
    }
    JobStore store(file);
    EXPECT_EQ(store.OpenedVersion(), 3);
    EXPECT_TRUE(store.LoadAll()[0].run_alone) << "version " << version;
    EXPECT_EQ(store.Insert(JobRecord{}), 8u);
  }
}

TEST(JobStore, TheHighestNumberOutlivesTheRowsItNumbered) {
  TempFolder folder;
  JobStore store(folder.path() / "jobs.sqlite");
  EXPECT_EQ(store.HighestNumber(), 0u);
  store.Insert(Ended(100));
  const uint64_t last = store.Insert(Ended(200));
  store.DeleteEnded(1e18, 0);
  EXPECT_TRUE(store.LoadAll().empty());
  EXPECT_EQ(store.HighestNumber(), last);
}

// A copy of the state of an open store, as a crash (kill -9) leaves it.
struct CrashedStore {
  std::filesystem::path file;
  std::string wal;
};

CrashedStore CrashWithRows(const std::filesystem::path& folder, int rows) {
  const auto live = folder / "live" / "jobs.sqlite";
  std::filesystem::create_directories(live.parent_path());
  std::filesystem::create_directories(folder / "crashed");
  const auto file = folder / "crashed" / "jobs.sqlite";
  JobStore store(live);
  for (int i = 0; i < rows; ++i) store.Insert(Ended(100 + i));
  for (const char* suffix : {"", "-wal", "-open"})
    std::filesystem::copy_file(live.string() + suffix, file.string() + suffix);
  return {file, Bytes(file.string() + "-wal")};
}

std::string RefusalToOpen(const std::filesystem::path& file, const std::string& job_files = "") {
  try {
    JobStore store(file, job_files);
  } catch (const StorageError& e) {
    return e.what();
  }
  return "";
}

TEST(JobStore, ACrashedStoreOpensWithEveryRowItCommitted) {
  TempFolder folder;
  const CrashedStore crashed = CrashWithRows(folder.path(), 3);
  EXPECT_EQ(RefusalToOpen(crashed.file), "");
  EXPECT_EQ(JobStore(crashed.file).LoadAll().size(), 3u);
}

TEST(JobStore, AMissingOrEmptyDatabaseIsRefusedWhenTheFolderHoldsFilesOfJobs) {
  TempFolder folder;
  const auto file = folder.path() / "jobs.sqlite";
  EXPECT_TRUE(Says(RefusalToOpen(file, "2 files in results"), "jobs.sqlite is missing, but the state folder holds 2 files in results"));
  EXPECT_FALSE(std::filesystem::exists(file)) << "the refusal created the database";
  Overwrite(file, "");
  EXPECT_TRUE(Says(RefusalToOpen(file, "2 files in results"), "jobs.sqlite is empty"));
  EXPECT_EQ(std::filesystem::file_size(file), 0u);
  EXPECT_EQ(RefusalToOpen(file), "") << "a fresh folder";
}

TEST(JobStore, ADamagedDatabaseIsRefusedSayingWhatToDo) {
  TempFolder folder;
  const auto file = folder.path() / "jobs.sqlite";
  Overwrite(file, std::string(8192, 'x'));
  const std::string refusal = RefusalToOpen(file, "1 file in results");
  EXPECT_TRUE(Says(refusal, "not a database")) << refusal;
  EXPECT_TRUE(Says(refusal, "nothing was changed")) << refusal;
  EXPECT_TRUE(Says(refusal, "1 file in results")) << refusal;
}

TEST(JobStore, AWalDamagedBeforeItsLastCommitIsRefused) {
  TempFolder folder;
  const CrashedStore crashed = CrashWithRows(folder.path(), 3);
  const auto wal = crashed.file.string() + "-wal";
  // A byte of the first frame's page: every commit after it would be dropped.
  std::string damaged = crashed.wal;
  damaged[32 + 24 + 100] ^= 1;
  Overwrite(wal, damaged);
  std::string refusal = RefusalToOpen(crashed.file);
  EXPECT_TRUE(Says(refusal, "jobs.sqlite-wal is damaged at frame 1")) << refusal;
  EXPECT_EQ(Bytes(wal), damaged) << "the refusal changed the log";
  // A damaged header: SQLite would ignore the whole log.
  damaged = crashed.wal;
  damaged[16] ^= 1;
  Overwrite(wal, damaged);
  refusal = RefusalToOpen(crashed.file);
  EXPECT_TRUE(Says(refusal, "damaged header")) << refusal;
}

TEST(JobStore, AWalCutOffInItsLastTransactionIsWhatACrashLeavesAndOpens) {
  TempFolder folder;
  const CrashedStore crashed = CrashWithRows(folder.path(), 3);
  // Torn in its last frame, as when the server died while writing it.
  Overwrite(crashed.file.string() + "-wal", crashed.wal.substr(0, crashed.wal.size() - 100));
  EXPECT_EQ(RefusalToOpen(crashed.file), "");
  // The last transaction is gone: no check of the log can tell a torn
  // transaction that was never acknowledged from a damaged one that was.
  EXPECT_EQ(JobStore(crashed.file).LoadAll().size(), 2u);
}

TEST(JobStore, AWalLostAfterACrashIsRefusedUntilTheMarkerIsRemoved) {
  TempFolder folder;
  const CrashedStore crashed = CrashWithRows(folder.path(), 3);
  std::filesystem::remove(crashed.file.string() + "-wal");
  const std::string refusal = RefusalToOpen(crashed.file);
  EXPECT_TRUE(Says(refusal, "was not closed by the last yarfd")) << refusal;
  EXPECT_TRUE(Says(refusal, "jobs.sqlite-wal is missing")) << refusal;
  std::filesystem::remove(JobStore::OpenMarker(crashed.file));
  EXPECT_EQ(RefusalToOpen(crashed.file), "") << "told to go on with what the database holds";
}

TEST(JobStore, AStoreClosedCleanlyLeavesNeitherLogNorMarker) {
  TempFolder folder;
  const auto file = folder.path() / "jobs.sqlite";
  {
    JobStore store(file);
    store.Insert(Ended(100));
    EXPECT_TRUE(std::filesystem::exists(JobStore::OpenMarker(file)));
  }
  EXPECT_FALSE(std::filesystem::exists(file.string() + "-wal"));
  EXPECT_FALSE(std::filesystem::exists(JobStore::OpenMarker(file)));
  EXPECT_EQ(JobStore(file).LoadAll().size(), 1u);
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
  const JobFileOwner owner{7, 2};
  WriteCheckpoint(folder.path() / "a.film", owner, 12, film.Save());
  const auto checkpoint = ReadCheckpoint(folder.path() / "a.film", owner);
  ASSERT_TRUE(checkpoint);
  EXPECT_EQ(checkpoint->samples_done, 12u);
  EXPECT_EQ(checkpoint->attempt, 2u);
  EXPECT_EQ(checkpoint->film.Pixels(), film.Pixels());
  EXPECT_FALSE(ReadCheckpoint(folder.path() / "missing.film", owner));

  const JobImage image{2, 1, {1, 2, 3, 4, 5, 6}, {0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.6f}};
  WriteJobImage(folder.path() / "a.image", owner, image);
  const auto read = ReadJobImage(folder.path() / "a.image", owner);
  ASSERT_TRUE(read);
  EXPECT_EQ(read->width, 2u);
  EXPECT_EQ(read->pixels, image.pixels);
  EXPECT_EQ(read->variances, image.variances);
  EXPECT_EQ(ReadJobImageSize(folder.path() / "a.image", owner), std::pair(2u, 1u));
  std::ofstream(folder.path() / "b.image") << "YARFIMG2 truncated";
  EXPECT_THROW(ReadJobImage(folder.path() / "b.image", owner), Error);
}

TEST(JobFiles, ACheckpointOfAnotherJobALaterAttemptOrChangedBytesIsRefused) {
  TempFolder folder;
  v1::ReconstructionFilter filter;
  Film film(2, 2, filter);
  film.Add(0.5f, 0.5f, {1, 2, 3});
  film.EndPass();
  const auto path = folder.path() / "a.film";
  WriteCheckpoint(path, {7, 2}, 12, film.Save());
  // An earlier attempt's checkpoint is what a run after a crash resumes.
  EXPECT_TRUE(ReadCheckpoint(path, {7, 3}));
  EXPECT_TRUE(Says(RefusalOf([&] { ReadCheckpoint(path, {8, 2}); }), "belongs to job number 7"));
  EXPECT_TRUE(Says(RefusalOf([&] { ReadCheckpoint(path, {7, 1}); }), "attempt 2"));
  const std::string good = Bytes(path);
  // samples_done, then a byte of the film, then the checksum itself.
  for (size_t offset : {size_t(8), good.size() / 2, good.size() - 1}) {
    std::string changed = good;
    changed[offset] ^= 1;
    Overwrite(path, changed);
    EXPECT_TRUE(Says(RefusalOf([&] { ReadCheckpoint(path, {7, 2}); }), "fails its checksum")) << offset;
  }
  Overwrite(path, "YARFCKP1" + good.substr(8));
  EXPECT_TRUE(Says(RefusalOf([&] { ReadCheckpoint(path, {7, 2}); }), "older yarfd"));
}

TEST(JobFiles, AnImageOfAnotherJobOrAttemptOrWithChangedBytesIsRefused) {
  TempFolder folder;
  const auto path = folder.path() / "a.image";
  const JobImage image{2, 1, {1, 2, 3, 4, 5, 6}, {0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.6f}};
  WriteJobImage(path, {7, 2}, image);
  for (const JobFileOwner other : {JobFileOwner{8, 2}, JobFileOwner{7, 1}, JobFileOwner{7, 3}}) {
    EXPECT_FALSE(RefusalOf([&] { ReadJobImage(path, other); }).empty());
    EXPECT_FALSE(RefusalOf([&] { ReadJobImageSize(path, other); }).empty());
  }
  const std::string good = Bytes(path);
  std::string changed = good;
  changed[40] ^= 0x40;  // a pixel
  Overwrite(path, changed);
  EXPECT_TRUE(Says(RefusalOf([&] { ReadJobImage(path, {7, 2}); }), "fails its checksum"));
}

TEST(JobFiles, AnImageWithoutPixelsIsRefused) {
  TempFolder folder;
  const auto path = folder.path() / "a.image";
  for (const auto [width, height] : {std::pair(0u, 2u), std::pair(3u, 0u), std::pair(0u, 0u)}) {
    WriteJobImage(path, {7, 2}, JobImage{width, height, {}, {}});
    EXPECT_TRUE(Says(RefusalOf([&] { ReadJobImage(path, {7, 2}); }), "is not a yarf image file")) << width;
    EXPECT_TRUE(Says(RefusalOf([&] { ReadJobImageSize(path, {7, 2}); }), "is not a yarf image file")) << width;
  }
}

TEST(JobFiles, AnImageOfAnOlderYarfdIsRefusedUntilItIsAdopted) {
  TempFolder folder;
  const auto path = folder.path() / "a.image";
  std::string legacy = "YARFIMG1";
  for (uint32_t value : {2u, 1u}) legacy.append(reinterpret_cast<const char*>(&value), 4);
  for (float value : {1.f, 2.f, 3.f, 4.f, 5.f, 6.f, .1f, .2f, .3f, .4f, .5f, .6f})
    legacy.append(reinterpret_cast<const char*>(&value), 4);
  Overwrite(path, legacy);
  EXPECT_TRUE(Says(RefusalOf([&] { ReadJobImage(path, {7, 2}); }), "older yarfd"));
  EXPECT_TRUE(UpgradeLegacyJobImage(path, {7, 2}));
  EXPECT_FALSE(UpgradeLegacyJobImage(path, {7, 2}));  // already bound
  const auto read = ReadJobImage(path, {7, 2});
  ASSERT_TRUE(read);
  EXPECT_EQ(read->pixels, (std::vector<float>{1, 2, 3, 4, 5, 6}));
  EXPECT_THROW(ReadJobImage(path, {8, 2}), Error);
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

TEST(Job, AJobToRunAloneRunsBesideOthersAgainOnceARunOfItEnds) {
  TempFolder folder;
  JobRecord retried;
  retried.max_retries = 1;
  for (const auto& [outcome, row] :
       {std::pair(Job::Outcome::kStopped, JobRecord{}), std::pair(Job::Outcome::kFailed, retried),
        std::pair(Job::Outcome::kFailed, JobRecord{}), std::pair(Job::Outcome::kSucceeded, JobRecord{})}) {
    JobRecord alone = row;
    alone.run_alone = true;
    RecordedJob job(folder.path(), alone);
    EXPECT_TRUE(job->RunsAlone());
    ASSERT_TRUE(job->Begin());
    job->EndRun({outcome, "broken"});
    EXPECT_FALSE(job.rows.back().run_alone);
    EXPECT_FALSE(job->RunsAlone());
  }
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
