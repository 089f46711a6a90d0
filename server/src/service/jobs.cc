#include "service/jobs.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <optional>
#include <set>

#include "components/scene_builder.h"
#include "service/class_checks.h"
#include "service/job_files.h"
#include "service/job_splits.h"
#include "service/job_memory.h"
#include "service/request_checks.h"
#include "yarf/aov.h"
#include "yarf/error.h"

namespace yarf {
namespace {

// A job the server died under this many times in a row, each time while it
// ran alone, is not run again: it may be what kills the server.
constexpr uint32_t kMaxCrashes = 3;

double Now() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

std::string IdOf(uint64_t number) {
  char id[32];
  std::snprintf(id, sizeof id, "job-%06llu", static_cast<unsigned long long>(number));
  return id;
}

// The number of a well-formed id, else 0 (never a job's number).
uint64_t NumberOf(const std::string& id) {
  if (id.size() < 5 || id.size() > 24 || id.compare(0, 4, "job-") != 0) return 0;
  uint64_t number = 0;
  for (size_t i = 4; i < id.size(); ++i) {
    if (id[i] < '0' || id[i] > '9') return 0;
    number = number * 10 + uint64_t(id[i] - '0');
  }
  return IdOf(number) == id ? number : 0;
}

void RemoveFile(const std::filesystem::path& path) {
  std::error_code ignored;
  std::filesystem::remove(path, ignored);
}

}  // namespace

JobManager::JobManager(JobResources resources, JobQueueOptions options, const StateFolder& folder,
                       JobObserver* observer)
    : resources_(std::move(resources)),
      options_(std::move(options)),
      folder_(folder),
      observer_(observer),
      // Told what files of jobs there are, so that it refuses to replace a
      // lost database with an empty one (the sweep below would delete them).
      store_(folder_.Database(), folder_.DescribeJobFiles()),
      scheduler_([this](const std::shared_ptr<Job>& job) { RunJob(job); }) {
  Restore();
  ApplyRetention();
  RemoveStrayFiles();
}

JobManager::~JobManager() { StopAll(); }

void JobManager::StopAll() {
  scheduler_.Stop();
  for (const auto& job : List()) job->RequestStop();
  scheduler_.Join();
}

void JobManager::Start() { scheduler_.Start(options_.max_running_jobs); }

std::shared_ptr<Job> JobManager::MakeJob(JobRecord record, std::shared_ptr<const v1::SubmitRequest> request) {
  const std::string id = IdOf(record.number);
  Job::Files files{folder_.Checkpoint(id), folder_.Result(id)};
  return std::make_shared<Job>(id, std::move(record), std::move(request), std::move(files),
                               [this](const JobRecord& row) { store_.Update(row); }, observer_);
}

void JobManager::EndCancelled(JobRecord& row) const {
  row.state = v1::CANCELLED;
  row.finished_at = Now();
  // The image of the last checkpoint, if there is a sound one, as a
  // cancelled run would have left it.
  const std::string id = IdOf(row.number);
  const JobFileOwner owner{row.number, row.attempts};
  try {
    if (std::optional<FilmCheckpoint> checkpoint = ReadCheckpoint(folder_.Checkpoint(id), owner)) {
      const Film& film = checkpoint->film;
      WriteJobImage(folder_.Result(id), owner, {film.width(), film.height(), film.Pixels(), film.Variances()});
      row.samples_done = checkpoint->samples_done;
    }
  } catch (const Error& e) {
    std::cerr << "yarfd: job " << id << ": cancelled without an image: " << e.what() << "\n";
  }
}

void JobManager::AdoptLegacyResult(const JobRecord& row) const {
  const std::filesystem::path result = folder_.Result(IdOf(row.number));
  try {
    if (UpgradeLegacyJobImage(result, {row.number, row.attempts}))
      std::cerr << "yarfd: job " << IdOf(row.number) << ": result " << result.string()
                << " of an older yarfd bound to its job" << std::endl;
  } catch (const Error& e) {
    std::cerr << "yarfd: job " << IdOf(row.number) << ": " << e.what() << std::endl;
  }
}

void JobManager::Restore() {
  std::vector<JobRecord> rows = store_.LoadAll();
  // The jobs the server died under. With one, the crash may have been its
  // doing; with several, nothing tells whose it was, so none is blamed.
  // Either way each runs alone until it gets on, so that a crash that
  // comes again with it is told apart from its neighbours'.
  const auto running = std::count_if(rows.begin(), rows.end(), [](const JobRecord& row) {
    return row.state == v1::RUNNING;
  });
  // Older stores came with results that name no job: the first start on
  // such a store binds them to the jobs that hold them.
  constexpr int kFirstStoreOfBoundFiles = 3;
  const bool adopt_legacy_results =
      store_.OpenedVersion() > 0 && store_.OpenedVersion() < kFirstStoreOfBoundFiles;
  for (JobRecord& row : rows) {
    std::shared_ptr<v1::SubmitRequest> request;
    // Names and errors stored before they were bounded, or not UTF-8,
    // would break List for every client: mended once, here.
    const std::string name = SafeText(row.name, RequestLimits::kMaxNameBytes);
    const std::string error = SafeText(row.error, RequestLimits::kMaxErrorBytes);
    bool changed = name != row.name || error != row.error;
    row.name = name;
    row.error = error;
    if (!Ended(row.state)) {
      request = std::make_shared<v1::SubmitRequest>();
      if (!request->ParseFromString(row.request)) {
        request.reset();
        row.state = v1::FAILED;
        row.error = "the stored request of this job cannot be read";
        row.finished_at = Now();
        changed = true;
      }
    }
    if (!Ended(row.state) && row.cancel_requested) {
      // Cancelled while it ran, and the server died before the run ended.
      EndCancelled(row);
      request.reset();
      changed = true;
    }
    if (row.state == v1::RUNNING) {
      // It runs again from its checkpoint, unless the server died under it,
      // alone, too often in a row.
      row.run_alone = true;
      if (running == 1 && ++row.crashes >= kMaxCrashes) {
        row.state = v1::FAILED;
        row.error = "the server stopped " + std::to_string(row.crashes) +
                    " times in a row while this job ran alone; it is not run again";
        row.finished_at = Now();
        request.reset();
      } else {
        row.state = v1::QUEUED;
      }
      changed = true;
    }
    if (changed) store_.Update(row);
    if (adopt_legacy_results && Ended(row.state)) AdoptLegacyResult(row);
    auto job = MakeJob(std::move(row), std::move(request));
    jobs_[job->number()] = job;
    if (!job->Finished()) scheduler_.Enqueue(job);
  }
}

std::string JobManager::Submit(const v1::SubmitRequest& request, const std::string& owner,
                               std::vector<std::string>* warnings) {
  {
    std::lock_guard lock(mutex_);
    const auto pending = std::count_if(jobs_.begin(), jobs_.end(), [&](const auto& entry) {
      return entry.second->owner() == owner && !entry.second->Finished();
    });
    if (uint64_t(pending) >= options_.max_queued_jobs_per_user)
      throw LimitReached(owner + " has " + std::to_string(pending) +
                       " jobs queued or running, the most one user may (yarfd --max-queued-jobs-per-user)");
  }
  std::optional<UserAssets> assets;
  if (resources_.assets) assets.emplace(*resources_.assets, owner);
  auto accepted = std::make_shared<const v1::SubmitRequest>(AcceptSubmit(request, assets ? &*assets : nullptr));
  const std::vector<ComponentInfo> known = KnownClasses(resources_);
  CheckComponents(*accepted, known);
  CheckShare(*accepted, SplitsOf(*accepted, known));
  if (warnings) *warnings = SubmitWarnings(*accepted, known);
  if (const uint64_t bytes = EstimateJobBytes(*accepted, resources_.assets, resources_.asset_root,
                                                options_.max_job_bytes);
      bytes > options_.max_job_bytes)
    throw LimitReached("the job would need about " + std::to_string(bytes >> 20) +
                       " MiB (its film, meshes, images and placements), more than the " +
                       std::to_string(options_.max_job_bytes >> 20) +
                       " MiB a job may on this server (yarfd --max-job-memory)");
  JobRecord row;
  row.request = accepted->SerializeAsString();
  row.name = accepted->name();
  row.owner = owner;
  row.state = v1::QUEUED;
  row.priority = accepted->priority();
  row.max_retries = accepted->max_retries();
  row.samples_total = accepted->options().spp();
  row.submitted_at = Now();
  // Stored (and synced) before the caller hears of it.
  row.number = store_.Insert(row);
  auto job = MakeJob(std::move(row), std::move(accepted));
  {
    std::lock_guard lock(mutex_);
    jobs_[job->number()] = job;
  }
  // Before it is queued, so that the log tells submitted before started.
  job->Tell(JobEventKind::kSubmitted);
  scheduler_.Enqueue(job);
  return job->id();
}

std::shared_ptr<Job> JobManager::Find(const std::string& id) const {
  std::lock_guard lock(mutex_);
  auto it = jobs_.find(NumberOf(id));
  return it == jobs_.end() ? nullptr : it->second;
}

std::vector<std::shared_ptr<Job>> JobManager::List() const {
  std::lock_guard lock(mutex_);
  std::vector<std::shared_ptr<Job>> out;
  for (auto it = jobs_.rbegin(); it != jobs_.rend(); ++it) out.push_back(it->second);
  return out;
}

void JobManager::Cancel(Job& job) {
  if (!job.RequestCancel()) return;  // a running job ends through its run
  scheduler_.Remove(job);
  ApplyRetention();
}

bool JobManager::SetPriority(Job& job, uint32_t priority) {
  if (priority < 1 || priority > SubmitLimits::kMaxPriority)
    throw Error("priority " + std::to_string(priority) + " is out of range (1 to " +
                std::to_string(SubmitLimits::kMaxPriority) + ")");
  if (job.Finished()) return false;
  scheduler_.SetPriority(job, priority);
  return true;
}

void JobManager::RunJob(const std::shared_ptr<Job>& job) {
  try {
    bool began = false;
    try {
      began = job->Begin();
    } catch (const StorageError& e) {
      // Still QUEUED, in memory as in the store: it waits for another try
      // (Begin's own retries pace these).
      std::cerr << "yarfd: job " << job->id() << " cannot start, queued again: " << e.what() << std::endl;
      scheduler_.Enqueue(job);
      return;
    }
    if (!began) return;  // cancelled while queued, or the server is stopping
    const Job::RunResult result = job->Render(resources_, {options_.checkpoint_seconds});
    if (job->EndRun(result)) {
      scheduler_.Enqueue(job);
      return;
    }
    if (job->Finished()) ApplyRetention();
  } catch (const std::exception& e) {
    std::cerr << "yarfd: job " << job->id() << ": " << e.what() << std::endl;
  } catch (...) {
    // On a worker thread: anything escaping would end the server.
    std::cerr << "yarfd: job " << job->id() << ": an exception that is not a std::exception" << std::endl;
  }
}

void JobManager::ApplyRetention() {
  const double cutoff = Now() - options_.keep_finished_hours * 3600;
  const std::vector<uint64_t> numbers = store_.DeleteEnded(cutoff, options_.max_finished_jobs);
  std::vector<std::shared_ptr<Job>> deleted;
  {
    std::lock_guard lock(mutex_);
    for (uint64_t number : numbers) {
      if (auto it = jobs_.find(number); it != jobs_.end()) {
        deleted.push_back(std::move(it->second));
        jobs_.erase(it);
      }
    }
  }
  for (uint64_t number : numbers) {
    RemoveFile(folder_.Result(IdOf(number)));
    for (std::string_view aov : kAovNames) RemoveFile(AovImagePath(folder_.Result(IdOf(number)), aov));
    RemoveFile(folder_.Checkpoint(IdOf(number)));
  }
  CollectAssets();
}

// Assets are kept while a job still to run names them, and for a grace
// period after anyone last uploaded or asked for them.
void JobManager::CollectAssets() {
  if (!resources_.assets) return;
  const auto grace = std::chrono::seconds(int64_t(options_.asset_grace_hours * 3600));
  // Nothing becomes collectable sooner than its grace period: a tenth of it
  // (ten minutes at most) between two sweeps of the store, one at a time,
  // rather than a sweep at every job's end.
  const std::unique_lock sweeping(collection_mutex_, std::try_to_lock);
  if (!sweeping.owns_lock()) return;
  const auto now = std::chrono::steady_clock::now();
  const auto every = std::min<std::chrono::steady_clock::duration>(grace / 10, std::chrono::minutes(10));
  if (last_collection_ && now - *last_collection_ < every) return;
  last_collection_ = now;
  std::set<std::string> in_use;
  for (const auto& job : List())
    for (std::string& hash : job->Assets()) in_use.insert(std::move(hash));
  if (const size_t removed = resources_.assets->CollectGarbage(in_use, grace))
    std::cerr << "yarfd: " << removed << " assets no job needs, unused for " << options_.asset_grace_hours
              << " hours, deleted" << std::endl;
}

// Files a crash left behind: half-written temporaries, and the files of
// jobs that were deleted or have ended. Only of jobs the store numbered: a
// file of a job it never handed out is not its to delete (the database may
// have been replaced by an older or another one), and stays.
void JobManager::RemoveStrayFiles() const {
  std::set<std::string> live, kept;
  for (const auto& job : List()) {
    (job->Finished() ? kept : live).insert(job->id());
  }
  const uint64_t highest = store_.HighestNumber();
  auto sweep = [&](const std::filesystem::path& folder, const std::set<std::string>& wanted) {
    std::error_code error;
    for (const auto& entry : std::filesystem::directory_iterator(folder, error)) {
      const std::filesystem::path& path = entry.path();
      const std::string id = path.stem().string();
      if (path.extension() != ".tmp" && wanted.contains(id)) continue;
      const uint64_t number = NumberOf(id);
      if (path.extension() == ".tmp" || (number != 0 && number <= highest))
        RemoveFile(path);
      else
        std::cerr << "yarfd: " << path.string() << " is not of a job " << folder_.Database().string()
                  << " ever held; left as it is" << std::endl;
    }
  };
  sweep(folder_.Checkpoints(), live);
  sweep(folder_.Results(), kept);
}

}  // namespace yarf
