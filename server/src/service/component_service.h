// yarf.v1.Registry, Component and Factory: what the server can make, and
// instances made on request, by handle.
#pragma once

#include <chrono>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <vector>

#include "components/remote_classes.h"
#include "components/remote_instance.h"
#include "service/access.h"
#include "service/limits.h"
#include "yarf/v1/component.grpc.pb.h"

namespace yarf {

// A fresh random handle below 2^62 (exact in a double), never 0: a
// restarted server never gives out a handle a caller may still hold from
// before, and no caller can guess another's.
uint64_t RandomHandle();

// Instances made through Factory.Create, by handle, each bound to the user
// who made it: another user's handle is unknown to a caller, as if it did
// not exist (admins reach every instance).
class InstanceTable {
 public:
  // A user holds at most `max_per_user` instances (the server's own are not
  // counted); to make room, their instances unused for `idle` are released
  // (a client that died holding them would otherwise lock its user out).
  explicit InstanceTable(uint64_t max_per_user = 1000, std::chrono::seconds idle = std::chrono::hours(1))
      : max_per_user_(max_per_user), idle_(idle) {}
  // `owner` empty: the server's own (a running job's materials), for admins
  // only. Throws LimitReached when the owner holds the most they may.
  uint64_t Add(std::unique_ptr<Component> instance, const std::string& owner = "");
  bool Release(uint64_t handle, const Caller& caller);
  // nullptr when unknown or not the caller's; the instance lives while the
  // pointer is held.
  std::shared_ptr<Component> Find(uint64_t handle, const Caller& caller) const;
  // The server's own use (withdrawing a job's materials).
  void Release(uint64_t handle);

 private:
  struct Entry {
    std::shared_ptr<Component> instance;
    std::string owner;
    // Of the last Add or Find (which is const); guarded by mutex_.
    mutable std::chrono::steady_clock::time_point used;
  };
  void Erase(std::map<uint64_t, Entry>::iterator it);
  // Releases `owner`'s instances unused for idle_; under mutex_.
  void ReleaseIdle(const std::string& owner);

  const uint64_t max_per_user_;
  const std::chrono::seconds idle_;
  mutable std::mutex mutex_;
  std::map<uint64_t, Entry> instances_;
  std::map<std::string, uint64_t> per_owner_;
};


// Which plugins Registry.LoadPlugin may load: none unless `allowed`, and
// then only files directly inside one of `folders` (the --plugin-path
// folders, which the server's administrator controls).
struct PluginPolicy {
  bool allowed = false;
  std::vector<std::filesystem::path> folders;
};

class RegistryServiceImpl final : public v1::Registry::Service {
 public:
  RegistryServiceImpl(Registry& registry, RemoteClasses& remote, PluginPolicy plugins = {})
      : registry_(registry), remote_(remote), plugins_(std::move(plugins)) {}
  grpc::Status ListClasses(grpc::ServerContext*, const v1::ListClassesRequest*,
                           v1::ListClassesReply*) override;
  grpc::Status LoadPlugin(grpc::ServerContext*, const v1::LoadPluginRequest*,
                          v1::LoadPluginReply*) override;
  grpc::Status Register(grpc::ServerContext*, const v1::RegisterRequest*, v1::RegisterReply*) override;
  grpc::Status Unregister(grpc::ServerContext*, const v1::UnregisterRequest*, v1::UnregisterReply*) override;

 private:
  Registry& registry_;
  RemoteClasses& remote_;
  PluginPolicy plugins_;
};

class ComponentServiceImpl final : public v1::Component::Service {
 public:
  ComponentServiceImpl(const Registry& registry, const RemoteClasses& remote, const InstanceTable& instances)
      : registry_(registry), remote_(remote), instances_(instances) {}
  grpc::Status Describe(grpc::ServerContext*, const v1::DescribeRequest*, v1::ComponentInfo*) override;

 private:
  const Registry& registry_;
  const RemoteClasses& remote_;
  const InstanceTable& instances_;
};

class FactoryServiceImpl final : public v1::Factory::Service {
 public:
  // `remote_options`: the deadline of the calls made to the instances of
  // component processes' classes this factory makes.
  FactoryServiceImpl(const Registry& registry, const RemoteClasses& remote, InstanceTable& instances,
                     RemoteOptions remote_options = {})
      : registry_(registry), remote_(remote), instances_(instances), remote_options_(std::move(remote_options)) {}
  grpc::Status Create(grpc::ServerContext*, const v1::CreateRequest*, v1::CreateReply*) override;
  grpc::Status Release(grpc::ServerContext*, const v1::ReleaseRequest*, v1::ReleaseReply*) override;

 private:
  // A class of a component process: made there, called through Remote<I>.
  grpc::Status CreateRemote(grpc::ServerContext& context, const v1::CreateRequest& request,
                            const std::string& address, v1::CreateReply* reply);

  const Registry& registry_;
  const RemoteClasses& remote_;
  InstanceTable& instances_;
  const RemoteOptions remote_options_;
};

}  // namespace yarf
