// yarf.v1.Registry, Component and Factory: what the server can make, and
// instances made on request, by handle.
#pragma once

#include <map>
#include <memory>
#include <mutex>

#include "components/remote_classes.h"
#include "yarf/v1/component.grpc.pb.h"

namespace yarf {

// Where a table of handles starts counting: a random number below 2^62,
// so that a restarted server never gives out a handle a caller may still
// hold from before (and handles stay exact in a double).
uint64_t FirstHandle();

// Instances made through Factory.Create, by handle.
class InstanceTable {
 public:
  InstanceTable();
  uint64_t Add(std::unique_ptr<Component> instance);
  bool Release(uint64_t handle);
  // nullptr when unknown; the instance lives while the pointer is held.
  std::shared_ptr<Component> Find(uint64_t handle) const;

 private:
  mutable std::mutex mutex_;
  // Starts at a random number: a restarted server never gives out a
  // handle a client may still hold from before.
  uint64_t next_;
  std::map<uint64_t, std::shared_ptr<Component>> instances_;
};

class RegistryServiceImpl final : public v1::Registry::Service {
 public:
  RegistryServiceImpl(Registry& registry, RemoteClasses& remote) : registry_(registry), remote_(remote) {}
  grpc::Status ListClasses(grpc::ServerContext*, const v1::ListClassesRequest*,
                           v1::ListClassesReply*) override;
  grpc::Status LoadPlugin(grpc::ServerContext*, const v1::LoadPluginRequest*,
                          v1::LoadPluginReply*) override;
  grpc::Status Register(grpc::ServerContext*, const v1::RegisterRequest*, v1::RegisterReply*) override;
  grpc::Status Unregister(grpc::ServerContext*, const v1::UnregisterRequest*, v1::UnregisterReply*) override;

 private:
  Registry& registry_;
  RemoteClasses& remote_;
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
  FactoryServiceImpl(const Registry& registry, const RemoteClasses& remote, InstanceTable& instances)
      : registry_(registry), remote_(remote), instances_(instances) {}
  grpc::Status Create(grpc::ServerContext*, const v1::CreateRequest*, v1::CreateReply*) override;
  grpc::Status Release(grpc::ServerContext*, const v1::ReleaseRequest*, v1::ReleaseReply*) override;

 private:
  const Registry& registry_;
  const RemoteClasses& remote_;
  InstanceTable& instances_;
};

}  // namespace yarf
