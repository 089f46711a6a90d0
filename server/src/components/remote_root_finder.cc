#include "components/remote_root_finder.h"

#include <cmath>
#include <string>

#include "components/served_function.h"

namespace yarf {

Remote<RootFinder>::Remote(std::unique_ptr<RemoteInstance> instance)
    : instance_(std::move(instance)), stub_(v1::RootFinder::NewStub(instance_->channel())) {}

RootResult Remote<RootFinder>::FindRoot(Function& f, double lower, double upper, double tolerance,
                                        uint32_t max_iterations) {
  const ServedFunction served(f, instance_->address());
  v1::FindRootRequest request;
  request.set_function_address(served.address());
  request.set_function_handle(0);
  request.set_lower(lower);
  request.set_upper(upper);
  request.set_tolerance(tolerance);
  request.set_max_iterations(max_iterations);
  v1::FindRootReply reply;
  instance_->Call("FindRoot", [&](grpc::ClientContext& context, uint64_t handle) {
    request.set_handle(handle);
    return stub_->FindRoot(&context, request, &reply);
  });
  if (!std::isfinite(reply.root()) || reply.root() < lower || reply.root() > upper)
    throw instance_->BadReply("FindRoot", "a root (" + std::to_string(reply.root()) + ") outside the bracket [" +
                                              std::to_string(lower) + ", " + std::to_string(upper) + "]");
  if (reply.iterations() > max_iterations)
    throw instance_->BadReply("FindRoot", std::to_string(reply.iterations()) + " iterations (at most " +
                                              std::to_string(max_iterations) + " were allowed)");
  return {.root = reply.root(), .iterations = reply.iterations()};
}

}  // namespace yarf
