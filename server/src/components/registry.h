// The class registry: what yarfd can make, filled by C++ plugins loaded
// at run time (the paper's DLL registration).
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <mutex>
#include <string>
#include <vector>

#include "yarf/component.h"
#include "yarf/error.h"

namespace yarf {

struct PluginFailure {
  std::string path;
  std::string message;
};

// Instances it made must be destroyed before it: their code lives in the
// plugins it unloads.
class Registry final {
 public:
  Registry() = default;
  Registry(const Registry&) = delete;
  Registry& operator=(const Registry&) = delete;
  ~Registry();

  // Loads every lib*.so of a folder; failures are recorded, not thrown.
  void LoadDirectory(const std::filesystem::path& dir);
  // Loads one plugin; throws Error naming the file on failure. Returns the
  // classes it registered.
  std::vector<ComponentInfo> LoadPlugin(const std::filesystem::path& file);

  // Makes an instance; throws Error for an unknown class, a bad property or
  // a property the class did not read.
  std::unique_ptr<Component> Create(const std::string& class_name, const Properties& props) const;
  // Create, then check the instance serves interface I.
  template <typename I>
  std::unique_ptr<I> CreateAs(const std::string& class_name, const Properties& props) const {
    std::unique_ptr<Component> c = Create(class_name, props);
    auto* typed = dynamic_cast<I*>(c.get());
    if (!typed)
      throw Error("class '" + class_name + "' does not implement " + I::kInterface);
    c.release();
    return std::unique_ptr<I>(typed);
  }

  std::vector<ComponentInfo> Classes() const;
  std::vector<PluginFailure> Failures() const;
  bool Has(const std::string& class_name) const;
  // What Describe says of a class; none for an unknown one.
  std::optional<ComponentInfo> Info(const std::string& class_name) const;

 private:
  struct Entry {
    ComponentInfo info;
    ComponentFactory factory;
  };

  mutable std::mutex mutex_;
  std::map<std::string, Entry> classes_;
  std::vector<PluginFailure> failures_;
  // Kept open for the registry's life: instances' code lives in them.
  std::vector<void*> libraries_;
};

}  // namespace yarf
