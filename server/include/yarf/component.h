// The component model in process: every component derives from Component;
// a plugin registers its classes through one exported function.
#pragma once

#include <concepts>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "yarf/interface_version.h"
#include "yarf/parameters.h"
#include "yarf/properties.h"

namespace yarf {

// Answer to Describe (proto ComponentInfo).
struct ComponentInfo {
  std::string class_name;
  std::string version;
  std::vector<std::string> interfaces;
  std::string summary;
  std::string origin;
  // The class's parameters, when it declares them (declares_parameters):
  // then a property not among them is refused.
  bool declares_parameters = false;
  std::vector<Parameter> parameters;
  // What the class can do beyond its interfaces (kCapabilities), which the
  // service and the farm read instead of comparing class names.
  std::vector<std::string> capabilities;
};

// Capabilities a class may declare.
// An Integrator that renders any range of sample passes, from
// RenderTarget::FirstSample() on, and only RenderTarget::Crop()'s pixels,
// with the same per-sample seeds whatever the range: its jobs resume from
// a checkpoint, split into sample shares and tiles, and take a crop.
inline constexpr char kSamplePassesCapability[] = "sample_passes";
// A Transport whose film samples land only where their own points' film
// coordinates put them (it never splats): tiles rendered apart make the
// whole film.
inline constexpr char kPixelLocalCapability[] = "pixel_local";
// A Sampler whose points of a pixel are best in counts that are powers of
// two: a count between two leaves the finer power's pattern part-made
// (Sobol's nets), so Submit warns of one.
inline constexpr char kPowerOfTwoSamplesCapability[] = "power_of_two_samples";
inline const std::vector<std::string> kCapabilities = {kSamplePassesCapability, kPixelLocalCapability,
                                                       kPowerOfTwoSamplesCapability};

inline bool HasCapability(const ComponentInfo& info, std::string_view capability) {
  for (const std::string& c : info.capabilities)
    if (c == capability) return true;
  return false;
}

// A class declares capabilities with `static std::vector<std::string> Capabilities()`.
template <typename T>
concept DeclaresCapabilities = requires {
  { T::Capabilities() } -> std::convertible_to<std::vector<std::string>>;
};

class Component {
 public:
  virtual ~Component() = default;
  // Which class this is and the interfaces it serves (QueryInterface).
  const ComponentInfo& Describe() const { return info_; }
  void SetInfo(ComponentInfo info) { info_ = std::move(info); }

 private:
  ComponentInfo info_;
};

using ComponentFactory = std::function<std::unique_ptr<Component>(const Properties&)>;

// What a plugin's registration function receives.
class Registrar {
 public:
  virtual ~Registrar() = default;
  virtual void Add(ComponentInfo info, ComponentFactory factory) = 0;
};

// The interfaces (proto service names) a C++ class implements, found from
// its bases: each interface class names its service in kInterface.
// An interface's virtual methods mirror its service's rpcs: each serves the
// rpc of its own name, unless the comment above it has a line
// `rpc: Name[, Name]` (the rpcs it serves) or `in-process only: why`; and
// every rpc is served by some method. tests/test_interface_mirror.py reads
// both declarations and checks.
template <typename T, typename... Interfaces>
std::vector<std::string> InterfacesOf() {
  std::vector<std::string> names;
  ((std::is_base_of_v<Interfaces, T> ? names.push_back(Interfaces::kInterface) : void()), ...);
  return names;
}

}  // namespace yarf

// Names of the two functions a plugin exports: the interface version it
// was compiled against, checked before anything else, and its registration.
#define YARF_VERSION_SYMBOL "yarf_interface_version"
#define YARF_REGISTER_SYMBOL "yarf_register_components"
// Defines both: YARF_PLUGIN(registrar) { yarf::Register<Lambertian>(registrar, ...); }
#define YARF_PLUGIN(registrar)                                                                                  \
  extern "C" __attribute__((visibility("default"))) const char* yarf_interface_version() {                      \
    return YARF_INTERFACE_VERSION;                                                                              \
  }                                                                                                             \
  extern "C" __attribute__((visibility("default"))) void yarf_register_components(yarf::Registrar& registrar)
