// What a plugin source file includes to register its classes.
#pragma once

#include <memory>
#include <string>

#include "yarf/aggregate.h"
#include "yarf/component.h"
#include "yarf/math.h"
#include "yarf/medium.h"
#include "yarf/surface.h"
#include "yarf/texture.h"
#include "yarf/transport.h"

namespace yarf {

// Registers class T, constructible from Properties, under `name`.
template <typename T>
void Register(Registrar& registrar, std::string name, std::string version, std::string summary) {
  ComponentInfo info;
  info.class_name = std::move(name);
  info.version = std::move(version);
  info.interfaces = InterfacesOf<T, Function, Integrator, Sampler, Generator, RootFinder, Warp, SurfaceModel,
                                 Emitter, Transport, Texture, Medium, Aggregate>();
  info.summary = std::move(summary);
  if constexpr (DeclaresParameters<T>) {
    info.declares_parameters = true;
    info.parameters = T::Parameters();
  }
  if constexpr (DeclaresCapabilities<T>) info.capabilities = T::Capabilities();
  registrar.Add(std::move(info), [](const Properties& p) -> std::unique_ptr<Component> {
    return std::make_unique<T>(p);
  });
}

}  // namespace yarf
