// Remote<Generator>: a stream of pseudo-random numbers served by another
// process.
#pragma once

#include "components/remote_instance.h"
#include "yarf/math.h"
#include "yarf/v1/math.grpc.pb.h"

namespace yarf {

// Every Next is one call; its numbers are checked to be `count` floats in
// [0, 1).
template <>
class Remote<Generator> final : public Generator {
 public:
  Remote(std::unique_ptr<RemoteInstance> instance);

  void Next(uint64_t seed, uint64_t stream, uint64_t offset, std::span<float> out) override;

 private:
  std::unique_ptr<RemoteInstance> instance_;
  std::unique_ptr<v1::Generator::Stub> stub_;
};

}  // namespace yarf
