// Remote<Medium>: a participating medium served by another process. The
// null-scattering trackers call it once per batch of walks: Majorants for
// every ray entering the medium, Coefficients at every round of tentative
// collisions, the phase calls at every round of real scattering. Emits is
// asked once, when the medium is made.
#pragma once

#include "components/remote_instance.h"
#include "yarf/medium.h"
#include "yarf/v1/medium.grpc.pb.h"

namespace yarf {

// Replies are checked: shapes, finite values, no negative coefficient,
// majorant, phase value or pdf; majorant segments within [0, tmax) of
// their ray, in increasing t, not overlapping; sampled directions of
// unit length.
template <>
class Remote<Medium> final : public Medium {
 public:
  explicit Remote(std::unique_ptr<RemoteInstance> instance);

  void Majorants(std::span<const float> origin, std::span<const float> direction, std::span<const float> tmax,
                 MajorantSegments& out) const override;
  void Coefficients(std::span<const float> position, std::span<float> sigma_a, std::span<float> sigma_s,
                    std::span<float> emission) const override;
  bool Emits() const override { return emits_; }
  void EvaluatePhase(std::span<const float> wi, std::span<const float> wo, std::span<const float> position,
                     std::span<float> value, std::span<float> pdf) const override;
  void SamplePhase(std::span<const float> wi, std::span<const float> position, std::span<const float> uniform,
                   std::span<float> wo, std::span<float> weight, std::span<float> pdf) const override;

 private:
  std::unique_ptr<RemoteInstance> instance_;
  std::unique_ptr<v1::Medium::Stub> stub_;
  // Fixed for an instance: asked once.
  bool emits_ = false;
};

}  // namespace yarf
