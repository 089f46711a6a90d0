// Remote<Function>: an integrand served by another process.
#pragma once

#include "components/remote_instance.h"
#include "yarf/math.h"
#include "yarf/v1/math.grpc.pb.h"

namespace yarf {

// Every batch is one Evaluate call; replies are checked for shape and
// finiteness.
template <>
class Remote<Function> final : public Function {
 public:
  Remote(std::unique_ptr<RemoteInstance> instance);

  uint32_t InputDimensions() const override { return input_dimensions_; }
  uint32_t OutputDimensions() const override { return output_dimensions_; }
  void Evaluate(std::span<const float> points, std::span<float> values) override;

 private:
  std::unique_ptr<RemoteInstance> instance_;
  std::unique_ptr<v1::Function::Stub> stub_;
  uint32_t input_dimensions_ = 0, output_dimensions_ = 0;
  uint64_t sequence_ = 0;
};

}  // namespace yarf
