#include "components/remote_integrator.h"

#include <cmath>
#include <string>

#include "components/remote_sampler.h"
#include "components/served_function.h"

namespace yarf {

Remote<Integrator>::Remote(std::unique_ptr<RemoteInstance> instance)
    : instance_(std::move(instance)), stub_(v1::Integrator::NewStub(instance_->channel())) {
  // Integrator::Render's message names the class.
  ComponentInfo info;
  info.class_name = instance_->class_name();
  info.interfaces = {kInterface};
  info.origin = "remote " + instance_->address();
  SetInfo(std::move(info));
}

uint64_t Remote<Integrator>::SamplerHandle(const Sampler& sampler) const {
  if (sampler.Describe().class_name == "independent") return 0;
  if (const auto* remote = dynamic_cast<const Remote<Sampler>*>(&sampler);
      remote && remote->instance().address() == instance_->address())
    return remote->instance().handle();
  const std::string name = sampler.Describe().class_name.empty() ? "this" : "'" + sampler.Describe().class_name + "'";
  throw Error(instance_->Name() + ": Integrator.Integrate cannot draw its points from sampler " + name +
              ": a request names a sampler only by its handle in the integrator's own process "
              "(use the independent sampler, or a sampler class of the integrator's process)");
}

std::vector<double> Remote<Integrator>::Checked(const char* field,
                                                const google::protobuf::RepeatedField<double>& values, size_t outputs,
                                                bool nan_allowed) const {
  if (size_t(values.size()) != outputs)
    throw instance_->BadReply("Integrate", std::to_string(values.size()) + " values of " + field + " for " +
                                               std::to_string(outputs) + " outputs of the integrand");
  for (int i = 0; i < values.size(); ++i)
    if (!std::isfinite(values[i]) && !(nan_allowed && std::isnan(values[i])))
      throw instance_->BadReply("Integrate", "a non-finite " + std::string(field) + " (" +
                                                 std::to_string(values[i]) + ") at output " + std::to_string(i));
  return {values.begin(), values.end()};
}

IntegrationResult Remote<Integrator>::Integrate(Function& f, std::span<const double> lower,
                                                std::span<const double> upper, uint64_t evaluations,
                                                uint64_t seed, const Sampler& sampler) {
  v1::IntegrateRequest request;
  request.set_sampler_handle(SamplerHandle(sampler));
  const ServedFunction served(f, instance_->address());
  request.set_function_address(served.address());
  request.set_function_handle(0);
  for (double l : lower) request.add_lower(l);
  for (double u : upper) request.add_upper(u);
  request.set_evaluations(evaluations);
  request.set_seed(seed);
  v1::IntegrateReply reply;
  instance_->Call("Integrate", [&](grpc::ClientContext& context, uint64_t handle) {
    request.set_handle(handle);
    return stub_->Integrate(&context, request, &reply);
  });
  const size_t k = f.OutputDimensions();
  IntegrationResult result;
  result.estimate = Checked("estimate", reply.estimate(), k, false);
  result.standard_error = Checked("standard_error", reply.standard_error(), k, false);
  for (size_t i = 0; i < k; ++i)
    if (result.standard_error[i] < 0)
      throw instance_->BadReply("Integrate", "a negative standard_error (" + std::to_string(result.standard_error[i]) +
                                                 ") at output " + std::to_string(i));
  if (reply.evaluations() > evaluations)
    throw instance_->BadReply("Integrate", std::to_string(reply.evaluations()) + " evaluations (the budget was " +
                                               std::to_string(evaluations) + ")");
  result.evaluations = reply.evaluations();
  // χ²/dof and Q: none for one-shot integrators, else one per output.
  if (!reply.chi2_per_dof().empty() || !reply.q().empty()) {
    result.chi2_per_dof = Checked("chi2_per_dof", reply.chi2_per_dof(), k, true);
    result.q = Checked("q", reply.q(), k, true);
    for (size_t i = 0; i < k; ++i)
      if (result.chi2_per_dof[i] < 0 || result.q[i] < 0 || result.q[i] > 1)
        throw instance_->BadReply("Integrate", "χ²/dof " + std::to_string(result.chi2_per_dof[i]) + " and Q " +
                                                   std::to_string(result.q[i]) + " at output " + std::to_string(i) +
                                                   " (expected χ²/dof ≥ 0, Q in [0, 1])");
  }
  return result;
}

}  // namespace yarf
