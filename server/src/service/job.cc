#include "service/job.h"

#include <algorithm>
#include <iostream>
#include <limits>
#include <optional>
#include <thread>
#include <tuple>
#include <utility>

#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include "kernel/film_target.h"
#include "service/job_files.h"
#include "service/request_checks.h"
#include "service/scene_summary.h"
#include "yarf/aov.h"
#include "yarf/error.h"

namespace yarf {
namespace {

double Now() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

void RemoveFile(const std::filesystem::path& path) {
  std::error_code ignored;
  std::filesystem::remove(path, ignored);
}

// A store that fails for a moment (a busy or briefly full disk) gets this
// many tries, the pauses between them growing threefold.
constexpr int kCommitTries = 4;
constexpr std::chrono::milliseconds kFirstCommitPause(100);
// A job's log keeps its last lines: a long render writes a checkpoint line
// every few seconds.
constexpr size_t kMaxLogLines = 200;

// The concurrency of a job's task arena: RenderOptions.threads, at most
// the server's (0: the server's).
int WorkerThreads(uint32_t threads) {
  const size_t server = tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism);
  return threads == 0 ? int(server) : int(std::min<size_t>(threads, server));
}

std::optional<v1::RenderOptions> OptionsOf(const v1::SubmitRequest* request) {
  return request ? std::optional(request->options()) : std::nullopt;
}

std::optional<v1::SceneSummary> SummaryOf(const v1::SubmitRequest* request) {
  return request ? std::optional(SummarizeScene(request->scene())) : std::nullopt;
}

}  // namespace

bool Ended(v1::JobState state) { return state == v1::SUCCEEDED || state == v1::FAILED || state == v1::CANCELLED; }

Job::Job(std::string id, JobRecord record, std::shared_ptr<const v1::SubmitRequest> request, Files files,
         Persist persist, JobObserver* observer)
    : id_(std::move(id)),
      number_(record.number),
      owner_(record.owner),
      files_(std::move(files)),
      persist_(std::move(persist)),
      observer_(observer),
      request_(std::move(request)),
      options_(OptionsOf(request_.get())),
      scene_summary_(SummaryOf(request_.get())),
      row_(std::move(record)),
      samples_done_(row_.samples_done),
      closest_hit_rays_(row_.closest_hit_rays),
      shadow_rays_(row_.shadow_rays) {
  row_.request.clear();  // held parsed in request_
}

v1::JobStatus Job::Status() const {
  std::lock_guard lock(mutex_);
  v1::JobStatus s;
  s.set_job_id(id_);
  s.set_name(row_.name);
  s.set_state(row_.state);
  s.set_samples_done(samples_done_);
  s.set_samples_total(row_.samples_total);
  s.set_percent(row_.samples_total ? 100.0 * samples_done_ / row_.samples_total : 0);
  if (row_.state == v1::RUNNING) {
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
    s.set_elapsed_seconds(elapsed);
    // The rate of this run: a resumed run started at run_first_sample_.
    if (samples_done_ > run_first_sample_)
      s.set_eta_seconds(elapsed * (row_.samples_total - samples_done_) / (samples_done_ - run_first_sample_));
  } else if (Ended(row_.state)) {
    s.set_elapsed_seconds(row_.elapsed_seconds);
  }
  s.set_error(row_.error);
  s.set_closest_hit_rays(closest_hit_rays_);
  s.set_shadow_rays(shadow_rays_);
  s.set_priority(row_.priority);
  s.set_owner(owner_);
  s.set_attempts(row_.attempts);
  s.set_submitted_at(row_.submitted_at);
  return s;
}

JobEvent Job::Describe(JobEventKind kind) const {
  std::lock_guard lock(mutex_);
  return DescribeLocked(kind);
}

void Job::Tell(JobEventKind kind) { Tell(Describe(kind)); }

void Job::Tell(const JobEvent& event) {
  {
    std::lock_guard lock(mutex_);
    log_.push_back(FormatKeyValue(event));
    if (log_.size() > kMaxLogLines) log_.pop_front();
  }
  if (observer_) observer_->OnJobEvent(event);
}

