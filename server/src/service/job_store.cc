#include "service/job_store.h"

#include <sqlite3.h>

#include <optional>
#include <system_error>
#include <utility>

#include "service/sqlite_wal.h"
#include "service/state_folder.h"
#include "yarf/error.h"

namespace yarf {
namespace {

// Bumped when the schema changes, so a newer database is refused rather
// than misread.
constexpr int kSchemaVersion = 3;

// AUTOINCREMENT: numbers of deleted jobs are never handed out again.
constexpr char kSchema[] = R"sql(
CREATE TABLE IF NOT EXISTS jobs (
  number INTEGER PRIMARY KEY AUTOINCREMENT,
  request BLOB NOT NULL,
  name TEXT NOT NULL,
  owner TEXT NOT NULL,
  state INTEGER NOT NULL,
  priority INTEGER NOT NULL,
  max_retries INTEGER NOT NULL,
  attempts INTEGER NOT NULL,
  failures INTEGER NOT NULL,
  crashes INTEGER NOT NULL,
  samples_done INTEGER NOT NULL,
  samples_total INTEGER NOT NULL,
  error TEXT NOT NULL,
  submitted_at REAL NOT NULL,
  finished_at REAL NOT NULL,
  elapsed_seconds REAL NOT NULL,
  closest_hit_rays INTEGER NOT NULL,
  shadow_rays INTEGER NOT NULL,
  cancel_requested INTEGER NOT NULL DEFAULT 0,
  run_alone INTEGER NOT NULL DEFAULT 0);
CREATE INDEX IF NOT EXISTS jobs_ended ON jobs (finished_at) WHERE finished_at > 0;
)sql";

// Columns tables of older versions lack, and how they get them.
constexpr std::pair<const char*, const char*> kAddedColumns[] = {
    {"cancel_requested", "INTEGER NOT NULL DEFAULT 0"},  // version 2
    {"run_alone", "INTEGER NOT NULL DEFAULT 0"},         // version 3
};

bool EndedState(int state) { return state == v1::SUCCEEDED || state == v1::FAILED || state == v1::CANCELLED; }

// One prepared statement, finalized when it goes.
class Statement {
 public:
  Statement(sqlite3* db, const char* sql, const std::filesystem::path& file) : db_(db), file_(file) {
    if (sqlite3_prepare_v2(db, sql, -1, &statement_, nullptr) != SQLITE_OK) Fail("prepare");
  }
  ~Statement() { sqlite3_finalize(statement_); }
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;

  Statement& Bind(int i, int64_t value) {
    Check(sqlite3_bind_int64(statement_, i, value));
    return *this;
  }
  Statement& Bind(int i, double value) {
    Check(sqlite3_bind_double(statement_, i, value));
    return *this;
  }
  Statement& Bind(int i, const std::string& text) {
    Check(sqlite3_bind_text(statement_, i, text.data(), int(text.size()), SQLITE_TRANSIENT));
    return *this;
  }
  Statement& BindBlob(int i, const std::string& bytes) {
    Check(sqlite3_bind_blob(statement_, i, bytes.data(), int(bytes.size()), SQLITE_TRANSIENT));
    return *this;
  }
  // Whether a row came; throws on an error.
  bool Step() {
    const int code = sqlite3_step(statement_);
    if (code == SQLITE_ROW) return true;
    if (code == SQLITE_DONE) return false;
    Fail("step");
  }
  int64_t Int(int i) const { return sqlite3_column_int64(statement_, i); }
  double Real(int i) const { return sqlite3_column_double(statement_, i); }
  std::string Text(int i) const {
    const void* data = sqlite3_column_blob(statement_, i);
    return data ? std::string(static_cast<const char*>(data), size_t(sqlite3_column_bytes(statement_, i)))
                : std::string();
  }

