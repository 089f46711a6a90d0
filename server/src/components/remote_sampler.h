// Remote<Sampler>: a point set served by another process. Generate is one
// call per batch; the lazy per-coordinate Sample fetches a point's first
// coordinates at once and keeps them per thread.
#pragma once

#include "components/remote_instance.h"
#include "yarf/math.h"
#include "yarf/v1/math.grpc.pb.h"

namespace yarf {

template <>
class Remote<Sampler> final : public Sampler {
 public:
  Remote(std::unique_ptr<RemoteInstance> instance);

  float Sample(uint64_t index, uint32_t dimension, uint64_t seed) const override;
  void Generate(uint64_t first, uint32_t count, uint32_t dimensions, uint64_t seed,
                std::span<float> out) const override;
  // Where the sampler lives: a Remote<Integrator> of the same process
  // names it by its handle there.
  const RemoteInstance& instance() const { return *instance_; }

 private:
  std::unique_ptr<RemoteInstance> instance_;
  std::unique_ptr<v1::Sampler::Stub> stub_;
};

}  // namespace yarf
