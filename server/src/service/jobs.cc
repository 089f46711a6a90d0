#include "service/jobs.h"

#include <cstdio>

#include "kernel/film_target.h"
#include "kernel/scene_builder.h"
#include "yarf/error.h"
#include "yarf/math.h"

namespace yarf {
namespace {

constexpr uint32_t kDefaultSpp = 16;
constexpr uint32_t kMaxSpp = 1u << 20;
constexpr uint32_t kMaxComponentRetries = 100;
constexpr double kMaxComponentTimeout = 24 * 3600;

bool Terminal(v1::JobState state) {
  return state == v1::SUCCEEDED || state == v1::FAILED || state == v1::CANCELLED;
}

// The job's choice, else the scene's, else the default class.
v1::ComponentSpec Choose(const v1::ComponentSpec& job, const v1::ComponentSpec& scene,
                         const char* fallback) {
  if (!job.class_name().empty()) return job;
  if (!scene.class_name().empty()) return scene;
  v1::ComponentSpec spec;
  spec.set_class_name(fallback);
  return spec;
}

// Whether the job calls a component in another process: a class named
// with an address, or registered by a component process.
bool CallsOtherProcesses(const v1::Scene& scene, const v1::RenderOptions& options, const JobResources& resources) {
  auto remote = [&](const std::string& class_name, const std::string& address) {
    return !address.empty() ||
           (!resources.registry.Has(class_name) && resources.remote_classes.AddressOf(class_name).has_value());
  };
  for (const v1::Material& m : scene.materials())
    if (remote(m.class_name(), m.address())) return true;
  for (const v1::ComponentSpec* spec : {&options.transport(), &scene.transport(), &options.sampler(), &scene.sampler()})
    if (!spec->class_name().empty() && remote(spec->class_name(), spec->address())) return true;
  return false;
}

// The integrator a job runs: its own, else the scene's, else mean_sample.
// For jobs that call other processes, mean_sample works in large batches
// (128² pixels × 4 samples per call) unless told otherwise, since every
// call costs a round trip whatever its size.
v1::ComponentSpec IntegratorSpec(const v1::ComponentSpec& job, const v1::ComponentSpec& scene,
                                 bool calls_other_processes) {
  v1::ComponentSpec spec = Choose(job, scene, "mean_sample");
  if (calls_other_processes && spec.class_name() == "mean_sample" && spec.address().empty()) {
    auto& values = *spec.mutable_properties()->mutable_values();
    if (!values.contains("tile_size")) values["tile_size"].set_int_value(128);
    if (!values.contains("samples_per_pass")) values["samples_per_pass"].set_int_value(4);
  }
  return spec;
}

RemoteOptions RemoteOptionsOf(const v1::RenderOptions& options, std::shared_ptr<RemoteCalls> calls) {
  RemoteOptions remote;
  remote.calls = std::move(calls);
  if (options.component_timeout_seconds() > 0)
    remote.deadline = std::chrono::milliseconds(int64_t(options.component_timeout_seconds() * 1000));
  remote.retries = options.component_retries();
  return remote;
}

template <typename I>
std::unique_ptr<I> Make(const ComponentSources& sources, const v1::ComponentSpec& spec, const char* role) {
  try {
    return MakeComponent<I>(sources, spec.class_name(), spec.properties(), spec.address());
  } catch (const Error& e) {
    throw Error(std::string(role) + " '" + spec.class_name() + "': " + e.what());
  }
}

}  // namespace

Job::Job(std::string id, v1::SubmitRequest request) : id_(std::move(id)), request_(std::move(request)) {
  status_.set_job_id(id_);
  status_.set_name(request_.name());
  status_.set_state(v1::QUEUED);
  status_.set_samples_total(request_.options().spp());
}

v1::JobStatus Job::Status() const {
  std::lock_guard lock(mutex_);
  return status_;
}

uint64_t Job::Version() const {
  std::lock_guard lock(mutex_);
  return version_;
}

bool Job::Finished() const {
  std::lock_guard lock(mutex_);
  return Terminal(status_.state());
}

void Job::WaitForChange(uint64_t seen, std::chrono::milliseconds timeout) const {
  std::unique_lock lock(mutex_);
  changed_.wait_for(lock, timeout, [&] { return version_ != seen; });
}

void Job::Update(const std::function<void(v1::JobStatus&)>& change) {
  {
    std::lock_guard lock(mutex_);
    change(status_);
    if (status_.state() == v1::RUNNING || Terminal(status_.state())) {
      const double elapsed =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
      status_.set_elapsed_seconds(elapsed);
      const double fraction = status_.samples_total() ? double(status_.samples_done()) / status_.samples_total() : 0;
      status_.set_percent(100 * fraction);
      status_.set_eta_seconds(fraction > 0 && !Terminal(status_.state()) ? elapsed * (1 - fraction) / fraction : 0);
    }
    ++version_;
  }
  changed_.notify_all();
}

void Job::RequestCancel() {
  cancel_ = true;
  remote_calls_->Cancel();
  Update([](v1::JobStatus& s) {
    if (s.state() == v1::QUEUED) s.set_state(v1::CANCELLED);
  });
}

bool Job::Snapshot(std::vector<float>& pixels, std::vector<float>& variances, uint32_t& width,
                   uint32_t& height) const {
  std::lock_guard lock(film_mutex_);
  if (film_) {
    pixels = film_->Pixels();
    variances = film_->Variances();
  } else if (!final_pixels_.empty()) {
    pixels = final_pixels_;
    variances = final_variances_;
  } else {
    return false;
  }
  width = width_;
  height = height_;
  return true;
}

void Job::KeepFinalImage() {
  std::lock_guard lock(film_mutex_);
  if (!film_) return;
  final_pixels_ = film_->Pixels();
  final_variances_ = film_->Variances();
  film_.reset();
}

void Job::Run(const JobResources& resources) {
  {
    std::lock_guard lock(mutex_);
    if (status_.state() != v1::QUEUED) return;  // cancelled while queued
    started_ = std::chrono::steady_clock::now();
  }
  Update([](v1::JobStatus& s) { s.set_state(v1::RUNNING); });
  try {
    const v1::Scene& scene = request_.scene();
    const v1::RenderOptions& options = request_.options();
    const ComponentSources components{resources.registry, &resources.remote_classes, RemoteOptionsOf(options, remote_calls_)};
    std::shared_ptr<KernelScene> kernel =
        BuildScene(scene, SceneSources{components, resources.device, resources.asset_root});
    auto transport = Make<Transport>(components, Choose(options.transport(), scene.transport(), "path"), "transport");
    auto integrator = Make<Integrator>(
        components,
        IntegratorSpec(options.integrator(), scene.integrator(), CallsOtherProcesses(scene, options, resources)),
        "integrator");
    auto sampler = Make<Sampler>(components, Choose(options.sampler(), scene.sampler(), "sobol"), "sampler");
    {
      std::lock_guard lock(film_mutex_);
      film_ = std::make_unique<Film>(scene.film().width(), scene.film().height(), scene.film().filter());
      width_ = film_->width();
      height_ = film_->height();
    }
    const KernelScene* counters = kernel.get();
    FilmTarget target(*film_, film_mutex_, options.spp(), options.seed(), cancel_, [&](uint32_t done) {
      Update([&](v1::JobStatus& s) {
        s.set_samples_done(done);
        s.set_closest_hit_rays(counters->ClosestHitRays());
        s.set_shadow_rays(counters->ShadowRays());
      });
    });
    // Served while it renders, for transports in other processes.
    const auto served = resources.scenes.Serve(kernel, target);
    transport->Prepare(*kernel);
    integrator->Render(*transport, *kernel, *sampler, target);
    KeepFinalImage();
    Update([&](v1::JobStatus& s) {
      s.set_state(cancel_ ? v1::CANCELLED : v1::SUCCEEDED);
      s.set_closest_hit_rays(counters->ClosestHitRays());
      s.set_shadow_rays(counters->ShadowRays());
    });
  } catch (const std::exception& e) {
    KeepFinalImage();
    Update([&](v1::JobStatus& s) {
      // A cancel that cut a remote call short is a cancel, not a failure.
      s.set_state(cancel_ ? v1::CANCELLED : v1::FAILED);
      if (!cancel_) s.set_error(e.what());
    });
  }
}

JobManager::~JobManager() {
  for (const auto& job : List()) job->RequestCancel();
  threads_.clear();  // joins
}

std::string JobManager::Submit(const v1::SubmitRequest& request) {
  v1::SubmitRequest accepted = request;
  uint32_t spp = request.options().spp();
  if (spp == 0) spp = kDefaultSpp;
  if (spp > kMaxSpp)
    throw Error("spp " + std::to_string(spp) + " is out of range (1 to " + std::to_string(kMaxSpp) + ")");
  accepted.mutable_options()->set_spp(spp);
  const double timeout = request.options().component_timeout_seconds();
  if (!(timeout >= 0 && timeout <= kMaxComponentTimeout))
    throw Error("component_timeout_seconds " + std::to_string(timeout) + " is out of range (0 to " +
                std::to_string(kMaxComponentTimeout) + ")");
  if (request.options().component_retries() > kMaxComponentRetries)
    throw Error("component_retries " + std::to_string(request.options().component_retries()) +
                " is out of range (0 to " + std::to_string(kMaxComponentRetries) + ")");
  ValidateScene(accepted.scene());

  std::lock_guard lock(mutex_);
  char id[32];
  std::snprintf(id, sizeof id, "job-%06llu", static_cast<unsigned long long>(next_id_++));
  auto job = std::make_shared<Job>(id, std::move(accepted));
  jobs_[id] = job;
  threads_.emplace_back([this, job] { job->Run(resources_); });
  return id;
}

std::shared_ptr<Job> JobManager::Find(const std::string& id) const {
  std::lock_guard lock(mutex_);
  auto it = jobs_.find(id);
  return it == jobs_.end() ? nullptr : it->second;
}

std::vector<std::shared_ptr<Job>> JobManager::List() const {
  std::lock_guard lock(mutex_);
  std::vector<std::shared_ptr<Job>> out;
  for (auto it = jobs_.rbegin(); it != jobs_.rend(); ++it) out.push_back(it->second);
  return out;
}

}  // namespace yarf
