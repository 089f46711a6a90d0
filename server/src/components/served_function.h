// A Function of this process lent to a component process for one call.
// IntegrateRequest and FindRootRequest name their integrand by the address
// of an endpoint serving it and a handle there (0: the endpoint's single
// function), so a Remote<Integrator> or Remote<RootFinder> serves yarfd's
// Function on an endpoint of its own while the component calls it back.
#pragma once

#include <grpcpp/grpcpp.h>

#include <filesystem>
#include <memory>
#include <string>

#include "yarf/math.h"

namespace yarf {

class ServedFunction {
 public:
  // Serves `function` as handle 0 where the component at
  // `component_address` can reach it: a socket in a private folder for a
  // unix: component, the loopback for one on this machine, else the local
  // address of the route to the component's host. Throws Error when it
  // cannot listen.
  ServedFunction(Function& function, const std::string& component_address);
  // Stops serving: a call still running is cancelled.
  ~ServedFunction();
  ServedFunction(const ServedFunction&) = delete;
  ServedFunction& operator=(const ServedFunction&) = delete;

  // Where the function is served ("unix:/...", "127.0.0.1:PORT").
  const std::string& address() const { return address_; }

 private:
  class Service;

  std::unique_ptr<Service> service_;
  std::filesystem::path folder_;
  std::unique_ptr<grpc::Server> server_;
  std::string address_;
};

}  // namespace yarf
