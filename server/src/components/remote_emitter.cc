#include "components/remote_emitter.h"

namespace yarf {

Remote<Emitter>::Remote(std::unique_ptr<RemoteInstance> instance)
    : instance_(std::move(instance)), stub_(v1::Emitter::NewStub(instance_->channel())) {}

void Remote<Emitter>::Radiance(std::span<const float> w, const SurfacePoints& at, std::span<float> radiance) const {
  const uint32_t n = uint32_t(w.size() / 3);
  if (n == 0) return;
  v1::RadianceRequest request;
  SetFloats(request.mutable_w(), w.first(3 * n), {n, 3});
  SetFloats(request.mutable_uv(), at.uv.first(2 * n), {n, 2});
  v1::RadianceReply reply;
  instance_->Call("Radiance", [&](grpc::ClientContext& context, uint64_t handle) {
    request.set_handle(handle);
    return stub_->Radiance(&context, request, &reply);
  });
  instance_->CopyFloats("Radiance", "radiance", reply.radiance(), n, {3}, radiance.first(3 * n));
  instance_->RequireNonNegative("Radiance", "radiance", radiance.first(3 * n));
}

void Remote<Emitter>::SampleDirection(std::span<const float> uniform, std::span<float> w,
                                      std::span<float> pdf) const {
  const uint32_t n = uint32_t(uniform.size() / 2);
  if (n == 0) return;
  v1::SampleDirectionRequest request;
  SetFloats(request.mutable_uniform(), uniform.first(2 * n), {n, 2});
  v1::SampleDirectionReply reply;
  instance_->Call("SampleDirection", [&](grpc::ClientContext& context, uint64_t handle) {
    request.set_handle(handle);
    return stub_->SampleDirection(&context, request, &reply);
  });
  instance_->CopyFloats("SampleDirection", "w", reply.w(), n, {3}, w.first(3 * n));
  instance_->CopyFloats("SampleDirection", "pdf", reply.pdf(), n, {}, pdf.first(n));
  instance_->RequireNonNegative("SampleDirection", "pdf", pdf.first(n));
}

void Remote<Emitter>::PdfDirection(std::span<const float> w, std::span<float> pdf) const {
  const uint32_t n = uint32_t(w.size() / 3);
  if (n == 0) return;
  v1::PdfDirectionRequest request;
  SetFloats(request.mutable_w(), w.first(3 * n), {n, 3});
  v1::PdfDirectionReply reply;
  instance_->Call("PdfDirection", [&](grpc::ClientContext& context, uint64_t handle) {
    request.set_handle(handle);
    return stub_->PdfDirection(&context, request, &reply);
  });
  instance_->CopyFloats("PdfDirection", "pdf", reply.pdf(), n, {}, pdf.first(n));
  instance_->RequireNonNegative("PdfDirection", "pdf", pdf.first(n));
}

}  // namespace yarf