 private:
  void Check(int code) const {
    if (code != SQLITE_OK) Fail("bind");
  }
  [[noreturn]] void Fail(const char* what) const {
    throw StorageError("job database " + file_.string() + ": " + what + ": " + sqlite3_errmsg(db_));
  }
  sqlite3* db_;
  const std::filesystem::path& file_;
  sqlite3_stmt* statement_ = nullptr;
};

void Execute(sqlite3* db, const char* sql, const std::filesystem::path& file) {
  char* message = nullptr;
  if (sqlite3_exec(db, sql, nullptr, nullptr, &message) != SQLITE_OK) {
    const std::string text = message ? message : sqlite3_errmsg(db);
    sqlite3_free(message);
    throw StorageError("job database " + file.string() + ": " + text);
  }
}

// Parameters ?2..?19 of Insert and Update: every column but the first.
void BindFields(Statement& statement, const JobRecord& r) {
  statement.Bind(2, r.name).Bind(3, r.owner).Bind(4, int64_t(r.state));
  statement.Bind(5, int64_t(r.priority)).Bind(6, int64_t(r.max_retries)).Bind(7, int64_t(r.attempts));
  statement.Bind(8, int64_t(r.failures)).Bind(9, int64_t(r.crashes)).Bind(10, int64_t(r.samples_done));
  statement.Bind(11, int64_t(r.samples_total)).Bind(12, r.error).Bind(13, r.submitted_at).Bind(14, r.finished_at);
  statement.Bind(15, r.elapsed_seconds).Bind(16, int64_t(r.closest_hit_rays)).Bind(17, int64_t(r.shadow_rays));
  statement.Bind(18, int64_t(r.cancel_requested)).Bind(19, int64_t(r.run_alone));
}

}  // namespace

void JobStore::Close::operator()(sqlite3* db) const { sqlite3_close(db); }

std::filesystem::path JobStore::OpenMarker(const std::filesystem::path& file) { return file.string() + "-open"; }

namespace {

std::filesystem::path WalOf(const std::filesystem::path& file) { return file.string() + "-wal"; }

// 0 for a file that is not there.
uintmax_t SizeOf(const std::filesystem::path& file) {
  std::error_code error;
  const uintmax_t size = std::filesystem::file_size(file, error);
  return error ? 0 : size;
}

// Refuses, before SQLite opens (and may create, or recover from its log)
// `file`, a database that would come up with fewer jobs than it
// acknowledged. Nothing is written.
void CheckBeforeOpening(const std::filesystem::path& file, const std::string& job_files) {
  const std::filesystem::path wal = WalOf(file), marker = JobStore::OpenMarker(file);
  const bool exists = std::filesystem::exists(file);
  const std::string what = exists ? " is empty" : " is missing";
  if (SizeOf(file) == 0) {
    // A fresh folder holds neither jobs' files nor a log.
    if (!job_files.empty())
      throw StorageError("the job database " + file.string() + what + ", but the state folder holds " + job_files +
                         ": the database was lost or replaced. Nothing was changed; restore it from a backup, or,"
                         " to start with an empty job table, move those files away");
    if (SizeOf(wal) > 0)
      throw StorageError("the job database " + file.string() + what + ", but its write-ahead log " + wal.string() +
                         " holds " + std::to_string(SizeOf(wal)) +
                         " bytes. Nothing was changed; restore the database, or move the log away to start with an"
                         " empty job table");
    return;
  }
  if (const std::optional<std::string> damage = WalDamage(wal))
    throw StorageError("the write-ahead log of the job database: " + *damage +
                       ". Nothing was changed; restore the log from a backup, or, to start with what " +
                       file.string() + " holds without it, move " + wal.string() + " away and delete " +
                       marker.string());
  // SQLite removes the log when it closes the database cleanly, and only then.
  if (std::filesystem::exists(marker) && InWalMode(file) && SizeOf(wal) == 0)
    throw StorageError("the job database " + file.string() +
                       " was not closed by the last yarfd that used it, yet its write-ahead log " + wal.string() +
                       (std::filesystem::exists(wal) ? " is empty" : " is missing") +
                       ": the jobs acknowledged since SQLite last copied the log into the database would be lost."
                       " Nothing was changed; put the log back, or delete " +
                       marker.string() + " to start with what the database holds");
}

}  // namespace