v1::JobDetails Job::Details() const {
  v1::JobDetails details;
  *details.mutable_status() = Status();
  if (options_) *details.mutable_options() = *options_;
  if (scene_summary_) *details.mutable_scene() = *scene_summary_;
  std::lock_guard lock(mutex_);
  details.mutable_log()->Assign(log_.begin(), log_.end());
  return details;
}

JobEvent Job::DescribeLocked(JobEventKind kind) const {
  JobEvent event;
  event.kind = kind;
  event.job = id_;
  event.owner = owner_;
  event.attempt = row_.attempts;
  event.spp_done = samples_done_;
  event.spp_total = row_.samples_total;
  if (Ended(row_.state))
    event.seconds = row_.elapsed_seconds;
  else if (row_.state == v1::RUNNING || kind == JobEventKind::kRequeued)
    event.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
  event.rays = closest_hit_rays_ + shadow_rays_;
  event.error = row_.error;
  return event;
}

std::optional<JobEvent> Job::EventOfChange(const JobRecord& before) const {
  if (before.state == row_.state) {
    // A stored checkpoint moves the samples a restart goes on from.
    if (row_.state == v1::RUNNING && row_.samples_done != before.samples_done)
      return DescribeLocked(JobEventKind::kCheckpoint);
    return std::nullopt;
  }
  switch (row_.state) {
    case v1::RUNNING: {
      JobEvent event = DescribeLocked(JobEventKind::kStarted);
      event.queue_seconds = std::chrono::duration<double>(started_ - queued_since_).count();
      return event;
    }
    case v1::QUEUED: return DescribeLocked(JobEventKind::kRequeued);
    case v1::SUCCEEDED: return DescribeLocked(JobEventKind::kFinished);
    case v1::FAILED: return DescribeLocked(JobEventKind::kFailed);
    case v1::CANCELLED: return DescribeLocked(JobEventKind::kCancelled);
    default: return std::nullopt;
  }
}

uint64_t Job::Version() const {
  std::lock_guard lock(mutex_);
  return version_;
}

bool Job::Finished() const {
  std::lock_guard lock(mutex_);
  return Ended(row_.state);
}

uint32_t Job::Priority() const {
  std::lock_guard lock(mutex_);
  return row_.priority;
}

bool Job::RunsAlone() const {
  std::lock_guard lock(mutex_);
  return row_.run_alone;
}

JobFileOwner Job::FileOwner() const {
  std::lock_guard lock(mutex_);
  return {number_, row_.attempts};
}

std::vector<std::string> Job::Assets() const {
  std::shared_ptr<const v1::SubmitRequest> request;
  {
    std::lock_guard lock(mutex_);
    request = request_;  // held while it is read, whoever ends the job meanwhile
  }
  return request ? SceneAssets(request->scene()) : std::vector<std::string>{};
}

bool Job::Commit(const std::function<bool(JobRecord&)>& change) {
  std::optional<JobEvent> event;
  {
    std::lock_guard lock(mutex_);
    JobRecord next = row_;
    if (!change(next)) return false;
    persist_(next);
    const JobRecord before = std::exchange(row_, std::move(next));
    ++version_;
    event = EventOfChange(before);
    if (row_.state == v1::QUEUED && before.state != v1::QUEUED) queued_since_ = std::chrono::steady_clock::now();
  }
  // Told once stored, as watchers are, and outside the lock.
  if (event) Tell(*event);
  return true;
}

bool Job::CommitRetrying(const std::function<bool(JobRecord&)>& change) {
  auto pause = kFirstCommitPause;
  for (int tries = 1;; ++tries) {
    try {
      return Commit(change);
    } catch (const StorageError& e) {
      if (tries == kCommitTries) throw;
      std::cerr << "yarfd: job " << id_ << ": storing its state failed, trying again: " << e.what() << "\n";
    }
    std::this_thread::sleep_for(pause);
    pause *= 3;
  }
}

