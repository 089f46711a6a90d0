// Remote<Integrator>: a numerical integrator served by another process,
// calling back the integrand (served by ServedFunction).
//
// It renders images through Integrate alone: the film in tiles of
// kTileSide × kTileSide pixels, row by row, each lent to the component as
// a TileIntegrand (the job's transport over the tile, one output per
// pixel and channel) and integrated once with samples per pixel × the
// tile's pixels evaluations, the seed hashed from the job's, the first
// sample and the tile. Each pixel's estimate and its standard error go to
// the film as they are (RenderTarget::AddPixelEstimates), so the film
// shows the integrator's estimate under any reconstruction filter; a
// progressive preview shows the tiles done. Transports that splat cannot
// be integrated pixel by pixel and are refused.
#pragma once

#include "components/remote_instance.h"
#include "yarf/math.h"
#include "yarf/v1/math.grpc.pb.h"

namespace yarf {

// The result is checked: one finite estimate and one finite, non-negative
// standard error per output of the integrand, evaluations within the
// budget, χ²/dof and Q (when given) one per output, Q in [0, 1].
template <>
class Remote<Integrator> final : public Integrator {
 public:
  Remote(std::unique_ptr<RemoteInstance> instance);

  // The sampler travels as a handle in the integrator's process: yarfd's
  // independent sampler as 0 (the component's own independent points for
  // the seed), a sampler made in the same process as its handle there;
  // others cannot be named (IntegrateRequest has no sampler address), an
  // Error says so.
  IntegrationResult Integrate(Function& f, std::span<const double> lower, std::span<const double> upper,
                              uint64_t evaluations, uint64_t seed, const Sampler& sampler) override;
  // Samples target.FirstSample() .. target.SamplesPerPixel() - 1 of the
  // target's crop window, as one pass (PassDone once, at the end); stops
  // between tiles when cancelled. The sampler as Integrate's. A failure
  // (the transport's, the component's, a wrong reply) throws Error naming
  // the component and the tile.
  void Render(Transport& transport, const SceneView& scene, const Sampler& sampler, RenderTarget& target) override;

  static constexpr uint32_t kTileSide = 16;

 private:
  uint64_t SamplerHandle(const Sampler& sampler) const;
  // One Integrate call of the function served at `function_address`, of
  // `outputs` outputs, its reply checked.
  IntegrationResult IntegrateServed(const std::string& function_address, size_t outputs,
                                    std::span<const double> lower, std::span<const double> upper,
                                    uint64_t evaluations, uint64_t seed, uint64_t sampler_handle);
  // `values` of the reply's `field`: one per output, each finite (NaN
  // allowed for χ²/dof and Q, which have none with one iteration).
  std::vector<double> Checked(const char* field, const google::protobuf::RepeatedField<double>& values,
                              size_t outputs, bool nan_allowed) const;

  std::unique_ptr<RemoteInstance> instance_;
  std::unique_ptr<v1::Integrator::Stub> stub_;
};

}  // namespace yarf
