#include "components/remote_medium.h"

#include <cmath>
#include <cstring>
#include <string>

namespace yarf {
namespace {

// The fields of one MajorantsReply.segments row: t0, t1, σ_maj r, g, b.
constexpr uint32_t kSegmentFields = 5;

std::string Number(float value) { return std::to_string(value); }

}  // namespace

Remote<Medium>::Remote(std::unique_ptr<RemoteInstance> instance)
    : instance_(std::move(instance)), stub_(v1::Medium::NewStub(instance_->channel())) {
  v1::EmitsReply reply;
  instance_->Call("Emits", [&](grpc::ClientContext& context, uint64_t handle) {
    v1::EmitsRequest request;
    request.set_handle(handle);
    return stub_->Emits(&context, request, &reply);
  });
  emits_ = reply.emits();
}

void Remote<Medium>::Majorants(std::span<const float> origin, std::span<const float> direction,
                               std::span<const float> tmax, MajorantSegments& out) const {
  out.Clear();
  const uint32_t n = uint32_t(tmax.size());
  if (n == 0) return;
  v1::MajorantsRequest request;
  SetFloats(request.mutable_origin(), origin.first(3 * size_t(n)), {n, 3});
  SetFloats(request.mutable_direction(), direction.first(3 * size_t(n)), {n, 3});
  SetFloats(request.mutable_tmax(), tmax, {n});
  v1::MajorantsReply reply;
  instance_->Call("Majorants", [&](grpc::ClientContext& context, uint64_t handle) {
    request.set_handle(handle);
    return stub_->Majorants(&context, request, &reply);
  });

  // The number of segments M is the component's to choose: read it from
  // the shape, then check the bytes carry exactly [M, 5] values.
  const v1::Array& segments = reply.segments();
  if (segments.dtype() != v1::Array::FLOAT32 || segments.shape_size() != 2 ||
      segments.shape(1) != kSegmentFields ||
      uint64_t(segments.shape(0)) * kSegmentFields * sizeof(float) != segments.data().size()) {
    std::string shape = "[";
    for (int i = 0; i < segments.shape_size(); ++i) shape += (i ? ", " : "") + std::to_string(segments.shape(i));
    throw instance_->BadReply("Majorants", "segments of shape " + shape + "] and " +
                                               std::to_string(segments.data().size() / 4) +
                                               " values (expected FLOAT32 [M, 5])");
  }
  const size_t m = segments.shape(0);
  std::vector<float> rows(kSegmentFields * m);
  std::memcpy(rows.data(), segments.data().data(), segments.data().size());
  out.offsets.resize(size_t(n) + 1);
  instance_->CopyUints("Majorants", "offsets", reply.offsets(), size_t(n) + 1, out.offsets);
  if (out.offsets[0] != 0 || out.offsets[n] != m)
    throw instance_->BadReply("Majorants", "offsets from " + std::to_string(out.offsets[0]) + " to " +
                                               std::to_string(out.offsets[n]) + " for " + std::to_string(m) +
                                               " segments (expected 0 to " + std::to_string(m) + ")");

  out.segments.resize(m);
  for (uint32_t ray = 0; ray < n; ++ray) {
    const uint32_t begin = out.offsets[ray], end = out.offsets[ray + 1];
    if (end < begin || end > m)
      throw instance_->BadReply("Majorants", "offsets that decrease or pass the segments at ray " + std::to_string(ray));
    float previous_end = 0;
    for (uint32_t k = begin; k < end; ++k) {
      const float* row = &rows[kSegmentFields * k];
      const MajorantSegment segment{row[0], row[1], Vec3(row[2], row[3], row[4])};
      const std::string where = " in segment " + std::to_string(k) + " of ray " + std::to_string(ray);
      // t1 may be infinite, along a ray that never leaves the medium;
      // everything else must be a finite number.
      if (!std::isfinite(segment.t0) || std::isnan(segment.t1))
        throw instance_->BadReply("Majorants", "t0 " + Number(segment.t0) + ", t1 " + Number(segment.t1) + where);
      if (!(segment.t0 >= previous_end && segment.t1 >= segment.t0 && segment.t1 <= tmax[ray]))
        throw instance_->BadReply("Majorants", "the interval [" + Number(segment.t0) + ", " + Number(segment.t1) +
                                                   ")" + where + " (expected in increasing t, not overlapping, "
                                                   "within [0, " + Number(tmax[ray]) + "))");
      for (int c = 0; c < 3; ++c) {
        const float sigma = segment.sigma_maj[c];
        if (!std::isfinite(sigma)) throw instance_->BadReply("Majorants", "a non-finite majorant (" + Number(sigma) + ")" + where);
        if (sigma < 0) throw instance_->BadReply("Majorants", "a negative majorant (" + Number(sigma) + ")" + where);
      }
      out.segments[k] = segment;
      previous_end = segment.t1;
    }
  }
}

void Remote<Medium>::Coefficients(std::span<const float> position, std::span<float> sigma_a, std::span<float> sigma_s,
                                  std::span<float> emission) const {
  const uint32_t n = uint32_t(position.size() / 3);
  if (n == 0) return;
  v1::CoefficientsRequest request;
  SetFloats(request.mutable_position(), position.first(3 * size_t(n)), {n, 3});
  v1::CoefficientsReply reply;
  instance_->Call("Coefficients", [&](grpc::ClientContext& context, uint64_t handle) {
    request.set_handle(handle);
    return stub_->Coefficients(&context, request, &reply);
  });
  instance_->CopyFloats("Coefficients", "sigma_a", reply.sigma_a(), n, {3}, sigma_a.first(3 * size_t(n)));
  instance_->CopyFloats("Coefficients", "sigma_s", reply.sigma_s(), n, {3}, sigma_s.first(3 * size_t(n)));
  instance_->CopyFloats("Coefficients", "emission", reply.emission(), n, {3}, emission.first(3 * size_t(n)));
  instance_->RequireNonNegative("Coefficients", "sigma_a", sigma_a.first(3 * size_t(n)));
  instance_->RequireNonNegative("Coefficients", "sigma_s", sigma_s.first(3 * size_t(n)));
  instance_->RequireNonNegative("Coefficients", "emission", emission.first(3 * size_t(n)));
}

void Remote<Medium>::EvaluatePhase(std::span<const float> wi, std::span<const float> wo,
                                   std::span<const float> position, std::span<float> value,
                                   std::span<float> pdf) const {
  const uint32_t n = uint32_t(wi.size() / 3);
  if (n == 0) return;
  v1::PhaseQuery request;
  SetFloats(request.mutable_wi(), wi.first(3 * size_t(n)), {n, 3});
  SetFloats(request.mutable_wo(), wo.first(3 * size_t(n)), {n, 3});
  SetFloats(request.mutable_position(), position.first(3 * size_t(n)), {n, 3});
  v1::EvaluatePhaseReply reply;
  instance_->Call("EvaluatePhase", [&](grpc::ClientContext& context, uint64_t handle) {
    request.set_handle(handle);
    return stub_->EvaluatePhase(&context, request, &reply);
  });
  instance_->CopyFloats("EvaluatePhase", "value", reply.value(), n, {}, value.first(n));
  instance_->CopyFloats("EvaluatePhase", "pdf", reply.pdf(), n, {}, pdf.first(n));
  instance_->RequireNonNegative("EvaluatePhase", "value", value.first(n));
  instance_->RequireNonNegative("EvaluatePhase", "pdf", pdf.first(n));
}

void Remote<Medium>::SamplePhase(std::span<const float> wi, std::span<const float> position,
                                 std::span<const float> uniform, std::span<float> wo, std::span<float> weight,
                                 std::span<float> pdf) const {
  const uint32_t n = uint32_t(wi.size() / 3);
  if (n == 0) return;
  v1::SamplePhaseRequest request;
  SetFloats(request.mutable_wi(), wi.first(3 * size_t(n)), {n, 3});
  SetFloats(request.mutable_position(), position.first(3 * size_t(n)), {n, 3});
  SetFloats(request.mutable_uniform(), uniform.first(2 * size_t(n)), {n, 2});
  v1::SamplePhaseReply reply;
  instance_->Call("SamplePhase", [&](grpc::ClientContext& context, uint64_t handle) {
    request.set_handle(handle);
    return stub_->SamplePhase(&context, request, &reply);
  });
  instance_->CopyFloats("SamplePhase", "wo", reply.wo(), n, {3}, wo.first(3 * size_t(n)));
  instance_->CopyFloats("SamplePhase", "weight", reply.weight(), n, {}, weight.first(n));
  instance_->CopyFloats("SamplePhase", "pdf", reply.pdf(), n, {}, pdf.first(n));
  instance_->RequireNonNegative("SamplePhase", "weight", weight.first(n));
  instance_->RequireNonNegative("SamplePhase", "pdf", pdf.first(n));
  // A drawn direction continues the path: it must be a direction.
  for (uint32_t i = 0; i < n; ++i) {
    if (!(pdf[i] > 0 && weight[i] > 0)) continue;
    const float length2 = wo[3 * i] * wo[3 * i] + wo[3 * i + 1] * wo[3 * i + 1] + wo[3 * i + 2] * wo[3 * i + 2];
    if (!(std::abs(length2 - 1) < 1e-3f))
      throw instance_->BadReply("SamplePhase", "a wo of length " + Number(std::sqrt(length2)) + " at query " +
                                                   std::to_string(i) + " (unit directions expected)");
  }
}

}  // namespace yarf