JobStore::JobStore(const std::filesystem::path& file, const std::string& job_files) : file_(file) {
  try {
    CheckBeforeOpening(file, job_files);
  } catch (const Error& e) {
    throw StorageError(e.what());
  }
  sqlite3* db = nullptr;
  const int code = sqlite3_open_v2(file.c_str(), &db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr);
  db_.reset(db);
  if (code != SQLITE_OK)
    throw StorageError("cannot open the job database " + file.string() + ": " +
                (db ? sqlite3_errmsg(db) : sqlite3_errstr(code)));
  sqlite3_extended_result_codes(db, 1);
  sqlite3_busy_timeout(db, 5000);
  try {
    {
      // A damaged file fails here, before anything is written to it.
      Statement check(db, "PRAGMA integrity_check", file_);
      if (!check.Step() || check.Text(0) != "ok")
        throw StorageError("job database " + file.string() + " fails its integrity check: " + check.Text(0));
    }
    {
      Statement version(db, "PRAGMA user_version", file_);
      version.Step();
      opened_version_ = int(version.Int(0));
      if (opened_version_ > kSchemaVersion)
        throw StorageError("job database " + file.string() + " has schema version " +
                           std::to_string(opened_version_) + ", newer than this yarfd's " +
                           std::to_string(kSchemaVersion));
    }
    Execute(db, "PRAGMA journal_mode = WAL", file_);
    Execute(db, "PRAGMA synchronous = FULL", file_);
    Execute(db, kSchema, file_);
    for (const auto& [name, definition] : kAddedColumns) {
      Statement column(db, "SELECT COUNT(*) FROM pragma_table_info('jobs') WHERE name = ?1", file_);
      column.Bind(1, std::string(name)).Step();
      if (column.Int(0) == 0)
        Execute(db, ("ALTER TABLE jobs ADD COLUMN " + std::string(name) + " " + definition).c_str(), file_);
    }
    Execute(db, ("PRAGMA user_version = " + std::to_string(kSchemaVersion)).c_str(), file_);
  } catch (const StorageError& e) {
    throw StorageError(std::string(e.what()) +
                       (job_files.empty()
                            ? " (move the file away to start with an empty job table, or use another --state-dir)"
                            : " (nothing was changed; restore the file from a backup, or, to start with an empty job"
                              " table, move it away together with the files of its jobs: " +
                                  job_files + ")"));
  }
  // Written once the log exists (the writes above made it): from now on a
  // missing log means it was lost.
  try {
    WriteFileAtomically(OpenMarker(file_), "the job database is open, or was not closed cleanly\n");
  } catch (const Error& e) {
    throw StorageError(e.what());
  }
}

JobStore::~JobStore() {
  // The marker goes once SQLite has copied the log into the database and
  // removed it, which it does only when it closes it cleanly.
  if (sqlite3_close(db_.release()) == SQLITE_OK && !std::filesystem::exists(WalOf(file_))) {
    std::error_code ignored;
    std::filesystem::remove(OpenMarker(file_), ignored);
  }
}

uint64_t JobStore::HighestNumber() const {
  std::lock_guard lock(mutex_);
  // The sequence outlives the rows AUTOINCREMENT numbered.
  Statement select(db_.get(),
                   "SELECT MAX(IFNULL((SELECT seq FROM sqlite_sequence WHERE name = 'jobs'), 0),"
                   " IFNULL((SELECT MAX(number) FROM jobs), 0))",
                   file_);
  select.Step();
  return uint64_t(select.Int(0));
}

uint64_t JobStore::Insert(const JobRecord& r) {
  std::lock_guard lock(mutex_);
  Statement insert(db_.get(),
                   "INSERT INTO jobs (request, name, owner, state, priority, max_retries, attempts, failures, crashes,"
                   " samples_done, samples_total, error, submitted_at, finished_at, elapsed_seconds,"
                   " closest_hit_rays, shadow_rays, cancel_requested, run_alone) VALUES (?1, ?2, ?3, ?4, ?5, ?6,"
                   " ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16, ?17, ?18, ?19)",
                   file_);
  insert.BindBlob(1, r.request);
  BindFields(insert, r);
  insert.Step();
  return uint64_t(sqlite3_last_insert_rowid(db_.get()));
}

