#include "components/make_remote_instance.h"

#include <vector>

#include "components/make_component.h"

namespace yarf {
namespace {

using Maker = std::unique_ptr<Component> (*)(std::unique_ptr<RemoteInstance>);

template <typename I>
std::unique_ptr<Component> Make(std::unique_ptr<RemoteInstance> instance) {
  return std::make_unique<Remote<I>>(std::move(instance));
}

template <typename I>
constexpr std::pair<const char*, Maker> kMaker{I::kInterface, &Make<I>};

// Transport is left out: a remote transport needs a job's scene.
constexpr std::pair<const char*, Maker> kMakers[] = {
    kMaker<SurfaceModel>, kMaker<Emitter>, kMaker<Sampler>,    kMaker<Function>,   kMaker<Texture>,
    kMaker<Medium>,       kMaker<Warp>,    kMaker<RootFinder>, kMaker<Generator>, kMaker<Integrator>};

}  // namespace

std::unique_ptr<Component> MakeRemoteInstance(const ComponentInfo& info, const std::string& address,
                                              const v1::Properties& properties, const RemoteOptions& options) {
  std::vector<std::pair<std::string, Maker>> usable;
  for (const std::string& id : info.interfaces)
    for (const auto& [interface, make] : kMakers)
      if (id == interface) usable.emplace_back(id, make);
  if (usable.size() != 1)
    throw Error("class '" + info.class_name + "' lives in the component at " + address + " and serves " +
                (usable.empty() ? "no interface this server calls" : "several interfaces") +
                ": create its instances there");
  std::unique_ptr<Component> instance = usable[0].second(
      std::make_unique<RemoteInstance>(address, info.class_name, properties, usable[0].first, options));
  instance->SetInfo(info);
  return instance;
}

}  // namespace yarf
