#include "components/remote_sampler.h"

#include <unordered_map>
#include <vector>

namespace yarf {
namespace {

// Coordinates fetched per point by the lazy Sample: a path's usual needs.
constexpr uint32_t kBlockDimensions = 64;
// Points kept per thread: a tile's worth, since transports read one
// coordinate of every path of a batch before the next.
constexpr size_t kCachedPoints = 1 << 14;

struct PointKey {
  const void* sampler;
  uint64_t index, seed;
  bool operator==(const PointKey&) const = default;
};
struct PointKeyHash {
  size_t operator()(const PointKey& k) const {
    return std::hash<uint64_t>()(k.index * 0x9E3779B97F4A7C15ull ^ k.seed) ^ std::hash<const void*>()(k.sampler);
  }
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
  thread_local std::unordered_map<PointKey, std::vector<float>, PointKeyHash> cache;
  const PointKey key{this, index, seed};
  auto it = cache.find(key);
  if (it == cache.end() || dimension >= it->second.size()) {
    if (cache.size() >= kCachedPoints) cache.clear();
    std::vector<float> values(std::max(kBlockDimensions, dimension + 1));
    Generate(index, 1, uint32_t(values.size()), seed, values);
    it = cache.insert_or_assign(key, std::move(values)).first;
  }
  return it->second[dimension];
}

}  // namespace yarf