void Job::EndUnstored(const StorageError& error) {
  std::cerr << "yarfd: job " << id_ << ": the end of its run cannot be stored: " << error.what() << std::endl;
  // The film may be large; nothing renders into it any more.
  DropFilms();
  {
    std::lock_guard lock(mutex_);
    // In memory only: the stored row stays RUNNING, which the next start
    // takes for a crash and resumes from the checkpoint.
    row_.state = v1::FAILED;
    row_.error = std::string("the state of this job could not be stored (") + error.what() +
                 "); it runs again when yarfd restarts";
    row_.finished_at = Now();
    row_.elapsed_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
    ++version_;
    request_.reset();
  }
  Tell(JobEventKind::kFailed);
}

void Job::Progress(uint32_t samples_done, uint64_t closest_hit_rays, uint64_t shadow_rays) {
  uint64_t new_pixel_samples = 0, new_rays = 0;
  {
    std::lock_guard lock(mutex_);
    // Only what was added: a run that starts counts its rays from 0 again.
    if (samples_done > samples_done_) new_pixel_samples = uint64_t(samples_done - samples_done_) * run_pixels_;
    if (closest_hit_rays + shadow_rays > closest_hit_rays_ + shadow_rays_)
      new_rays = closest_hit_rays + shadow_rays - closest_hit_rays_ - shadow_rays_;
    samples_done_ = samples_done;
    closest_hit_rays_ = closest_hit_rays;
    shadow_rays_ = shadow_rays;
    ++version_;
  }
  if (observer_ && (new_pixel_samples || new_rays)) observer_->OnProgress(new_pixel_samples, new_rays);
}

void Job::SetPriority(uint32_t priority) {
  Commit([&](JobRecord& row) {
    row.priority = priority;
    return true;
  });
}

bool Job::RequestCancel() {
  cancel_ = true;
  halt_ = true;
  remote_calls_->Cancel();
  bool was_queued = false;
  Commit([&](JobRecord& row) {
    if (row.state == v1::QUEUED) {
      was_queued = true;
      row.state = v1::CANCELLED;
      row.finished_at = Now();
      return true;
    }
    // Stored, so that a crash before the run ends still ends the job
    // CANCELLED instead of resuming it.
    if (row.state != v1::RUNNING || row.cancel_requested) return false;
    row.cancel_requested = true;
    return true;
  });
  if (was_queued) {
    // Begin refuses a cancelled job, so no worker reads the request any more.
    std::lock_guard lock(mutex_);
    request_.reset();
    RemoveFile(files_.checkpoint);
  }
  return was_queued;
}

void Job::RequestStop() {
  stop_ = true;
  halt_ = true;
  remote_calls_->Cancel();
}

bool Job::Snapshot(std::vector<float>& pixels, std::vector<float>& variances, uint32_t& width,
                   uint32_t& height) const {
  {
    std::lock_guard lock(film_mutex_);
    if (film_) {
      pixels = film_->Pixels();
      variances = film_->Variances();
      width = film_->width();
      height = film_->height();
      return true;
    }
  }
  if (!Finished()) return false;
  std::optional<JobImage> image;
  try {
    image = ReadJobImage(files_.result, FileOwner());
  } catch (const Error& e) {
    // Kept for whoever looks into it, but never served as this job's.
    std::cerr << "yarfd: job " << id_ << ": result discarded, not served: " << e.what() << "\n";
  }
  if (!image) return false;
  pixels = std::move(image->pixels);
  variances = std::move(image->variances);
  width = image->width;
  height = image->height;
  return true;
}

bool Job::ImageSize(uint32_t& width, uint32_t& height) const {
  {
    std::lock_guard lock(film_mutex_);
    if (film_) {
      width = film_->width();
      height = film_->height();
      return true;
    }
  }
  if (!Finished()) return false;
  try {
    if (const auto size = ReadJobImageSize(files_.result, FileOwner())) {
      std::tie(width, height) = *size;
      return true;
    }
  } catch (const Error& e) {
    std::cerr << "yarfd: job " << id_ << ": result discarded, not served: " << e.what() << "\n";
  }
  return false;
}

