// Remote<SurfaceModel>: a BSDF served by another process. The wavefront
// transports call it once per material per bounce, so a batch is a whole
// tile's worth of paths.
#pragma once

#include "components/remote_instance.h"
#include "yarf/surface.h"
#include "yarf/v1/surface.grpc.pb.h"

namespace yarf {

// Replies are checked: shapes, finite values, no negative value or pdf.
template <>
class Remote<SurfaceModel> final : public SurfaceModel {
 public:
  Remote(std::unique_ptr<RemoteInstance> instance);

  void Evaluate(TransportMode mode, std::span<const float> wi, std::span<const float> wo,
                const SurfacePoints& at, std::span<float> value) const override;
  void Sample(TransportMode mode, std::span<const float> wi, const SurfacePoints& at,
              std::span<const float> uniform, uint32_t allowed, std::span<float> wo, std::span<float> weight,
              std::span<float> pdf, std::span<uint32_t> flags) const override;
  void Pdf(std::span<const float> wi, std::span<const float> wo, const SurfacePoints& at,
           std::span<float> pdf) const override;
  uint32_t Lobes() const override { return lobes_; }

 private:
  std::unique_ptr<RemoteInstance> instance_;
  std::unique_ptr<v1::SurfaceModel::Stub> stub_;
  // Fixed for an instance: asked once.
  uint32_t lobes_ = 0;
};

}  // namespace yarf
