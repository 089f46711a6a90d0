#include "service/instance_services.h"

#include "components/remote_function.h"
#include "components/array_codec.h"
#include "yarf/math.h"
#include "yarf/medium.h"
#include "yarf/surface.h"

namespace yarf {
namespace {

// Largest batch one call may ask for, in values.
constexpr uint64_t kMaxValues = uint64_t(1) << 26;

// Runs `call` on the instance `handle` as interface I; maps a missing
// instance, a wrong interface and bad input to gRPC statuses.
template <typename I, typename Call>
grpc::Status WithInstance(const InstanceTable& instances, const Caller& caller, uint64_t handle, Call&& call) {
  std::shared_ptr<Component> instance = instances.Find(handle, caller);
  if (!instance) return {grpc::StatusCode::NOT_FOUND, "no instance " + std::to_string(handle)};
  auto* typed = dynamic_cast<I*>(instance.get());
  if (!typed)
    return {grpc::StatusCode::FAILED_PRECONDITION, "instance " + std::to_string(handle) + " ('" +
                                                       instance->Describe().class_name +
                                                       "') does not implement " + I::kInterface};
  try {
    call(*typed);
    return grpc::Status::OK;
  } catch (const std::exception& e) {
    return {grpc::StatusCode::INVALID_ARGUMENT, std::string(I::kInterface) + ": " + e.what()};
  }
}

void CheckSize(uint64_t values) {
  if (values > kMaxValues)
    throw Error("batch of " + std::to_string(values) + " values exceeds " + std::to_string(kMaxValues));
}

// Forward, Inverse and Pdf share their shape checks.
void WarpCall(const Warp& warp, const v1::WarpRequest& request, bool forward, bool inverse,
              v1::WarpReply* reply) {
  const uint32_t in_dims = forward ? warp.DomainDimensions() : warp.ImageDimensions();
  const uint32_t out_dims = forward ? warp.ImageDimensions() : warp.DomainDimensions();
  BatchDecoder batch;
  const std::vector<float> in = batch.Floats(request.points(), {in_dims}, "points");
  const uint32_t n = batch.rows();
  std::vector<float> out(n * out_dims), pdf(n);
  if (forward) warp.Forward(in, out, pdf);
  else if (inverse) warp.Inverse(in, out, pdf);
  else warp.Pdf(in, pdf);
  if (forward || inverse) *reply->mutable_points() = FloatArray(out, {n, out_dims});
  *reply->mutable_pdf() = FloatArray(pdf, {n});
}

// Rows of world-space positions or directions, each finite (a medium's
// walk must not start from NaN); directions are made unit.
std::vector<float> Finite(std::vector<float> xyz, const char* what, bool unit) {
  for (size_t k = 0; k + 2 < xyz.size(); k += 3) {
    const Vec3 v = Vec3::Load(&xyz[k]);
    const float length = Length(v);
    if (!std::isfinite(length) || (unit && !(length > 0)))
      throw Error(std::string(what) + " " + std::to_string(k / 3) + (unit ? " has no direction" : " is not finite"));
    if (unit) (v / length).Store(&xyz[k]);
  }
  return xyz;
}

// A call's integrand: an instance on this host, or a Remote<Function>.
struct FunctionArgument {
  std::shared_ptr<Component> local;
  std::unique_ptr<Function> remote;
  Function* function = nullptr;
};

FunctionArgument ResolveFunction(const InstanceTable& instances, const Caller& caller, uint64_t handle,
                                 const std::string& address) {
  FunctionArgument argument;
  if (!address.empty()) {
    argument.remote = std::make_unique<Remote<Function>>(
        std::make_unique<RemoteInstance>(address, handle, Function::kInterface, RemoteOptions{}));
    argument.function = argument.remote.get();
    return argument;
  }
  argument.local = instances.Find(handle, caller);
  argument.function = dynamic_cast<Function*>(argument.local.get());
  if (!argument.function) throw Error("no Function instance " + std::to_string(handle));
  return argument;
}

// The integrand while its caller waits: once the caller has gone (it
// cancelled, or its deadline passed), the next batch throws, so a call of
// 2^36 evaluations does not run on for nobody.
class WhileCallerWaits final : public Function {
 public:
  WhileCallerWaits(Function& function, const grpc::ServerContext& context) : function_(function), context_(context) {
    SetInfo(function.Describe());
  }
  uint32_t InputDimensions() const override { return function_.InputDimensions(); }
  uint32_t OutputDimensions() const override { return function_.OutputDimensions(); }
  void Evaluate(std::span<const float> points, std::span<float> values) override {
    if (context_.IsCancelled()) throw Error("the caller has gone (cancelled, or past its deadline)");
    function_.Evaluate(points, values);
  }