bool Job::Begin() {
  return CommitRetrying([&](JobRecord& row) {
    if (row.state != v1::QUEUED || stop_ || !request_) return false;
    row.state = v1::RUNNING;
    ++row.attempts;
    row.error.clear();
    started_ = std::chrono::steady_clock::now();
    return true;
  });
}

Job::RunResult Job::Render(const JobResources& resources, const RunSettings& settings) {
  const auto outcome = [&](Outcome otherwise) {
    return cancel_ ? Outcome::kCancelled : stop_ ? Outcome::kStopped : otherwise;
  };
  try {
    tbb::task_arena arena(WorkerThreads(request_->options().threads()));
    arena.execute([&] { RenderRun(resources, settings); });
    return {outcome(Outcome::kSucceeded), ""};
  } catch (const std::exception& e) {
    // A halt that cut a remote call short is a cancel or a stop, not a failure.
    return {outcome(Outcome::kFailed), SafeText(e.what(), RequestLimits::kMaxErrorBytes)};
  } catch (...) {
    // A plugin may throw anything; it fails the job, not the server.
    return {outcome(Outcome::kFailed), "a component threw an exception that is not a std::exception"};
  }
}

void Job::RenderRun(const JobResources& resources, const RunSettings& settings) {
  const v1::Scene& scene = request_->scene();
  const v1::RenderOptions& options = request_->options();
  JobComponents parts = MakeJobComponents(*request_, owner(), resources, remote_calls_, halt_);
  const std::shared_ptr<KernelScene> kernel = parts.scene;
  const bool resumable = parts.resumable;
  std::optional<FilmCheckpoint> checkpoint =
      resumable ? UsableCheckpoint(scene.film(), options.spp()) : std::nullopt;
  // A checkpoint in use stays until the next one replaces it, so that a
  // crash before then still resumes from it.
  if (!checkpoint) RemoveFile(files_.checkpoint);
  FilmTarget::Share share = ShareOf(options);
  {
    std::lock_guard lock(film_mutex_);
    film_ = checkpoint ? std::make_unique<Film>(std::move(checkpoint->film))
                       : std::make_unique<Film>(scene.film().width(), scene.film().height(), scene.film().filter());
    aov_films_.clear();
  }
  if (checkpoint) share.first_sample = std::max(share.first_sample, checkpoint->samples_done);
  {
    std::lock_guard lock(mutex_);
    run_first_sample_ = share.first_sample;
  }
  Progress(share.first_sample, 0, 0);
  {
    // After the first Progress: samples of a checkpoint or of another
    // share were not rendered by this run.
    std::lock_guard lock(mutex_);
    run_pixels_ = share.crop ? uint64_t(share.crop->x1 - share.crop->x0) * (share.crop->y1 - share.crop->y0)
                             : uint64_t(scene.film().width()) * scene.film().height();
  }

  const KernelScene* counters = kernel.get();
  // Checkpoints of a large film take a while to write: at least ten
  // times that long apart, so that they cost at most a tenth of the time.
  const std::chrono::duration<double> every(settings.checkpoint_seconds);
  auto next_checkpoint = std::chrono::steady_clock::now() + every;
  FilmTarget target(*film_, film_mutex_, options.spp(), options.seed(), share, halt_, [&](uint32_t done) {
    Progress(done, counters->ClosestHitRays(), counters->ShadowRays());
    if (!resumable || done >= options.spp() || halt_) return;
    const auto start = std::chrono::steady_clock::now();
    if (start < next_checkpoint) return;
    WriteCheckpoint(done);
    const auto end = std::chrono::steady_clock::now();
    next_checkpoint = end + std::max(every, std::chrono::duration<double>(10 * (end - start)));
  });
  target.WeighCameraSamples(kernel->CameraRayWeight());
  const v1::Film& film = scene.film();
  // A positive limit stays one in float (0 is none).
  const double limit = film.max_component_value();
  target.Expose(film.exposure() > 0 ? float(film.exposure()) : 1.0f,
                limit > 0 ? std::max(float(limit), std::numeric_limits<float>::denorm_min()) : 0.0f);
  // Served while it renders, for transports in other processes.
  const auto served = resources.scenes.Serve(kernel);
  parts.transport->Prepare(*kernel);
  parts.integrator->Render(*parts.transport, *kernel, *parts.sampler, target);
  RenderAovs(parts, *kernel, share);
  Progress(samples_done_, counters->ClosestHitRays(), counters->ShadowRays());
}

