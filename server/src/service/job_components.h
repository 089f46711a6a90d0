// What a job's render is made of: its kernel scene and the transport,
// integrator and sampler its request and scene choose.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "components/remote_classes.h"
#include "components/remote_instance.h"
#include "kernel/embree_device.h"
#include "kernel/film_target.h"
#include "components/scene_builder.h"
#include "service/asset_store.h"
#include "service/job_scenes.h"
#include "yarf/transport.h"
#include "yarf/v1/render.pb.h"

namespace yarf {

// What jobs are made from: the classes (in process and in component
// processes), the device, the folder mesh files resolve in, the table
// that serves running jobs' scenes to remote transports, and the uploaded
// assets (null: none).
struct JobResources {
  const Registry& registry;
  const RemoteClasses& remote_classes;
  const EmbreeDevice& device;
  std::filesystem::path asset_root;
  JobScenes& scenes;
  const AssetStore* assets = nullptr;
  // Where each user's folder of component files lies; empty: none.
  std::filesystem::path user_files;
};

// The classes a job may name without an address: the plugins' and those
// of component processes registered now.
std::vector<ComponentInfo> KnownClasses(const JobResources& resources);

struct JobComponents {
  std::shared_ptr<KernelScene> scene;
  std::unique_ptr<Transport> transport;
  std::unique_ptr<Integrator> integrator;
  std::unique_ptr<Sampler> sampler;
  // Whether the render can go on from a checkpoint of its film: its
  // integrator renders sample passes from any first sample with the same
  // per-sample seeds (JobSplits.sample_ranges), so a resumed render gives
  // the image an uninterrupted one gives. Others start anew.
  bool resumable = false;
  // RenderOptions.aovs: an `aov` transport for each, in its order, and the
  // mean_sample integrator that renders them.
  std::vector<std::pair<std::string, std::unique_ptr<Transport>>> aovs;
  std::unique_ptr<Integrator> aov_integrator;
};

// Builds the scene and makes the components of a job of `owner`; throws
// Error naming the part that failed. Calls to other processes are
// tracked in `calls`; once `stop` is set, building and tracing stop.
JobComponents MakeJobComponents(const v1::SubmitRequest& request, const std::string& owner,
                                const JobResources& resources, std::shared_ptr<RemoteCalls> calls,
                                const std::atomic<bool>& stop);

// The samples and pixels the request asks for (RenderOptions.first_sample, crop).
FilmTarget::Share ShareOf(const v1::RenderOptions& options);

}  // namespace yarf
