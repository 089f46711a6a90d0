// yarf.v1.Registry, Component and Factory: what the server can make, and
// instances made on request, by handle.
#pragma once

#include <map>
#include <memory>
#include <mutex>

#include "components/registry.h"
#include "yarf/v1/component.grpc.pb.h"

namespace yarf {

// Instances made through Factory.Create, by handle.
class InstanceTable {
 public:
  uint64_t Add(std::unique_ptr<Component> instance);
  bool Release(uint64_t handle);
  // nullptr when unknown; the instance lives while the pointer is held.
  std::shared_ptr<Component> Find(uint64_t handle) const;

 private:
  mutable std::mutex mutex_;
  uint64_t next_ = 1;
  std::map<uint64_t, std::shared_ptr<Component>> instances_;
};

class RegistryServiceImpl final : public v1::Registry::Service {
 public:
  explicit RegistryServiceImpl(Registry& registry) : registry_(registry) {}
  grpc::Status ListClasses(grpc::ServerContext*, const v1::ListClassesRequest*,
                           v1::ListClassesReply*) override;
  grpc::Status LoadPlugin(grpc::ServerContext*, const v1::LoadPluginRequest*,
                          v1::LoadPluginReply*) override;

 private:
  Registry& registry_;
};

class ComponentServiceImpl final : public v1::Component::Service {
 public:
  ComponentServiceImpl(const Registry& registry, const InstanceTable& instances)
      : registry_(registry), instances_(instances) {}
  grpc::Status Describe(grpc::ServerContext*, const v1::DescribeRequest*, v1::ComponentInfo*) override;

 private:
  const Registry& registry_;
  const InstanceTable& instances_;
};

class FactoryServiceImpl final : public v1::Factory::Service {
 public:
  FactoryServiceImpl(const Registry& registry, InstanceTable& instances)
      : registry_(registry), instances_(instances) {}
  grpc::Status Create(grpc::ServerContext*, const v1::CreateRequest*, v1::CreateReply*) override;
  grpc::Status Release(grpc::ServerContext*, const v1::ReleaseRequest*, v1::ReleaseReply*) override;

 private:
  const Registry& registry_;
  InstanceTable& instances_;
};

}  // namespace yarf
