// The job table: accepted render jobs, each rendering on its own thread
// while the server stays responsive.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "components/remote_classes.h"
#include "components/remote_instance.h"
#include "kernel/embree_device.h"
#include "kernel/film.h"
#include "service/job_scenes.h"
#include "yarf/v1/render.pb.h"

namespace yarf {

// What jobs are made from: the classes (in process and in component
// processes), the device, the folder assets resolve in, and the table
// that serves running jobs' scenes to remote transports.
struct JobResources {
  const Registry& registry;
  const RemoteClasses& remote_classes;
  const EmbreeDevice& device;
  std::filesystem::path asset_root;
  JobScenes& scenes;
};

class Job {
 public:
  Job(std::string id, v1::SubmitRequest request);

  const std::string& id() const { return id_; }
  const v1::SubmitRequest& request() const { return request_; }
  v1::JobStatus Status() const;
  // Bumped on every change, for watchers.
  uint64_t Version() const;
  // Waits until the version differs from `seen` or `timeout` passes.
  void WaitForChange(uint64_t seen, std::chrono::milliseconds timeout) const;
  void RequestCancel();
  bool Finished() const;
  // Pixels and variances of the film so far (empty before the film exists).
  bool Snapshot(std::vector<float>& pixels, std::vector<float>& variances, uint32_t& width,
                uint32_t& height) const;

  // Runs the job to its end (called on the job's own thread).
  void Run(const JobResources& resources);

 private:
  void Update(const std::function<void(v1::JobStatus&)>& change);
  void KeepFinalImage();

  const std::string id_;
  const v1::SubmitRequest request_;
  std::atomic<bool> cancel_{false};
  // Calls to components in other processes, ended at once by a cancel.
  const std::shared_ptr<RemoteCalls> remote_calls_ = std::make_shared<RemoteCalls>();
  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;
  v1::JobStatus status_;
  uint64_t version_ = 0;
  std::chrono::steady_clock::time_point started_;
  // The film while rendering; once the job ends only its estimates are
  // kept (a film holds several times their size).
  std::unique_ptr<Film> film_;
  std::vector<float> final_pixels_, final_variances_;
  uint32_t width_ = 0, height_ = 0;
  mutable std::mutex film_mutex_;
};

class JobManager {
 public:
  explicit JobManager(JobResources resources) : resources_(std::move(resources)) {}
  // Cancels running jobs and waits for their threads.
  ~JobManager();

  // Validates and starts a job; throws Error for a scene or options it refuses.
  std::string Submit(const v1::SubmitRequest& request);
  std::shared_ptr<Job> Find(const std::string& id) const;
  std::vector<std::shared_ptr<Job>> List() const;

 private:
  const JobResources resources_;
  mutable std::mutex mutex_;
  uint64_t next_id_ = 1;
  std::map<std::string, std::shared_ptr<Job>> jobs_;
  std::vector<std::jthread> threads_;
};

}  // namespace yarf
