// Remote<I>: a C++ interface implemented by calling a component that lives
// in another process (COM's containment). The kernel cannot tell it from
// an in-process plugin.
#pragma once

#include <grpcpp/grpcpp.h>

#include <chrono>
#include <memory>
#include <string>

#include "yarf/math.h"
#include "yarf/v1/math.grpc.pb.h"

namespace yarf {

template <typename I>
class Remote;

// A Function served at `address` (instance `handle` there). Every batch is
// one Evaluate call; replies are checked for shape and finiteness, and any
// failure is an Error naming the endpoint and the call.
template <>
class Remote<Function> final : public Function {
 public:
  Remote(const std::string& address, uint64_t handle,
         std::chrono::milliseconds deadline = std::chrono::seconds(60));

  uint32_t InputDimensions() const override { return input_dimensions_; }
  uint32_t OutputDimensions() const override { return output_dimensions_; }
  void Evaluate(std::span<const float> points, std::span<float> values) override;

 private:
  std::string Name() const;
  std::unique_ptr<grpc::ClientContext> Context() const;

  std::string address_;
  uint64_t handle_;
  std::chrono::milliseconds deadline_;
  std::unique_ptr<v1::Function::Stub> stub_;
  uint32_t input_dimensions_ = 0, output_dimensions_ = 0;
  uint64_t sequence_ = 0;
};

}  // namespace yarf