 private:
  Function& function_;
  const grpc::ServerContext& context_;
};

}  // namespace

grpc::Status IntegratorServiceImpl::Integrate(grpc::ServerContext* context, const v1::IntegrateRequest* request,
                                              v1::IntegrateReply* reply) {
  // The integrand and the sampler live as long as this call.
  FunctionArgument argument;
  std::shared_ptr<Component> sampler_instance;
  std::unique_ptr<Component> default_sampler;
  const Sampler* sampler = nullptr;
  if (grpc::Status allowed = MayNameAddresses(CallerOf(*context), *request); !allowed.ok()) return allowed;
  try {
    argument = ResolveFunction(instances_, CallerOf(*context), request->function_handle(), request->function_address());
    if (request->sampler_handle() != 0) {
      sampler_instance = instances_.Find(request->sampler_handle(), CallerOf(*context));
      sampler = dynamic_cast<const Sampler*>(sampler_instance.get());
      if (!sampler) throw Error("no Sampler instance " + std::to_string(request->sampler_handle()));
    } else {
      default_sampler = registry_.Create("independent", Properties{});
      sampler = dynamic_cast<const Sampler*>(default_sampler.get());
    }
  } catch (const Error& e) {
    return {grpc::StatusCode::FAILED_PRECONDITION, e.what()};
  }
  WhileCallerWaits waited(*argument.function, *context);
  Function* function = &waited;
  return WithInstance<Integrator>(instances_, CallerOf(*context), request->handle(), [&](Integrator& integrator) {
    if (request->lower_size() != int(function->InputDimensions()) || request->upper_size() != request->lower_size())
      throw Error("the box needs " + std::to_string(function->InputDimensions()) + " lower and upper bounds");
    if (request->evaluations() == 0 || request->evaluations() > (uint64_t(1) << 36))
      throw Error("evaluations must lie in [1, 2^36]");
    const std::vector<double> lower(request->lower().begin(), request->lower().end());
    const std::vector<double> upper(request->upper().begin(), request->upper().end());
    const IntegrationResult result =
        integrator.Integrate(*function, lower, upper, request->evaluations(), request->seed(), *sampler);
    for (double e : result.estimate) reply->add_estimate(e);
    for (double e : result.standard_error) reply->add_standard_error(e);
    for (double c : result.chi2_per_dof) reply->add_chi2_per_dof(c);
    for (double q : result.q) reply->add_q(q);
    reply->set_evaluations(result.evaluations);
  });
}

grpc::Status RootFinderServiceImpl::FindRoot(grpc::ServerContext* context, const v1::FindRootRequest* request,
                                             v1::FindRootReply* reply) {
  if (grpc::Status allowed = MayNameAddresses(CallerOf(*context), *request); !allowed.ok()) return allowed;
  FunctionArgument argument;
  try {
    argument = ResolveFunction(instances_, CallerOf(*context), request->function_handle(), request->function_address());
  } catch (const Error& e) {
    return {grpc::StatusCode::FAILED_PRECONDITION, e.what()};
  }
  WhileCallerWaits waited(*argument.function, *context);
  return WithInstance<RootFinder>(instances_, CallerOf(*context), request->handle(), [&](RootFinder& finder) {
    const RootResult result = finder.FindRoot(waited, request->lower(), request->upper(),
                                              request->tolerance(), request->max_iterations());
    reply->set_root(result.root);
    reply->set_iterations(result.iterations);
  });
}

grpc::Status SamplerServiceImpl::Generate(grpc::ServerContext* context, const v1::GenerateSamplesRequest* request,
                                          v1::GenerateSamplesReply* reply) {
  return WithInstance<Sampler>(instances_, CallerOf(*context), request->handle(), [&](const Sampler& sampler) {
    CheckSize(uint64_t(request->count()) * request->dimensions());
    std::vector<float> points(size_t(request->count()) * request->dimensions());
    sampler.Generate(request->first_index(), request->count(), request->dimensions(), request->seed(), points);
    *reply->mutable_points() = FloatArray(points, {request->count(), request->dimensions()});
  });
}

grpc::Status GeneratorServiceImpl::Next(grpc::ServerContext* context, const v1::GeneratorRequest* request,
                                        v1::GeneratorReply* reply) {
  return WithInstance<Generator>(instances_, CallerOf(*context), request->handle(), [&](Generator& generator) {
    CheckSize(request->count());
    std::vector<float> values(request->count());
    generator.Next(request->seed(), request->stream(), request->offset(), values);
    *reply->mutable_values() = FloatArray(values, {request->count()});
  });
}

grpc::Status WarpServiceImpl::Signature(grpc::ServerContext* context, const v1::WarpSignatureRequest* request,
                                        v1::WarpSignature* reply) {
  return WithInstance<Warp>(instances_, CallerOf(*context), request->handle(), [&](const Warp& warp) {
    reply->set_domain_dimensions(warp.DomainDimensions());
    reply->set_image_dimensions(warp.ImageDimensions());
  });
}

grpc::Status WarpServiceImpl::Forward(grpc::ServerContext* context, const v1::WarpRequest* request,
                                      v1::WarpReply* reply) {
  return WithInstance<Warp>(instances_, CallerOf(*context), request->handle(),
                            [&](const Warp& warp) { WarpCall(warp, *request, true, false, reply); });
}

grpc::Status WarpServiceImpl::Inverse(grpc::ServerContext* context, const v1::WarpRequest* request,
                                      v1::WarpReply* reply) {
  return WithInstance<Warp>(instances_, CallerOf(*context), request->handle(),
                            [&](const Warp& warp) { WarpCall(warp, *request, false, true, reply); });
}

grpc::Status WarpServiceImpl::Pdf(grpc::ServerContext* context, const v1::WarpRequest* request, v1::WarpReply* reply) {
  return WithInstance<Warp>(instances_, CallerOf(*context), request->handle(),
                            [&](const Warp& warp) { WarpCall(warp, *request, false, false, reply); });
}

grpc::Status SurfaceModelServiceImpl::Evaluate(grpc::ServerContext* context, const v1::SurfaceQuery* request,
                                               v1::EvaluateSurfaceReply* reply) {
  return WithInstance<SurfaceModel>(instances_, CallerOf(*context), request->handle(), [&](const SurfaceModel& model) {
    BatchDecoder batch;
    const auto wi = batch.Floats(request->wi(), {3}, "wi");
    const auto wo = batch.Floats(request->wo(), {3}, "wo");
    const auto uv = batch.Floats(request->uv(), {2}, "uv");
    const uint32_t n = batch.rows();
    std::vector<float> value(3 * n);
    model.Evaluate(TransportMode(request->mode()), wi, wo, SurfacePoints{.uv = uv}, value);
    *reply->mutable_value() = FloatArray(value, {n, 3});
  });
}

grpc::Status SurfaceModelServiceImpl::Sample(grpc::ServerContext* context, const v1::SampleSurfaceRequest* request,
                                             v1::SampleSurfaceReply* reply) {
  return WithInstance<SurfaceModel>(instances_, CallerOf(*context), request->handle(), [&](const SurfaceModel& model) {
    BatchDecoder batch;
    const auto wi = batch.Floats(request->wi(), {3}, "wi");
    const auto uv = batch.Floats(request->uv(), {2}, "uv");
    const auto u = batch.Floats(request->uniform(), {3}, "uniform");
    const uint32_t n = batch.rows();
    std::vector<float> wo(3 * n), weight(3 * n), pdf(n);
    std::vector<uint32_t> flags(n);
    model.Sample(TransportMode(request->mode()), wi, SurfacePoints{.uv = uv}, u, request->allowed(), wo, weight, pdf, flags);
    *reply->mutable_wo() = FloatArray(wo, {n, 3});
    *reply->mutable_weight() = FloatArray(weight, {n, 3});
    *reply->mutable_pdf() = FloatArray(pdf, {n});
    *reply->mutable_flags() = Uint32Array(flags, {n});
  });
}

grpc::Status SurfaceModelServiceImpl::Pdf(grpc::ServerContext* context, const v1::SurfaceQuery* request,
                                          v1::PdfSurfaceReply* reply) {
  return WithInstance<SurfaceModel>(instances_, CallerOf(*context), request->handle(), [&](const SurfaceModel& model) {
    BatchDecoder batch;
    const auto wi = batch.Floats(request->wi(), {3}, "wi");
    const auto wo = batch.Floats(request->wo(), {3}, "wo");
    const auto uv = batch.Floats(request->uv(), {2}, "uv");
    const uint32_t n = batch.rows();
    std::vector<float> pdf(n);
    model.Pdf(wi, wo, SurfacePoints{.uv = uv}, pdf);
    *reply->mutable_pdf() = FloatArray(pdf, {n});
  });
}

grpc::Status SurfaceModelServiceImpl::Lobes(grpc::ServerContext* context, const v1::LobesRequest* request,
                                            v1::LobesReply* reply) {
  return WithInstance<SurfaceModel>(instances_, CallerOf(*context), request->handle(),
                                    [&](const SurfaceModel& model) { reply->set_flags(model.Lobes()); });
}

grpc::Status EmitterServiceImpl::Radiance(grpc::ServerContext* context, const v1::RadianceRequest* request,
                                          v1::RadianceReply* reply) {
  return WithInstance<Emitter>(instances_, CallerOf(*context), request->handle(), [&](const Emitter& emitter) {
    BatchDecoder batch;
    const auto w = batch.Floats(request->w(), {3}, "w");
    const auto uv = batch.Floats(request->uv(), {2}, "uv");
    const uint32_t n = batch.rows();
    std::vector<float> radiance(3 * n);
    emitter.Radiance(w, SurfacePoints{.uv = uv}, radiance);
    *reply->mutable_radiance() = FloatArray(radiance, {n, 3});
  });
}

grpc::Status EmitterServiceImpl::SampleDirection(grpc::ServerContext* context,
                                                 const v1::SampleDirectionRequest* request,
                                                 v1::SampleDirectionReply* reply) {
  return WithInstance<Emitter>(instances_, CallerOf(*context), request->handle(), [&](const Emitter& emitter) {
    BatchDecoder batch;
    const auto u = batch.Floats(request->uniform(), {2}, "uniform");
    const uint32_t n = batch.rows();
    std::vector<float> w(3 * n), pdf(n);
    emitter.SampleDirection(u, w, pdf);
    *reply->mutable_w() = FloatArray(w, {n, 3});
    *reply->mutable_pdf() = FloatArray(pdf, {n});
  });
}

grpc::Status EmitterServiceImpl::PdfDirection(grpc::ServerContext* context, const v1::PdfDirectionRequest* request,
                                              v1::PdfDirectionReply* reply) {
  return WithInstance<Emitter>(instances_, CallerOf(*context), request->handle(), [&](const Emitter& emitter) {
    BatchDecoder batch;
    const auto w = batch.Floats(request->w(), {3}, "w");
    const uint32_t n = batch.rows();
    std::vector<float> pdf(n);
    emitter.PdfDirection(w, pdf);
    *reply->mutable_pdf() = FloatArray(pdf, {n});
  });
}

grpc::Status MediumServiceImpl::Majorants(grpc::ServerContext* context, const v1::MajorantsRequest* request,
                                          v1::MajorantsReply* reply) {
  return WithInstance<Medium>(instances_, CallerOf(*context), request->handle(), [&](const Medium& medium) {
    BatchDecoder batch;
    const auto origin = Finite(batch.Floats(request->origin(), {3}, "origin"), "origin", false);
    const auto direction = Finite(batch.Floats(request->direction(), {3}, "direction"), "direction", true);
    const auto tmax = batch.Floats(request->tmax(), {}, "tmax");
    CheckSize(uint64_t(batch.rows()) * 3);
    for (size_t i = 0; i < tmax.size(); ++i)
      if (!(tmax[i] >= 0)) throw Error("tmax " + std::to_string(i) + " is negative or NaN");
    MajorantSegments segments;
    segments.Clear();
    medium.Majorants(origin, direction, tmax, segments);
    std::vector<float> rows;
    rows.reserve(5 * segments.segments.size());
    for (const MajorantSegment& s : segments.segments)
      for (float value : {s.t0, s.t1, s.sigma_maj.x, s.sigma_maj.y, s.sigma_maj.z}) rows.push_back(value);
    *reply->mutable_segments() = FloatArray(rows, {uint32_t(segments.segments.size()), 5});
    *reply->mutable_offsets() = Uint32Array(segments.offsets, {uint32_t(segments.offsets.size())});
  });
}

grpc::Status MediumServiceImpl::Coefficients(grpc::ServerContext* context, const v1::CoefficientsRequest* request,
                                             v1::CoefficientsReply* reply) {
  return WithInstance<Medium>(instances_, CallerOf(*context), request->handle(), [&](const Medium& medium) {
    BatchDecoder batch;
    const auto position = Finite(batch.Floats(request->position(), {3}, "position"), "position", false);
    const uint32_t n = batch.rows();
    CheckSize(uint64_t(n) * 9);
    std::vector<float> sigma_a(3 * n), sigma_s(3 * n), emission(3 * n);
    medium.Coefficients(position, sigma_a, sigma_s, emission);
    *reply->mutable_sigma_a() = FloatArray(sigma_a, {n, 3});
    *reply->mutable_sigma_s() = FloatArray(sigma_s, {n, 3});
    *reply->mutable_emission() = FloatArray(emission, {n, 3});
  });
}

grpc::Status MediumServiceImpl::Emits(grpc::ServerContext* context, const v1::EmitsRequest* request,
                                      v1::EmitsReply* reply) {
  return WithInstance<Medium>(instances_, CallerOf(*context), request->handle(),
                              [&](const Medium& medium) { reply->set_emits(medium.Emits()); });
}

grpc::Status MediumServiceImpl::EvaluatePhase(grpc::ServerContext* context, const v1::PhaseQuery* request,
                                              v1::EvaluatePhaseReply* reply) {
  return WithInstance<Medium>(instances_, CallerOf(*context), request->handle(), [&](const Medium& medium) {
    BatchDecoder batch;
    const auto wi = Finite(batch.Floats(request->wi(), {3}, "wi"), "wi", true);
    const auto wo = Finite(batch.Floats(request->wo(), {3}, "wo"), "wo", true);
    const auto position = Finite(batch.Floats(request->position(), {3}, "position"), "position", false);
    const uint32_t n = batch.rows();
    CheckSize(uint64_t(n) * 2);
    std::vector<float> value(n), pdf(n);
    medium.EvaluatePhase(wi, wo, position, value, pdf);
    *reply->mutable_value() = FloatArray(value, {n});
    *reply->mutable_pdf() = FloatArray(pdf, {n});
  });
}

grpc::Status MediumServiceImpl::SamplePhase(grpc::ServerContext* context, const v1::SamplePhaseRequest* request,
                                            v1::SamplePhaseReply* reply) {
  return WithInstance<Medium>(instances_, CallerOf(*context), request->handle(), [&](const Medium& medium) {
    BatchDecoder batch;
    const auto wi = Finite(batch.Floats(request->wi(), {3}, "wi"), "wi", true);
    const auto position = Finite(batch.Floats(request->position(), {3}, "position"), "position", false);
    const auto u = batch.Floats(request->uniform(), {2}, "uniform");
    const uint32_t n = batch.rows();
    CheckSize(uint64_t(n) * 5);
    for (size_t i = 0; i < u.size(); ++i)
      if (!(u[i] >= 0 && u[i] < 1)) throw Error("uniform " + std::to_string(i / 2) + " is not in [0, 1)");
    std::vector<float> wo(3 * n), weight(n), pdf(n);
    medium.SamplePhase(wi, position, u, wo, weight, pdf);
    *reply->mutable_wo() = FloatArray(wo, {n, 3});
    *reply->mutable_weight() = FloatArray(weight, {n});
    *reply->mutable_pdf() = FloatArray(pdf, {n});
  });
}

}  // namespace yarf
