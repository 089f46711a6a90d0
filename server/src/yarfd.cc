// yarfd: the render server. Loads the plugins, then serves rendering, the
// component registry, health and reflection until SIGINT or SIGTERM.
#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>
#include <tbb/global_control.h>

#include <malloc.h>
#include <sys/prctl.h>
#include <unistd.h>

#include <csignal>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <vector>

#include "grpc/health/v1/health.pb.h"
#include "service/asset_service.h"
#include "service/component_service.h"
#include "service/instance_services.h"
#include "service/job_events.h"
#include "service/job_memory.h"
#include "service/job_scene_service.h"
#include "service/listen_port.h"
#include "service/metrics_endpoint.h"
#include "service/render_service.h"
#include "service/request_checks.h"
#include "service/server_credentials.h"
#include "service/server_options.h"
#include "service/server_metrics.h"

namespace {

// The number of jobs in each state, every state named even when none is in it.
std::map<std::string, uint64_t> CountJobsByState(const yarf::JobManager& jobs) {
  std::map<std::string, uint64_t> counts;
  const auto* states = yarf::v1::JobState_descriptor();
  for (int i = 0; i < states->value_count(); ++i)
    if (states->value(i)->number() != yarf::v1::JOB_STATE_UNSPECIFIED) counts[states->value(i)->name()] = 0;
  for (const auto& job : jobs.List()) ++counts[yarf::v1::JobState_Name(job->Status().state())];
  return counts;
}

int Serve(const yarf::ServerOptions& options, const sigset_t& signals) {
  // Every job, plugin and component call would run with every right.
  if (geteuid() == 0 && !options.allow_root) {
    std::cerr << "yarfd: refusing to run as root: run it as a user of its own (deploy/systemd does), or pass "
                 "--allow-root (YARF_ALLOW_ROOT=1) where root is all there is, as in a container\n";
    return 2;
  }
  // Stops with the process that started it (an embedded server's
  // notebook or script), however that ends: SIGTERM, as from a user.
  if (options.parent_pid > 0) {
    prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (getppid() != options.parent_pid) {
      std::cerr << "yarfd: the process " << options.parent_pid << " that started it has ended\n";
      return 1;
    }
  }
  // First: a refused address or a bad tokens file stops yarfd before any work.
  const auto credentials = yarf::ListenCredentials(options);
  // So is a port another process holds: yarfd never shares one.
  yarf::CheckPortFree(options.listen);
  if (!options.metrics.empty()) yarf::CheckPortFree(options.metrics);
  std::optional<tbb::global_control> threads;
  if (options.threads > 0) threads.emplace(tbb::global_control::max_allowed_parallelism, options.threads);

  yarf::EmbreeDevice device;
  yarf::Registry registry;
  for (const auto& dir : options.plugin_paths) registry.LoadDirectory(dir);
  for (const auto& failure : registry.Failures())
    std::cerr << "yarfd: plugin " << failure.path << ": " << failure.message << "\n";

  yarf::RemoteClasses remote_classes(registry);
  for (const auto& address : options.components) {
    try {
      remote_classes.Register(address, std::chrono::seconds(0));
    } catch (const std::exception& e) {
      std::cerr << "yarfd: component " << address << ": " << e.what() << "\n";
    }
  }

  // Every job event is a line on stderr, and counts in the metrics when
  // they are asked for.
  yarf::JobLog job_log(std::cerr, options.log_json);
  std::optional<yarf::ServerMetrics> metrics;
  std::vector<yarf::JobObserver*> observers = {&job_log};
  if (!options.metrics.empty()) observers.push_back(&metrics.emplace());
  yarf::JobObservers job_observers(std::move(observers));

  yarf::InstanceTable instances(uint64_t(options.max_instances_per_user),
                                std::chrono::seconds(options.instance_idle_seconds));
  yarf::JobScenes job_scenes(instances);
  // Locked before anything touches the folder: a second yarfd on it stops here.
  yarf::StateFolder state_folder(options.state_dir);
  yarf::AssetStore assets(options.state_dir / "assets", options.max_asset_bytes_per_user);
  yarf::JobManager jobs({registry, remote_classes, device, options.asset_root, job_scenes, &assets,
                         options.state_dir / "files"},
                        {.max_running_jobs = uint32_t(options.max_running_jobs),
                         .checkpoint_seconds = options.checkpoint_seconds,
                         .keep_finished_hours = options.keep_finished_hours,
                         .max_finished_jobs = uint64_t(options.max_finished_jobs),
                         .max_queued_jobs_per_user = uint64_t(options.max_queued_jobs_per_user),
                         .max_job_bytes = options.max_job_memory ? options.max_job_memory : yarf::DefaultMaxJobBytes(),
                         .asset_grace_hours = options.asset_grace_hours},
                        state_folder, &job_observers);
  yarf::AssetServiceImpl asset_service(assets);
  yarf::RenderServiceImpl render(jobs, uint32_t(options.max_watches_per_user));
  yarf::RegistryServiceImpl registry_service(registry, remote_classes,
                                             {options.allow_load_plugin, options.plugin_paths});
  yarf::ComponentServiceImpl component(registry, remote_classes, instances);
  yarf::FactoryServiceImpl factory(
      registry, remote_classes, instances,
      {.deadline = std::chrono::milliseconds(int64_t(options.component_timeout_seconds * 1000))});
  yarf::IntersectServiceImpl intersect(job_scenes);
  yarf::SceneViewServiceImpl scene_view(job_scenes);
  yarf::ShapeServiceImpl shape(job_scenes);
  yarf::SampleSurfaceAreaServiceImpl sample_surface_area(job_scenes);
  yarf::SampleSurfaceDirectionServiceImpl sample_surface_direction(job_scenes);
  yarf::IntegratorServiceImpl integrator(registry, instances);
  yarf::RootFinderServiceImpl root_finder(instances);
  yarf::SamplerServiceImpl sampler(instances);
  yarf::GeneratorServiceImpl generator(instances);
  yarf::WarpServiceImpl warp(instances);
  yarf::SurfaceModelServiceImpl surface_model(instances);
  yarf::EmitterServiceImpl emitter(instances);
  yarf::MediumServiceImpl medium(instances);

  grpc::EnableDefaultHealthCheckService(true);
  // gRPC serves the health service without putting its descriptor in the
  // pool reflection reads; naming a message of it links the health proto
  // in, so that grpcurl and other reflection clients can call it.
  grpc::health::v1::HealthCheckRequest::descriptor();
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  grpc::ServerBuilder builder;
  int port = 0;
  builder.AddListeningPort(options.listen, credentials, &port);
  // gRPC sets SO_REUSEPORT by default: a second server on a port in use
  // would start, and clients would alternate between the two.
  builder.AddChannelArgument(GRPC_ARG_ALLOW_REUSEPORT, 0);
  // Batches and images are large.
  builder.SetMaxReceiveMessageSize(yarf::kMaxMessageBytes);
  builder.SetMaxSendMessageSize(yarf::kMaxMessageBytes);
  if (metrics) {
    std::vector<std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface>> timers;
    timers.push_back(metrics->CallTimer());
    builder.experimental().SetInterceptorCreators(std::move(timers));
  }
  for (grpc::Service* service : std::initializer_list<grpc::Service*>{
           &render, &registry_service, &component, &factory, &integrator, &root_finder, &sampler, &generator, &warp,
           &surface_model, &emitter, &medium, &intersect, &scene_view, &shape, &sample_surface_area,
           &sample_surface_direction, &asset_service})
    builder.RegisterService(service);
  std::unique_ptr<grpc::Server> server = builder.BuildAndStart();
  if (!server) {
    std::cerr << "yarfd: cannot listen on " << options.listen << " (is another server using it?)\n";
    return 1;
  }
  // Jobs start once the server listens: their components may call it back.
  jobs.Start();
  std::cout << "yarfd listening on " << options.listen << " (port " << port << ")" << std::endl;
  // Stopped before the jobs it counts go (declared after them).
  std::optional<yarf::MetricsEndpoint> metrics_endpoint;
  if (metrics) {
    metrics_endpoint.emplace(options.metrics, [&] { return metrics->Exposition(CountJobsByState(jobs)); });
    std::cout << "yarfd metrics on " << options.metrics << " (port " << metrics_endpoint->port()
              << "), at /metrics" << std::endl;
  }
  if (!options.port_file.empty()) {
    const auto tmp = options.port_file.string() + ".tmp";
    std::ofstream(tmp) << port << "\n";
    std::filesystem::rename(tmp, options.port_file);
  }
  int signal = 0;
  sigwait(&signals, &signal);
  std::cout << "yarfd: shutting down" << std::endl;
  // Jobs first, while the server still answers the calls their components
  // make back to it: a stopped job waits, QUEUED, for the next start.
  jobs.StopAll();
  server->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(2));
  return 0;
}

