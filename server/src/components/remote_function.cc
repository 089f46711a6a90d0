#include "components/remote_function.h"

namespace yarf {

Remote<Function>::Remote(std::unique_ptr<RemoteInstance> instance)
    : instance_(std::move(instance)), stub_(v1::Function::NewStub(instance_->channel())) {
  v1::FunctionSignature signature;
  instance_->Call("Signature", [&](grpc::ClientContext& context, uint64_t handle) {
    v1::FunctionSignatureRequest request;
    request.set_handle(handle);
    return stub_->Signature(&context, request, &signature);
  });
  if (signature.input_dimensions() == 0 || signature.output_dimensions() == 0)
    throw instance_->BadReply("Signature", "no dimensions");
  input_dimensions_ = signature.input_dimensions();
  output_dimensions_ = signature.output_dimensions();
}

void Remote<Function>::Evaluate(std::span<const float> points, std::span<float> values) {
  const size_t n = points.size() / input_dimensions_;
  v1::EvaluateRequest request;
  request.set_sequence(++sequence_);
  SetFloats(request.mutable_points(), points, {uint32_t(n), input_dimensions_});
  v1::EvaluateReply reply;
  instance_->Call("Evaluate", [&](grpc::ClientContext& context, uint64_t handle) {
    request.set_handle(handle);
    return stub_->Evaluate(&context, request, &reply);
  });
  instance_->CopyFloats("Evaluate", "values", reply.values(), n, {output_dimensions_}, values);
}

}  // namespace yarf
