#include "components/remote.h"

#include <cmath>
#include <cstring>

#include "yarf/error.h"

namespace yarf {
namespace {

constexpr int kMaxMessageBytes = 256 << 20;

std::shared_ptr<grpc::Channel> Connect(const std::string& address) {
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(kMaxMessageBytes);
  args.SetMaxSendMessageSize(kMaxMessageBytes);
  return grpc::CreateCustomChannel(address, grpc::InsecureChannelCredentials(), args);
}

}  // namespace

Remote<Function>::Remote(const std::string& address, uint64_t handle, std::chrono::milliseconds deadline)
    : address_(address), handle_(handle), deadline_(deadline), stub_(v1::Function::NewStub(Connect(address))) {
  v1::FunctionSignatureRequest request;
  request.set_handle(handle_);
  v1::FunctionSignature signature;
  const grpc::Status status = stub_->Signature(Context().get(), request, &signature);
  if (!status.ok()) throw Error(Name() + ": Signature failed: " + status.error_message());
  if (signature.input_dimensions() == 0 || signature.output_dimensions() == 0)
    throw Error(Name() + ": Signature gives no dimensions");
  input_dimensions_ = signature.input_dimensions();
  output_dimensions_ = signature.output_dimensions();
}

std::string Remote<Function>::Name() const {
  return "remote function " + std::to_string(handle_) + " at " + address_;
}

std::unique_ptr<grpc::ClientContext> Remote<Function>::Context() const {
  auto context = std::make_unique<grpc::ClientContext>();
  context->set_deadline(std::chrono::system_clock::now() + deadline_);
  return context;
}

void Remote<Function>::Evaluate(std::span<const float> points, std::span<float> values) {
  const size_t n = points.size() / input_dimensions_;
  v1::EvaluateRequest request;
  request.set_handle(handle_);
  request.set_sequence(++sequence_);
  v1::Array* array = request.mutable_points();
  array->set_dtype(v1::Array::FLOAT32);
  array->add_shape(uint32_t(n));
  array->add_shape(input_dimensions_);
  array->set_data(reinterpret_cast<const char*>(points.data()), points.size_bytes());
  v1::EvaluateReply reply;
  const grpc::Status status = stub_->Evaluate(Context().get(), request, &reply);
  if (!status.ok()) throw Error(Name() + ": Evaluate failed: " + status.error_message());
  const v1::Array& out = reply.values();
  if (out.dtype() != v1::Array::FLOAT32 || out.shape_size() != 2 || out.shape(0) != n ||
      out.shape(1) != output_dimensions_ || out.data().size() != values.size_bytes())
    throw Error(Name() + ": Evaluate returned " + std::to_string(out.data().size() / 4) + " values for " +
                std::to_string(n) + " points of " + std::to_string(output_dimensions_) + " outputs");
  std::memcpy(values.data(), out.data().data(), values.size_bytes());
  for (float v : values)
    if (!std::isfinite(v)) throw Error(Name() + ": Evaluate returned a non-finite value");
}

}  // namespace yarf