void Job::RenderAovs(JobComponents& parts, const KernelScene& kernel, const FilmTarget::Share& share) {
  if (parts.aovs.empty() || halt_) return;
  const v1::Film& film = request_->scene().film();
  const v1::RenderOptions& options = request_->options();
  // Geometry converges in few samples; the albedo's one model sample per
  // camera sample wants a few dozen.
  constexpr uint32_t kMaxAovSpp = 64;
  const uint32_t spp = std::min(options.spp(), kMaxAovSpp);
  std::vector<std::pair<std::string, std::unique_ptr<Film>>> films;
  for (auto& [name, transport] : parts.aovs) {
    auto aov_film = std::make_unique<Film>(film.width(), film.height(), film.filter());
    FilmLock unshared;  // nobody reads it before it is done
    FilmTarget target(*aov_film, unshared, spp, options.seed(), {0, share.crop}, halt_, [](uint32_t) {});
    parts.aov_integrator->Render(*transport, kernel, *parts.sampler, target);
    if (halt_) return;
    films.emplace_back(name, std::move(aov_film));
  }
  std::lock_guard lock(film_mutex_);
  aov_films_ = std::move(films);
}

std::vector<ImageLayer> Job::AovSnapshot() const {
  std::vector<ImageLayer> layers;
  {
    std::lock_guard lock(film_mutex_);
    if (!aov_films_.empty()) {
      for (std::string_view name : kAovNames)
        for (const auto& [aov, film] : aov_films_)
          if (aov == name) layers.push_back({aov, film->Pixels()});
      return layers;
    }
    if (film_) return layers;
  }
  if (!Finished()) return layers;
  for (std::string_view name : kAovNames) {
    try {
      if (std::optional<JobImage> image = ReadJobImage(AovImagePath(files_.result, name), FileOwner()))
        layers.push_back({std::string(name), std::move(image->pixels)});
    } catch (const Error& e) {
      std::cerr << "yarfd: job " << id_ << ": aov " << name << " discarded, not served: " << e.what() << "\n";
    }
  }
  return layers;
}

void Job::DropFilms() {
  std::lock_guard lock(film_mutex_);
  film_.reset();
  aov_films_.clear();
}

std::optional<FilmCheckpoint> Job::UsableCheckpoint(const v1::Film& film, uint32_t spp) const {
  try {
    std::optional<FilmCheckpoint> checkpoint = ReadCheckpoint(files_.checkpoint, FileOwner());
    if (checkpoint && (checkpoint->film.width() != film.width() || checkpoint->film.height() != film.height()))
      throw Error("the checkpoint is not of this job's film size");
    // Resuming past spp would report more samples than the job has.
    if (checkpoint && checkpoint->samples_done > spp)
      throw Error("the checkpoint has " + std::to_string(checkpoint->samples_done) + " samples per pixel, more than " +
                  std::to_string(spp));
    return checkpoint;
  } catch (const Error& e) {
    std::cerr << "yarfd: job " << id_ << ": checkpoint " << files_.checkpoint.string()
              << " discarded, starting anew: " << e.what() << "\n";
    return std::nullopt;
  }
}

