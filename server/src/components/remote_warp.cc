#include "components/remote_warp.h"

#include <string>

namespace yarf {
namespace {

// Warps map a few uniform numbers to a point of a small space (a disk, a
// direction, a triangle); a signature beyond this is a broken reply.
constexpr uint32_t kMaxDimensions = 64;

}  // namespace

Remote<Warp>::Remote(std::unique_ptr<RemoteInstance> instance)
    : instance_(std::move(instance)), stub_(v1::Warp::NewStub(instance_->channel())) {
  v1::WarpSignature signature;
  instance_->Call("Signature", [&](grpc::ClientContext& context, uint64_t handle) {
    v1::WarpSignatureRequest request;
    request.set_handle(handle);
    return stub_->Signature(&context, request, &signature);
  });
  for (uint32_t dimensions : {signature.domain_dimensions(), signature.image_dimensions()})
    if (dimensions == 0 || dimensions > kMaxDimensions)
      throw instance_->BadReply("Signature", "dimensions " + std::to_string(signature.domain_dimensions()) +
                                                 " -> " + std::to_string(signature.image_dimensions()) +
                                                 " (expected 1 to " + std::to_string(kMaxDimensions) + " each)");
  domain_dimensions_ = signature.domain_dimensions();
  image_dimensions_ = signature.image_dimensions();
}

void Remote<Warp>::Call(const char* method, Rpc rpc, std::span<const float> in, uint32_t in_dims, std::span<float> out,
                        uint32_t out_dims, std::span<float> pdf) const {
  const uint32_t n = uint32_t(in.size() / in_dims);
  if (n == 0) return;
  v1::WarpRequest request;
  SetFloats(request.mutable_points(), in.first(size_t(n) * in_dims), {n, in_dims});
  v1::WarpReply reply;
  instance_->Call(method, [&](grpc::ClientContext& context, uint64_t handle) {
    request.set_handle(handle);
    return ((*stub_).*rpc)(&context, request, &reply);
  });
  if (out_dims > 0)
    instance_->CopyFloats(method, "points", reply.points(), n, {out_dims}, out.first(size_t(n) * out_dims));
  instance_->CopyFloats(method, "pdf", reply.pdf(), n, {}, pdf.first(n));
  instance_->RequireNonNegative(method, "pdf", pdf.first(n));
}

void Remote<Warp>::Forward(std::span<const float> uniform, std::span<float> points, std::span<float> pdf) const {
  Call("Forward", &v1::Warp::Stub::Forward, uniform, domain_dimensions_, points, image_dimensions_, pdf);
}

void Remote<Warp>::Inverse(std::span<const float> points, std::span<float> uniform, std::span<float> pdf) const {
  Call("Inverse", &v1::Warp::Stub::Inverse, points, image_dimensions_, uniform, domain_dimensions_, pdf);
  // The closed cube, not [0,1): the inverse of a point on the image's edge
  // may round to 1.
  const size_t n = (points.size() / image_dimensions_) * domain_dimensions_;
  for (size_t i = 0; i < n; ++i)
    if (!(uniform[i] >= 0 && uniform[i] <= 1))
      throw instance_->BadReply("Inverse", "a preimage coordinate outside [0, 1] (" + std::to_string(uniform[i]) +
                                               ") at point " + std::to_string(i / domain_dimensions_));
}

void Remote<Warp>::Pdf(std::span<const float> points, std::span<float> pdf) const {
  Call("Pdf", &v1::Warp::Stub::Pdf, points, image_dimensions_, {}, 0, pdf);
}

}  // namespace yarf