// --check-requests: touches no state and listens nowhere; loads the
// plugins only to read their classes' capabilities.
int CheckRequests(const yarf::ServerOptions& options) {
  yarf::Registry registry;
  for (const auto& dir : options.plugin_paths) registry.LoadDirectory(dir);
  return yarf::ServeRequestChecks(std::cin, std::cout, registry.Classes());
}

}  // namespace

int main(int argc, char** argv) {
  // Render threads allocate and free batch buffers of a few megabytes per
  // tile. With glibc's defaults such a block is a fresh mmap, or is handed
  // back to the kernel when freed, and every reuse faults its pages in
  // again (a tenth of bdpt's cycles): blocks up to 32 MiB come from the heap,
  // and each arena keeps up to 32 MiB free.
  constexpr int kHeldBlock = 32 << 20;
  mallopt(M_MMAP_THRESHOLD, kHeldBlock);
  mallopt(M_TRIM_THRESHOLD, kHeldBlock);
  // Block the stop signals in every thread; the main thread waits for them.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  try {
    const yarf::ServerOptions options = yarf::ParseServerOptions(argc, argv);
    if (options.check_requests) return CheckRequests(options);
    return Serve(options, signals);
  } catch (const std::exception& e) {
    std::cerr << "yarfd: " << e.what() << "\n";
    return 2;
  }
}