void Job::WriteCheckpoint(uint32_t samples_done) {
  try {
    std::string film;
    {
      std::lock_guard lock(film_mutex_);
      film = film_->Save();
    }
    ::yarf::WriteCheckpoint(files_.checkpoint, FileOwner(), samples_done, film);
    Commit([&](JobRecord& row) {
      row.samples_done = samples_done;
      // The job gets on: crashes before this one need not be its doing.
      row.crashes = 0;
      row.run_alone = false;
      return true;
    });
  } catch (const std::exception& e) {
    // The render goes on; only its resumability suffers.
    if (!std::exchange(checkpoint_failed_, true))
      std::cerr << "yarfd: job " << id_ << ": no checkpoint: " << e.what() << "\n";
  }
}

bool Job::EndRun(const RunResult& result) {
  try {
    return StoreEndOfRun(result);
  } catch (const StorageError& e) {
    EndUnstored(e);
    return false;
  }
}

bool Job::StoreEndOfRun(const RunResult& result) {
  switch (result.outcome) {
    case Outcome::kStopped:
      // Back in the queue for the next start, which goes on from the last
      // checkpoint (row_.samples_done says where).
      CommitRetrying([](JobRecord& row) {
        row.state = v1::QUEUED;
        // A clean stop ends a run of crashes, and clears the job of them.
        row.crashes = 0;
        row.run_alone = false;
        return true;
      });
      return false;
    case Outcome::kFailed:
      // Gone before the row says QUEUED: a crash in between must not let
      // the retry resume from the failed run's film.
      RemoveFile(files_.checkpoint);
      if (CommitRetrying([&](JobRecord& row) {
            if (row.failures + 1 > row.max_retries) return false;
            ++row.failures;
            // The run ended without taking the server down.
            row.crashes = 0;
            row.run_alone = false;
            row.state = v1::QUEUED;
            row.samples_done = 0;
            row.error = result.error;  // why it runs again
            return true;
          })) {
        std::cerr << "yarfd: job " << id_ << " failed, queued again: " << result.error << "\n";
        DropFilms();
        std::lock_guard lock(mutex_);
        samples_done_ = 0;
        return true;
      }
      Finish(v1::FAILED, result.error);
      return false;
    case Outcome::kCancelled:
      Finish(v1::CANCELLED, "");
      return false;
    case Outcome::kSucceeded:
      Finish(v1::SUCCEEDED, "");
      return false;
  }
  return false;
}

void Job::Finish(v1::JobState state, const std::string& error) {
  // The image first, so that a job that reads SUCCEEDED after a restart has it.
  std::vector<std::pair<std::filesystem::path, JobImage>> images;
  {
    std::lock_guard lock(film_mutex_);
    if (film_) images.emplace_back(files_.result, JobImage{film_->width(), film_->height(), film_->Pixels(), film_->Variances()});
    for (const auto& [name, film] : aov_films_)
      images.emplace_back(AovImagePath(files_.result, name), JobImage{film->width(), film->height(), film->Pixels(), film->Variances()});
  }
  for (const auto& [path, image] : images) {
    try {
      WriteJobImage(path, FileOwner(), image);
    } catch (const Error& e) {
      std::cerr << "yarfd: job " << id_ << ": image " << path.filename().string() << " not kept: " << e.what() << "\n";
    }
  }
  CommitRetrying([&](JobRecord& row) {
    if (state == v1::FAILED) ++row.failures;
    row.state = state;
    row.error = error;
    row.crashes = 0;
    row.run_alone = false;
    row.finished_at = Now();
    row.elapsed_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
    row.samples_done = samples_done_;
    row.closest_hit_rays = closest_hit_rays_;
    row.shadow_rays = shadow_rays_;
    return true;
  });
  // Only once the row has ended: a crash before the commit resumes the run
  // from the checkpoint rather than redoing it.
  RemoveFile(files_.checkpoint);
  DropFilms();
  // Other threads read it (Assets) under the lock.
  std::lock_guard lock(mutex_);
  request_.reset();
}

}  // namespace yarf
