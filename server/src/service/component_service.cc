#include "service/component_service.h"

#include <random>

#include "components/make_remote_instance.h"
#include "components/parameter_checks.h"
#include "components/properties_proto.h"

namespace yarf {

uint64_t RandomHandle() {
  std::random_device entropy;  // the kernel's CSPRNG (getrandom)
  return ((uint64_t(entropy()) << 32 | entropy()) >> 2) + 1;
}

uint64_t InstanceTable::Add(std::unique_ptr<Component> instance, const std::string& owner) {
  std::lock_guard lock(mutex_);
  if (!owner.empty() && per_owner_[owner] >= max_per_user_) ReleaseIdle(owner);
  if (!owner.empty() && per_owner_[owner] >= max_per_user_)
    throw LimitReached(owner + " holds " + std::to_string(per_owner_[owner]) +
                        " instances, the most one user may (yarfd --max-instances-per-user); release some first");
  uint64_t handle = RandomHandle();
  while (instances_.contains(handle)) handle = RandomHandle();
  instances_[handle] = {std::move(instance), owner, std::chrono::steady_clock::now()};
  if (!owner.empty()) ++per_owner_[owner];
  return handle;
}

void InstanceTable::ReleaseIdle(const std::string& owner) {
  const auto cutoff = std::chrono::steady_clock::now() - idle_;
  for (auto it = instances_.begin(); it != instances_.end();) {
    const auto next = std::next(it);
    if (it->second.owner == owner && it->second.used < cutoff) Erase(it);
    it = next;
  }
}

void InstanceTable::Erase(std::map<uint64_t, Entry>::iterator it) {
  if (const std::string& owner = it->second.owner; !owner.empty() && --per_owner_[owner] == 0) per_owner_.erase(owner);
  instances_.erase(it);
}

bool InstanceTable::Release(uint64_t handle, const Caller& caller) {
  std::lock_guard lock(mutex_);
  auto it = instances_.find(handle);
  if (it == instances_.end() || !MayActOn(caller, it->second.owner)) return false;
  Erase(it);
  return true;
}

void InstanceTable::Release(uint64_t handle) {
  std::lock_guard lock(mutex_);
  if (auto it = instances_.find(handle); it != instances_.end()) Erase(it);
}

std::shared_ptr<Component> InstanceTable::Find(uint64_t handle, const Caller& caller) const {
  std::lock_guard lock(mutex_);
  auto it = instances_.find(handle);
  if (it == instances_.end() || !MayActOn(caller, it->second.owner)) return nullptr;
  it->second.used = std::chrono::steady_clock::now();
  return it->second.instance;
}

grpc::Status RegistryServiceImpl::ListClasses(grpc::ServerContext*, const v1::ListClassesRequest*,
                                              v1::ListClassesReply* reply) {
  for (const ComponentInfo& info : registry_.Classes()) *reply->add_classes() = ToProto(info);
  for (const ComponentInfo& info : remote_.Classes()) *reply->add_classes() = ToProto(info);
  for (const PluginFailure& failure : registry_.Failures()) {
    v1::PluginError* e = reply->add_plugin_errors();
    e->set_path(failure.path);
    e->set_message(failure.message);
  }
  return grpc::Status::OK;
}

namespace {

// The plugin file `path` names, resolved, if the policy lets it load;
// else Error saying why.
std::filesystem::path AllowedPlugin(const PluginPolicy& policy, const std::string& path) {
  namespace fs = std::filesystem;
  if (!policy.allowed)
    throw Error("plugin '" + path + "': this server loads no plugins on request (start yarfd with "
                "--allow-load-plugin, or put the plugin in a --plugin-path folder and restart it)");
  std::error_code error;
  const fs::path file = fs::canonical(path, error);
  if (error) throw Error("plugin '" + path + "': " + error.message());
  for (const fs::path& folder : policy.folders) {
    const fs::path allowed = fs::canonical(folder, error);
    if (!error && file.parent_path() == allowed && fs::is_regular_file(file)) return file;
  }
  throw Error("plugin '" + path + "' is not a file directly inside a --plugin-path folder of this server");
}

}  // namespace

grpc::Status RegistryServiceImpl::LoadPlugin(grpc::ServerContext*, const v1::LoadPluginRequest* request,
                                             v1::LoadPluginReply* reply) {
  try {
    for (const ComponentInfo& info : registry_.LoadPlugin(AllowedPlugin(plugins_, request->path())))
      *reply->add_classes() = ToProto(info);
    return grpc::Status::OK;
  } catch (const Error& e) {
    return {grpc::StatusCode::FAILED_PRECONDITION, e.what()};
  }
}

grpc::Status RegistryServiceImpl::Register(grpc::ServerContext*, const v1::RegisterRequest* request,
                                           v1::RegisterReply* reply) {
  const std::chrono::seconds lease =
      request->lease_seconds() > 0 ? std::chrono::seconds(request->lease_seconds()) : RemoteClasses::kDefaultLease;
  try {
    for (const ComponentInfo& info : remote_.Register(request->address(), lease)) *reply->add_classes() = ToProto(info);
    reply->set_lease_seconds(uint32_t(std::min(lease, RemoteClasses::kMaxLease).count()));
    return grpc::Status::OK;
  } catch (const ClassConflict& e) {
    return {grpc::StatusCode::ALREADY_EXISTS, e.what()};
  } catch (const Error& e) {
    return {grpc::StatusCode::FAILED_PRECONDITION, e.what()};
  }
}

grpc::Status RegistryServiceImpl::Unregister(grpc::ServerContext*, const v1::UnregisterRequest* request,
                                             v1::UnregisterReply*) {
  if (!remote_.Unregister(request->address()))
    return {grpc::StatusCode::NOT_FOUND, "no component is registered at '" + request->address() + "'"};
  return grpc::Status::OK;
}

grpc::Status ComponentServiceImpl::Describe(grpc::ServerContext* context, const v1::DescribeRequest* request,
                                            v1::ComponentInfo* reply) {
  if (request->handle() != 0) {
    auto instance = instances_.Find(request->handle(), CallerOf(*context));
    if (!instance) return {grpc::StatusCode::NOT_FOUND, "no instance " + std::to_string(request->handle())};
    *reply = ToProto(instance->Describe());
    return grpc::Status::OK;
  }
  for (const auto& classes : {registry_.Classes(), remote_.Classes()})
    for (const ComponentInfo& info : classes)
      if (info.class_name == request->class_name()) {
        *reply = ToProto(info);
        return grpc::Status::OK;
      }
  return {grpc::StatusCode::NOT_FOUND, "unknown component class '" + request->class_name() + "'"};
}

grpc::Status FactoryServiceImpl::Create(grpc::ServerContext* context, const v1::CreateRequest* request,
                                        v1::CreateReply* reply) {
  if (!registry_.Has(request->class_name()))
    if (const auto address = remote_.AddressOf(request->class_name()))
      return CreateRemote(*context, *request, *address, reply);
  try {
    if (const auto info = registry_.Info(request->class_name()))
      CheckProperties(*info, request->properties(), "properties");
    auto instance = registry_.Create(request->class_name(), FromProto(request->properties()));
    *reply->mutable_info() = ToProto(instance->Describe());
    reply->set_handle(instances_.Add(std::move(instance), CallerOf(*context).user));
    return grpc::Status::OK;
  } catch (const LimitReached& e) {
    return {grpc::StatusCode::RESOURCE_EXHAUSTED, e.what()};
  } catch (const Error& e) {
    const bool unknown = !registry_.Has(request->class_name());
    return {unknown ? grpc::StatusCode::NOT_FOUND : grpc::StatusCode::INVALID_ARGUMENT, e.what()};
  }
}

grpc::Status FactoryServiceImpl::CreateRemote(grpc::ServerContext& context, const v1::CreateRequest& request,
                                              const std::string& address, v1::CreateReply* reply) {
  try {
    for (const ComponentInfo& info : remote_.Classes()) {
      if (info.class_name != request.class_name()) continue;
      std::unique_ptr<Component> instance = MakeRemoteInstance(info, address, request.properties(), remote_options_);
      *reply->mutable_info() = ToProto(instance->Describe());
      reply->set_handle(instances_.Add(std::move(instance), CallerOf(context).user));
      return grpc::Status::OK;
    }
    return {grpc::StatusCode::NOT_FOUND, "unknown component class '" + request.class_name() + "'"};
  } catch (const LimitReached& e) {
    return {grpc::StatusCode::RESOURCE_EXHAUSTED, e.what()};
  } catch (const Error& e) {
    return {grpc::StatusCode::FAILED_PRECONDITION, e.what()};
  }
}

grpc::Status FactoryServiceImpl::Release(grpc::ServerContext* context, const v1::ReleaseRequest* request,
                                         v1::ReleaseReply*) {
  if (!instances_.Release(request->handle(), CallerOf(*context)))
    return {grpc::StatusCode::NOT_FOUND, "no instance " + std::to_string(request->handle())};
  return grpc::Status::OK;
}

}  // namespace yarf
