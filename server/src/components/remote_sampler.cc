#include "components/remote_sampler.h"

#include <vector>

namespace yarf {
namespace {

// Coordinates fetched per point by the lazy Sample: a path's usual needs.
constexpr uint32_t kBlockDimensions = 64;

struct CachedPoint {
  const void* sampler = nullptr;
  uint64_t index = 0, seed = 0;
  uint32_t dimensions = 0;
  std::vector<float> values;
};

}  // namespace

Remote<Sampler>::Remote(std::unique_ptr<RemoteInstance> instance)
    : instance_(std::move(instance)), stub_(v1::Sampler::NewStub(instance_->channel())) {}

void Remote<Sampler>::Generate(uint64_t first, uint32_t count, uint32_t dimensions, uint64_t seed,
                               std::span<float> out) const {
  if (count == 0 || dimensions == 0) return;
  v1::GenerateSamplesRequest request;
  request.set_first_index(first);
  request.set_count(count);
  request.set_dimensions(dimensions);
  request.set_seed(seed);
  v1::GenerateSamplesReply reply;
  instance_->Call("Generate", [&](grpc::ClientContext& context, uint64_t handle) {
    request.set_handle(handle);
    return stub_->Generate(&context, request, &reply);
  });
  std::span<float> values = out.first(size_t(count) * dimensions);
  instance_->CopyFloats("Generate", "points", reply.points(), count, {dimensions}, values);
  for (size_t i = 0; i < values.size(); ++i)
    if (!(values[i] >= 0 && values[i] < 1))
      throw instance_->BadReply("Generate", "a coordinate outside [0, 1) (" + std::to_string(values[i]) +
                                                ") at point " + std::to_string(first + i / dimensions));
}

float Remote<Sampler>::Sample(uint64_t index, uint32_t dimension, uint64_t seed) const {
  thread_local CachedPoint cached;
  if (cached.sampler != this || cached.index != index || cached.seed != seed || dimension >= cached.dimensions) {
    const uint32_t dimensions = std::max(kBlockDimensions, dimension + 1);
    cached.values.resize(dimensions);
    Generate(index, 1, dimensions, seed, cached.values);
    cached = {this, index, seed, dimensions, std::move(cached.values)};
  }
  return cached.values[dimension];
}

}  // namespace yarf
