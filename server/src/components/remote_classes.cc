#include "components/remote_classes.h"

#include "components/parameter_checks.h"
#include "components/properties_proto.h"
#include "components/remote_instance.h"
#include "yarf/v1/component.grpc.pb.h"

namespace yarf {

std::vector<ComponentInfo> RemoteClasses::Register(const std::string& address, std::chrono::seconds lease) {
  if (address.empty()) throw Error("register: the component's address is empty");
  v1::ListClassesReply reply;
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(5));
  const grpc::Status status =
      v1::Registry::NewStub(ComponentChannel(address))->ListClasses(&context, v1::ListClassesRequest{}, &reply);
  if (!status.ok())
    throw Error("the component at " + address + " did not answer Registry.ListClasses: " + status.error_message());
  std::vector<ComponentInfo> classes;
  for (const v1::ComponentInfo& c : reply.classes()) {
    if (c.class_name().empty()) throw Error("the component at " + address + " lists a class without a name");
    for (const std::string& id : c.interfaces())
      if (!SpeaksOurIdl(id))
        throw Error("class '" + c.class_name() + "' at " + address + " serves " + id +
                    ", an interface of another IDL version (this server speaks yarf.v1.*)");
    ComponentInfo info;
    try {
      info = FromProto(c, "remote " + address);
      CheckSchema(info);
    } catch (const Error& e) {
      throw Error("the component at " + address + " describes its classes in a way yarf cannot check: " +
                  e.what());
    }
    classes.push_back(std::move(info));
  }
  if (classes.empty()) throw Error("the component at " + address + " lists no classes");

  std::lock_guard lock(mutex_);
  DropExpired();
  for (const ComponentInfo& info : classes) {
    if (local_.Has(info.class_name))
      throw ClassConflict("class '" + info.class_name + "' is already a class of this server");
    for (const auto& [other, endpoint] : endpoints_)
      if (other != address)
        for (const ComponentInfo& taken : endpoint.classes)
          if (taken.class_name == info.class_name)
            throw ClassConflict("class '" + info.class_name + "' is already served by " + other);
  }
  Endpoint& endpoint = endpoints_[address];
  endpoint.classes = classes;
  if (lease.count() > 0)
    endpoint.expires = Clock::now() + std::min(lease, kMaxLease);
  else
    endpoint.expires.reset();
  return classes;
}

bool RemoteClasses::Unregister(const std::string& address) {
  std::lock_guard lock(mutex_);
  DropExpired();
  return endpoints_.erase(address) > 0;
}

std::optional<std::string> RemoteClasses::AddressOf(const std::string& class_name) const {
  std::lock_guard lock(mutex_);
  DropExpired();
  for (const auto& [address, endpoint] : endpoints_)
    for (const ComponentInfo& info : endpoint.classes)
      if (info.class_name == class_name) return address;
  return std::nullopt;
}

std::vector<ComponentInfo> RemoteClasses::Classes() const {
  std::lock_guard lock(mutex_);
  DropExpired();
  std::vector<ComponentInfo> all;
  for (const auto& [address, endpoint] : endpoints_)
    all.insert(all.end(), endpoint.classes.begin(), endpoint.classes.end());
  return all;
}

void RemoteClasses::DropExpired() const {
  const Clock::time_point now = Clock::now();
  std::erase_if(endpoints_, [&](const auto& entry) { return entry.second.expires && *entry.second.expires < now; });
}

}  // namespace yarf
