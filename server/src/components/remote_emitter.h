// Remote<Emitter>: a light's emission served by another process. The
// transports ask it once per emitter per bounce (emission seen, light
// samples) and once per batch of light paths.
#pragma once

#include "components/remote_instance.h"
#include "yarf/surface.h"
#include "yarf/v1/surface.grpc.pb.h"

namespace yarf {

// Replies are checked: shapes, finite values, no negative radiance or pdf.
template <>
class Remote<Emitter> final : public Emitter {
 public:
  explicit Remote(std::unique_ptr<RemoteInstance> instance);

  void Radiance(std::span<const float> w, const SurfacePoints& at, std::span<float> radiance) const override;
  void SampleDirection(std::span<const float> uniform, std::span<float> w, std::span<float> pdf) const override;
  void PdfDirection(std::span<const float> w, std::span<float> pdf) const override;

 private:
  std::unique_ptr<RemoteInstance> instance_;
  std::unique_ptr<v1::Emitter::Stub> stub_;
};

}  // namespace yarf
