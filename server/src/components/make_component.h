// Making the component a scene or a job names: an in-process class of the
// registry, or one made in a component process (the spec's address, or a
// registered remote class) behind Remote<I>. Callers cannot tell them apart.
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <type_traits>

#include "components/properties_proto.h"
#include "components/registry.h"
#include "components/remote_classes.h"
#include "components/remote_emitter.h"
#include "components/remote_function.h"
#include "components/remote_generator.h"
#include "components/remote_integrator.h"
#include "components/remote_medium.h"
#include "components/remote_root_finder.h"
#include "components/remote_sampler.h"
#include "components/remote_surface_model.h"
#include "components/remote_texture.h"
#include "components/remote_transport.h"
#include "components/remote_warp.h"
#include "yarf/texture.h"

namespace yarf {

struct ComponentSources {
  ComponentSources(const Registry& registry, const RemoteClasses* remote_classes = nullptr,
                   RemoteOptions remote_options = {}, std::filesystem::path file_folder = {})
      : registry(registry),
        remote_classes(remote_classes),
        remote_options(remote_options),
        file_folder(std::move(file_folder)) {}

  const Registry& registry;
  // Classes of component processes; nullptr: none.
  const RemoteClasses* remote_classes;
  RemoteOptions remote_options;
  // Where in-process components may keep files (Properties::File); empty: nowhere.
  std::filesystem::path file_folder;
};

// What the kernel resolves in a component's properties before the
// component is made: references to the scene's textures, and files the
// server found for it (a request names files only by relative path or
// asset hash).
struct ResolvedProperties {
  // The scene's, by name, which every component made from it shares
  // (never copied: a scene may hold many); null: none may be named.
  const std::map<std::string, std::shared_ptr<const Texture>>* textures = nullptr;
  const std::map<std::string, std::shared_ptr<const SurfaceModel>>* materials = nullptr;
  // The component's own, by property key.
  std::map<std::string, std::filesystem::path> files;
};

// The interfaces with a Remote<I>.
template <typename I>
constexpr bool kHasRemote = std::is_same_v<I, SurfaceModel> || std::is_same_v<I, Emitter> ||
                            std::is_same_v<I, Sampler> || std::is_same_v<I, Transport> ||
                            std::is_same_v<I, Function> || std::is_same_v<I, Texture> || std::is_same_v<I, Medium> ||
                            std::is_same_v<I, Warp> || std::is_same_v<I, RootFinder> ||
                            std::is_same_v<I, Generator> || std::is_same_v<I, Integrator>;

// `address` empty: the registry's class, or a registered remote class.
template <typename I>
std::unique_ptr<I> MakeComponent(const ComponentSources& sources, const std::string& class_name,
                                 const v1::Properties& properties, const std::string& address = "",
                                 const ResolvedProperties* resolved = nullptr) {
  std::string where = address;
  if (where.empty() && sources.remote_classes && !sources.registry.Has(class_name))
    where = sources.remote_classes->AddressOf(class_name).value_or("");
  if (where.empty()) {
    Properties local = FromProto(properties);
    local.SetFileFolder(sources.file_folder);
    if (resolved) {
      for (const auto& [key, value] : properties.values()) {
        if (value.value_case() != v1::Property::kReference) continue;
        if (resolved->textures)
          if (auto it = resolved->textures->find(value.reference()); it != resolved->textures->end()) {
            local.Set(key, it->second);
            continue;
          }
        if (resolved->materials)
          if (auto model = resolved->materials->find(value.reference()); model != resolved->materials->end())
            local.Set(key, model->second);
      }
      for (const auto& [key, path] : resolved->files) local.Set(key, path);
    }
    return sources.registry.CreateAs<I>(class_name, local);
  }
  if constexpr (kHasRemote<I>) {
    return std::make_unique<Remote<I>>(
        std::make_unique<RemoteInstance>(where, class_name, properties, I::kInterface, sources.remote_options));
  } else {
    throw Error("class '" + class_name + "' at " + where + ": this server cannot use a remote " +
                std::string(I::kInterface) + " yet");
  }
}

}  // namespace yarf
