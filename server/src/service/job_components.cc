#include "service/job_components.h"

#include <algorithm>
#include <optional>
#include <string>

#include "components/make_component.h"
#include "service/job_splits.h"
#include "service/user_files.h"
#include "yarf/error.h"

namespace yarf {
namespace {

// Whether the job calls a component in another process: a class named
// with an address, or registered by a component process, anywhere in the
// scene (materials, emitters, textures, media, aggregates) or the job.
bool CallsOtherProcesses(const v1::Scene& scene, const v1::RenderOptions& options, const JobResources& resources) {
  auto remote = [&](const std::string& class_name, const std::string& address) {
    return !class_name.empty() &&
           (!address.empty() ||
            (!resources.registry.Has(class_name) && resources.remote_classes.AddressOf(class_name).has_value()));
  };
  auto remote_spec = [&](const v1::ComponentSpec& spec) { return remote(spec.class_name(), spec.address()); };
  auto remote_shape = [&](const v1::SceneShape& shape) { return shape.has_emitter() && remote_spec(shape.emitter()); };
  for (const v1::Material& m : scene.materials())
    if (remote(m.class_name(), m.address())) return true;
  for (const v1::ComponentSpec* spec : {&options.transport(), &scene.transport(), &options.sampler(), &scene.sampler(),
                                        &scene.aggregate()})
    if (remote_spec(*spec)) return true;
  if (std::any_of(scene.shapes().begin(), scene.shapes().end(), remote_shape)) return true;
  for (const v1::Group& group : scene.groups())
    if (remote_spec(group.aggregate()) || std::any_of(group.shapes().begin(), group.shapes().end(), remote_shape))
      return true;
  for (const v1::Light& light : scene.lights())
    if (remote_spec(light.emitter())) return true;
  for (const v1::SceneTexture& texture : scene.textures())
    if (remote_spec(texture.texture())) return true;
  for (const v1::SceneMedium& medium : scene.media())
    if (remote_spec(medium.medium())) return true;
  return false;
}

// The integrator a job runs: its own, else the scene's, else the default.
// For jobs that call other processes, an integrator that batches tiles
// and passes (declaring tile_size and samples_per_pass) works in large
// batches (128² pixels × 4 samples per call) unless told otherwise, since
// every call costs a round trip whatever its size.
v1::ComponentSpec IntegratorSpec(const v1::ComponentSpec& job, const v1::ComponentSpec& scene,
                                 bool calls_other_processes, const Registry& registry) {
  v1::ComponentSpec spec = Chosen(job, scene, kDefaultIntegrator);
  if (!calls_other_processes || !spec.address().empty()) return spec;
  const std::optional<ComponentInfo> info = registry.Info(spec.class_name());
  const auto declares = [&](const char* name) {
    return info && std::any_of(info->parameters.begin(), info->parameters.end(),
                               [&](const Parameter& p) { return p.name == name; });
  };
  if (!declares("tile_size") || !declares("samples_per_pass")) return spec;
  auto& values = *spec.mutable_properties()->mutable_values();
  if (!values.contains("tile_size")) values["tile_size"].set_int_value(128);
  if (!values.contains("samples_per_pass")) values["samples_per_pass"].set_int_value(4);
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

std::vector<ComponentInfo> KnownClasses(const JobResources& resources) {
  std::vector<ComponentInfo> classes = resources.registry.Classes();
  for (ComponentInfo& info : resources.remote_classes.Classes()) classes.push_back(std::move(info));
  return classes;
}

JobComponents MakeJobComponents(const v1::SubmitRequest& request, const std::string& owner,
                                const JobResources& resources, std::shared_ptr<RemoteCalls> calls,
                                const std::atomic<bool>& stop) {
  const v1::Scene& scene = request.scene();
  const v1::RenderOptions& options = request.options();
  const ComponentSources components{
      resources.registry, &resources.remote_classes, RemoteOptionsOf(options, std::move(calls)),
      resources.user_files.empty() ? std::filesystem::path() : UserFileFolder(resources.user_files, owner)};
  JobComponents parts;
  // A job reads the assets its owner uploaded, and no others.
  std::optional<UserAssets> assets;
  if (resources.assets) assets.emplace(*resources.assets, owner);
  parts.scene = BuildScene(scene, SceneSources{components, resources.device, resources.asset_root,
                                               assets ? &*assets : nullptr, &stop});
  parts.scene->SetSamplesPerPixel(options.spp());
  parts.transport = Make<Transport>(components, Chosen(options.transport(), scene.transport(), kDefaultTransport), "transport");
  const v1::ComponentSpec integrator =
      IntegratorSpec(options.integrator(), scene.integrator(), CallsOtherProcesses(scene, options, resources),
                     resources.registry);
  parts.integrator = Make<Integrator>(components, integrator, "integrator");
  parts.sampler = Make<Sampler>(components, Chosen(options.sampler(), scene.sampler(), kDefaultSampler), "sampler");
  parts.resumable = SplitsOf(request, KnownClasses(resources)).sample_ranges();
  for (const std::string& name : options.aovs()) {
    v1::ComponentSpec aov;
    aov.set_class_name("aov");
    (*aov.mutable_properties()->mutable_values())["aov"].set_string_value(name);
    parts.aovs.emplace_back(name, Make<Transport>(components, aov, "aov"));
  }
  if (!parts.aovs.empty()) {
    v1::ComponentSpec mean_sample;
    mean_sample.set_class_name("mean_sample");
    parts.aov_integrator = Make<Integrator>(components, mean_sample, "aov integrator");
  }
  return parts;
}

FilmTarget::Share ShareOf(const v1::RenderOptions& options) {
  FilmTarget::Share share{options.first_sample(), std::nullopt};
  if (options.has_crop()) {
    const v1::PixelWindow& c = options.crop();
    share.crop = PixelWindow{c.x0(), c.y0(), c.x1(), c.y1()};
  }
  return share;
}

}  // namespace yarf
