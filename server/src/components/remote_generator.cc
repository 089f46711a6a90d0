#include "components/remote_generator.h"

#include <limits>
#include <string>

namespace yarf {

Remote<Generator>::Remote(std::unique_ptr<RemoteInstance> instance)
    : instance_(std::move(instance)), stub_(v1::Generator::NewStub(instance_->channel())) {}

void Remote<Generator>::Next(uint64_t seed, uint64_t stream, uint64_t offset, std::span<float> out) {
  if (out.empty()) return;
  if (out.size() > std::numeric_limits<uint32_t>::max())
    throw Error(instance_->Name() + ": Generator.Next of " + std::to_string(out.size()) +
                " numbers in one call (at most 2^32 - 1)");
  v1::GeneratorRequest request;
  request.set_seed(seed);
  request.set_stream(stream);
  request.set_offset(offset);
  request.set_count(uint32_t(out.size()));
  v1::GeneratorReply reply;
  instance_->Call("Next", [&](grpc::ClientContext& context, uint64_t handle) {
    request.set_handle(handle);
    return stub_->Next(&context, request, &reply);
  });
  instance_->CopyFloats("Next", "values", reply.values(), out.size(), {}, out);
  for (size_t i = 0; i < out.size(); ++i)
    if (!(out[i] >= 0 && out[i] < 1))
      throw instance_->BadReply("Next", "a number outside [0, 1) (" + std::to_string(out[i]) + ") at output " +
                                            std::to_string(offset + i));
}

}  // namespace yarf
