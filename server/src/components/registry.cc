#include "components/registry.h"

#include <dlfcn.h>

#include <algorithm>

#include "components/parameter_checks.h"

namespace yarf {
namespace {

using RegisterFunction = void (*)(Registrar&);

// Collects what one plugin registers, so a plugin that throws halfway
// adds nothing.
class CollectingRegistrar final : public Registrar {
 public:
  struct Item {
    ComponentInfo info;
    ComponentFactory factory;
  };
  void Add(ComponentInfo info, ComponentFactory factory) override {
    items.push_back({std::move(info), std::move(factory)});
  }
  std::vector<Item> items;
};

}  // namespace

Registry::~Registry() {
  // The factories' code lives in the libraries: drop them first.
  classes_.clear();
  for (void* lib : libraries_) dlclose(lib);
}

void Registry::LoadDirectory(const std::filesystem::path& dir) {
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) {
    std::lock_guard lock(mutex_);
    failures_.push_back({dir.string(), "plugin folder does not exist"});
    return;
  }
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    if (entry.path().extension() == ".so") files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  for (const auto& file : files) {
    try {
      LoadPlugin(file);
    } catch (const Error& e) {
      std::lock_guard lock(mutex_);
      failures_.push_back({file.string(), e.what()});
    }
  }
}

std::vector<ComponentInfo> Registry::LoadPlugin(const std::filesystem::path& file) {
  const std::string path = file.string();
  void* lib = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!lib) throw Error("plugin '" + path + "' failed to load: " + dlerror());
  // Before any call into it: a plugin built against other headers may lay
  // out every interface differently.
  using VersionFunction = const char* (*)();
  auto version = reinterpret_cast<VersionFunction>(dlsym(lib, YARF_VERSION_SYMBOL));
  if (!version) {
    dlclose(lib);
    throw Error("plugin '" + path + "' exports no " YARF_VERSION_SYMBOL
                ": it was built against yarf headers older than this yarfd's; rebuild it against them");
  }
  if (const std::string built = version(); built != YARF_INTERFACE_VERSION) {
    dlclose(lib);
    throw Error("plugin '" + path + "' was built against yarf interface version " + built.substr(0, 32) +
                ", this yarfd has " YARF_INTERFACE_VERSION ": rebuild it against this yarf's headers");
  }
  auto fn = reinterpret_cast<RegisterFunction>(dlsym(lib, YARF_REGISTER_SYMBOL));
  if (!fn) {
    dlclose(lib);
    throw Error("plugin '" + path + "' does not export " YARF_REGISTER_SYMBOL);
  }
  CollectingRegistrar collected;
  std::string refusal;
  try {
    fn(collected);
    for (const auto& item : collected.items) CheckSchema(item.info);
  } catch (const std::exception& e) {
    refusal = e.what();
  } catch (...) {
    refusal = "it threw something that is no std::exception";
  }
  if (!refusal.empty()) {
    // The factories' code, and an exception's, is the plugin's: they go
    // before the plugin does.
    collected.items.clear();
    dlclose(lib);
    throw Error("plugin '" + path + "' failed to register: " + refusal);
  }
  std::vector<ComponentInfo> added;
  std::lock_guard lock(mutex_);
  for (auto& item : collected.items) {
    if (classes_.count(item.info.class_name)) {
      failures_.push_back({path, "class '" + item.info.class_name + "' already registered by " +
                                     classes_[item.info.class_name].info.origin});
      continue;
    }
    item.info.origin = path;
    added.push_back(item.info);
    classes_[item.info.class_name] = {item.info, std::move(item.factory)};
  }
  libraries_.push_back(lib);
  return added;
}

std::unique_ptr<Component> Registry::Create(const std::string& class_name,
                                            const Properties& props) const {
  Entry entry;
  {
    std::lock_guard lock(mutex_);
    auto it = classes_.find(class_name);
    if (it == classes_.end()) throw Error("unknown component class '" + class_name + "'");
    entry = it->second;
  }
  // The declared defaults of the keys left out reach the class.
  Properties given = props;
  for (const Parameter& parameter : entry.info.parameters)
    if (parameter.default_value && !given.Has(parameter.name)) given.SetDefault(parameter.name, *parameter.default_value);
  std::unique_ptr<Component> instance;
  try {
    instance = entry.factory(given);
  } catch (const std::exception& e) {
    throw Error("component '" + class_name + "': " + e.what());
  }
  std::vector<std::string> unread = given.Unread();
  if (entry.info.declares_parameters && !unread.empty()) {
    std::vector<std::string> names;
    for (const Parameter& parameter : entry.info.parameters) names.push_back(parameter.name);
    const std::string nearest = DidYouMean(unread.front(), names);
    throw Error("component '" + class_name + "' has no parameter '" + unread.front() + "'" +
                (nearest.empty() ? "" : "; did you mean '" + nearest + "'?"));
  }
  if (!unread.empty()) {
    std::string keys;
    for (const auto& k : unread) keys += (keys.empty() ? "'" : ", '") + k + "'";
    throw Error("component '" + class_name + "' does not understand property " + keys);
  }
  instance->SetInfo(entry.info);
  return instance;
}

std::vector<ComponentInfo> Registry::Classes() const {
  std::lock_guard lock(mutex_);
  std::vector<ComponentInfo> out;
  for (const auto& [name, entry] : classes_) out.push_back(entry.info);
  return out;
}

std::vector<PluginFailure> Registry::Failures() const {
  std::lock_guard lock(mutex_);
  return failures_;
}

std::optional<ComponentInfo> Registry::Info(const std::string& class_name) const {
  std::lock_guard lock(mutex_);
  const auto it = classes_.find(class_name);
  if (it == classes_.end()) return std::nullopt;
  return it->second.info;
}

bool Registry::Has(const std::string& class_name) const {
  std::lock_guard lock(mutex_);
  return classes_.count(class_name) != 0;
}

}  // namespace yarf
