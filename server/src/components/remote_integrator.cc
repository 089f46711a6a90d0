#include "components/remote_integrator.h"

#include <cmath>
#include <string>

#include "components/remote_sampler.h"
#include "components/served_function.h"
#include "components/tile_integrand.h"
#include "yarf/transport.h"

namespace yarf {

Remote<Integrator>::Remote(std::unique_ptr<RemoteInstance> instance)
    : instance_(std::move(instance)), stub_(v1::Integrator::NewStub(instance_->channel())) {
  // Errors name the class.
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
  const uint64_t sampler_handle = SamplerHandle(sampler);
  const ServedFunction served(f, instance_->address());
  return IntegrateServed(served.address(), f.OutputDimensions(), lower, upper, evaluations, seed, sampler_handle);
}

void Remote<Integrator>::Render(Transport& transport, const SceneView& scene, const Sampler& sampler,
                                RenderTarget& target) {
  const uint64_t sampler_handle = SamplerHandle(sampler);
  const uint32_t first = target.FirstSample(), spp = target.SamplesPerPixel();
  if (first >= spp) return;
  const uint32_t samples = spp - first;
  const PixelWindow window = target.Crop().value_or(PixelWindow{0, 0, scene.FilmWidth(), scene.FilmHeight()});
  TileIntegrand integrand(
      transport.Describe().class_name, transport.Dimensions(),
      [&](const PrimarySamples& points, FilmSamples& out) { transport.Evaluate(scene, points, out); },
      scene.FilmWidth(), scene.FilmHeight(), target, kTileSide);
  // One endpoint for the whole render: the component keeps a channel per
  // address it is lent.
  const ServedFunction served(integrand, instance_->address());
  const std::vector<double> lower(integrand.InputDimensions(), 0.0), upper(integrand.InputDimensions(), 1.0);
  std::vector<Vec3> values, variances;
  for (uint32_t y0 = window.y0; y0 < window.y1; y0 += kTileSide)
    for (uint32_t x0 = window.x0; x0 < window.x1; x0 += kTileSide) {
      if (target.Cancelled()) return;
      const PixelWindow tile{x0, y0, std::min(window.x1, x0 + kTileSide), std::min(window.y1, y0 + kTileSide)};
      const uint64_t pixels = uint64_t(tile.x1 - tile.x0) * (tile.y1 - tile.y0);
      integrand.SetTile(tile);
      IntegrationResult result;
      try {
        result = IntegrateServed(served.address(), integrand.OutputDimensions(), lower, upper, samples * pixels,
                                 Hash(target.Seed(), first, x0, y0), sampler_handle);
        // A component may carry on past a failed evaluation: its estimate
        // would not be of the integrand.
        if (!integrand.Failure().empty()) throw Error(integrand.Failure());
      } catch (const std::exception& e) {
        if (target.Cancelled()) return;
        // The integrand's own error is the cause; the component reports it
        // only second-hand. The call's own error names the component and
        // the call already: the tile goes in between.
        const std::string call = instance_->Name() + ": Integrator.Integrate";
        std::string cause = integrand.Failure().empty() ? e.what() : integrand.Failure();
        cause = cause.rfind(call, 0) == 0 ? cause.substr(call.size()) : ": " + cause;
        throw Error(call + " of pixels [" + std::to_string(tile.x0) + ", " + std::to_string(tile.x1) + ") x [" +
                    std::to_string(tile.y0) + ", " + std::to_string(tile.y1) + ")" + cause);
      }
      values.clear();
      variances.clear();
      for (uint32_t y = tile.y0; y < tile.y1; ++y)
        for (uint32_t x = tile.x0; x < tile.x1; ++x) {
          const size_t slot = integrand.Slot(x, y);
          const auto squared = [&](size_t i) { return float(result.standard_error[i] * result.standard_error[i]); };
          values.emplace_back(float(result.estimate[slot]), float(result.estimate[slot + 1]),
                              float(result.estimate[slot + 2]));
          variances.emplace_back(squared(slot), squared(slot + 1), squared(slot + 2));
        }
      target.AddPixelEstimates(tile, samples, values, variances);
    }
  target.PassDone(spp);
}

IntegrationResult Remote<Integrator>::IntegrateServed(const std::string& function_address, size_t outputs,
                                                      std::span<const double> lower, std::span<const double> upper,
                                                      uint64_t evaluations, uint64_t seed, uint64_t sampler_handle) {
  v1::IntegrateRequest request;
  request.set_sampler_handle(sampler_handle);
  request.set_function_address(function_address);
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
  const size_t k = outputs;
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
