// Remote<Integrator>: a numerical integrator served by another process,
// calling back the integrand (served by ServedFunction). It integrates
// functions; it does not render images (Integrator::Render's default).
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

 private:
  uint64_t SamplerHandle(const Sampler& sampler) const;
  // `values` of the reply's `field`: one per output, each finite (NaN
  // allowed for χ²/dof and Q, which have none with one iteration).
  std::vector<double> Checked(const char* field, const google::protobuf::RepeatedField<double>& values,
                              size_t outputs, bool nan_allowed) const;

  std::unique_ptr<RemoteInstance> instance_;
  std::unique_ptr<v1::Integrator::Stub> stub_;
};

}  // namespace yarf
