#include "components/remote_surface_model.h"

namespace yarf {
namespace {

constexpr uint32_t kKnownFlags =
    kScatterReflect | kScatterRefract | kScatterDelta | kScatterDiffuse | kScatterGlossy;

// Evaluate and Pdf ask about the same N direction pairs.
v1::SurfaceQuery QueryOf(std::span<const float> wi, std::span<const float> wo, std::span<const float> uv,
                         uint32_t n) {
  v1::SurfaceQuery query;
  SetFloats(query.mutable_wi(), wi.first(3 * n), {n, 3});
  SetFloats(query.mutable_wo(), wo.first(3 * n), {n, 3});
  SetFloats(query.mutable_uv(), uv.first(2 * n), {n, 2});
  return query;
}

v1::TransportMode ToProto(TransportMode mode) {
  return mode == TransportMode::kImportance ? v1::IMPORTANCE : v1::RADIANCE;
}

}  // namespace

Remote<SurfaceModel>::Remote(std::unique_ptr<RemoteInstance> instance)
    : instance_(std::move(instance)), stub_(v1::SurfaceModel::NewStub(instance_->channel())) {
  v1::LobesReply reply;
  instance_->Call("Lobes", [&](grpc::ClientContext& context, uint64_t handle) {
    v1::LobesRequest request;
    request.set_handle(handle);
    return stub_->Lobes(&context, request, &reply);
  });
  if (reply.flags() & ~kKnownFlags) throw instance_->BadReply("Lobes", "unknown flags " + std::to_string(reply.flags()));
  lobes_ = reply.flags();
}

void Remote<SurfaceModel>::Evaluate(TransportMode mode, std::span<const float> wi, std::span<const float> wo,
                                    const SurfacePoints& at, std::span<float> value) const {
  const uint32_t n = uint32_t(wi.size() / 3);
  if (n == 0) return;
  v1::SurfaceQuery request = QueryOf(wi, wo, at.uv, n);
  request.set_mode(ToProto(mode));
  v1::EvaluateSurfaceReply reply;
  instance_->Call("Evaluate", [&](grpc::ClientContext& context, uint64_t handle) {
    request.set_handle(handle);
    return stub_->Evaluate(&context, request, &reply);
  });
  instance_->CopyFloats("Evaluate", "value", reply.value(), n, {3}, value.first(3 * n));
  instance_->RequireNonNegative("Evaluate", "value", value.first(3 * n));
}

void Remote<SurfaceModel>::Sample(TransportMode mode, std::span<const float> wi, const SurfacePoints& at,
                                  std::span<const float> uniform, uint32_t allowed, std::span<float> wo,
                                  std::span<float> weight, std::span<float> pdf,
                                  std::span<uint32_t> flags) const {
  const uint32_t n = uint32_t(wi.size() / 3);
  if (n == 0) return;
  v1::SampleSurfaceRequest request;
  SetFloats(request.mutable_wi(), wi, {n, 3});
  SetFloats(request.mutable_uv(), at.uv.first(2 * n), {n, 2});
  SetFloats(request.mutable_uniform(), uniform.first(3 * n), {n, 3});
  request.set_allowed(allowed);
  request.set_mode(ToProto(mode));
  v1::SampleSurfaceReply reply;
  instance_->Call("Sample", [&](grpc::ClientContext& context, uint64_t handle) {
    request.set_handle(handle);
    return stub_->Sample(&context, request, &reply);
  });
  instance_->CopyFloats("Sample", "wo", reply.wo(), n, {3}, wo.first(3 * n));
  instance_->CopyFloats("Sample", "weight", reply.weight(), n, {3}, weight.first(3 * n));
  instance_->CopyFloats("Sample", "pdf", reply.pdf(), n, {}, pdf.first(n));
  instance_->CopyUints("Sample", "flags", reply.flags(), n, flags.first(n));
  instance_->RequireNonNegative("Sample", "weight", weight.first(3 * n));
  instance_->RequireNonNegative("Sample", "pdf", pdf.first(n));
  for (uint32_t i = 0; i < n; ++i)
    if (flags[i] & ~kKnownFlags)
      throw instance_->BadReply("Sample", "unknown flags " + std::to_string(flags[i]) + " at query " + std::to_string(i));
}

void Remote<SurfaceModel>::Pdf(std::span<const float> wi, std::span<const float> wo, const SurfacePoints& at,
                               std::span<float> pdf) const {
  const uint32_t n = uint32_t(wi.size() / 3);
  if (n == 0) return;
  v1::SurfaceQuery request = QueryOf(wi, wo, at.uv, n);
  v1::PdfSurfaceReply reply;
  instance_->Call("Pdf", [&](grpc::ClientContext& context, uint64_t handle) {
    request.set_handle(handle);
    return stub_->Pdf(&context, request, &reply);
  });
  instance_->CopyFloats("Pdf", "pdf", reply.pdf(), n, {}, pdf.first(n));
  instance_->RequireNonNegative("Pdf", "pdf", pdf.first(n));
}

}  // namespace yarf