void JobStore::Update(const JobRecord& r) {
  std::lock_guard lock(mutex_);
  Statement update(db_.get(),
                   "UPDATE jobs SET name = ?2, owner = ?3, state = ?4, priority = ?5, max_retries = ?6,"
                   " attempts = ?7, failures = ?8, crashes = ?9, samples_done = ?10, samples_total = ?11,"
                   " error = ?12, submitted_at = ?13, finished_at = ?14, elapsed_seconds = ?15,"
                   " closest_hit_rays = ?16, shadow_rays = ?17, cancel_requested = ?18, run_alone = ?19"
                   " WHERE number = ?1",
                   file_);
  update.Bind(1, int64_t(r.number));
  BindFields(update, r);
  update.Step();
}

std::vector<JobRecord> JobStore::LoadAll() const {
  std::lock_guard lock(mutex_);
  // The request of an ended job is never needed again: leave it on disk.
  Statement select(db_.get(),
                   "SELECT number, CASE WHEN state IN (3, 4, 5) THEN x'' ELSE request END, name, owner, state,"
                   " priority, max_retries, attempts, failures, crashes, samples_done, samples_total, error,"
                   " submitted_at, finished_at, elapsed_seconds, closest_hit_rays, shadow_rays, cancel_requested,"
                   " run_alone FROM jobs ORDER BY number",
                   file_);
  std::vector<JobRecord> records;
  while (select.Step()) {
    JobRecord& r = records.emplace_back();
    r.number = uint64_t(select.Int(0));
    r.request = select.Text(1);
    r.name = select.Text(2);
    r.owner = select.Text(3);
    const int state = int(select.Int(4));
    r.state = v1::JobState_IsValid(state) && state != v1::JOB_STATE_UNSPECIFIED ? v1::JobState(state) : v1::FAILED;
    r.priority = uint32_t(select.Int(5));
    r.max_retries = uint32_t(select.Int(6));
    r.attempts = uint32_t(select.Int(7));
    r.failures = uint32_t(select.Int(8));
    r.crashes = uint32_t(select.Int(9));
    r.samples_done = uint32_t(select.Int(10));
    r.samples_total = uint32_t(select.Int(11));
    r.error = select.Text(12);
    r.submitted_at = select.Real(13);
    r.finished_at = select.Real(14);
    r.elapsed_seconds = select.Real(15);
    r.closest_hit_rays = uint64_t(select.Int(16));
    r.shadow_rays = uint64_t(select.Int(17));
    r.cancel_requested = select.Int(18) != 0;
    r.run_alone = select.Int(19) != 0;
    if (!EndedState(r.state) && r.finished_at > 0) r.finished_at = 0;
  }
  return records;
}

std::vector<uint64_t> JobStore::DeleteEnded(double finished_before, uint64_t keep) {
  std::lock_guard lock(mutex_);
  Execute(db_.get(), "BEGIN IMMEDIATE", file_);
  try {
    std::vector<uint64_t> numbers;
    {
      Statement select(db_.get(),
                       "SELECT number FROM jobs WHERE state IN (3, 4, 5) AND (finished_at < ?1 OR number NOT IN"
                       " (SELECT number FROM jobs WHERE state IN (3, 4, 5)"
                       "  ORDER BY finished_at DESC, number DESC LIMIT ?2))",
                       file_);
      select.Bind(1, finished_before).Bind(2, int64_t(std::min<uint64_t>(keep, INT64_MAX)));
      while (select.Step()) numbers.push_back(uint64_t(select.Int(0)));
    }
    for (uint64_t number : numbers) {
      Statement remove(db_.get(), "DELETE FROM jobs WHERE number = ?1", file_);
      remove.Bind(1, int64_t(number)).Step();
    }
    Execute(db_.get(), "COMMIT", file_);
    return numbers;
  } catch (...) {
    sqlite3_exec(db_.get(), "ROLLBACK", nullptr, nullptr, nullptr);
    throw;
  }
}

}  // namespace yarf
