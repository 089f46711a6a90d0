// The interfaces of instances made with Factory.Create, served over gRPC:
// a remote caller uses an in-process component exactly as the kernel does.
#pragma once

#include "service/component_service.h"
#include "yarf/v1/math.grpc.pb.h"
#include "yarf/v1/medium.grpc.pb.h"
#include "yarf/v1/surface.grpc.pb.h"

namespace yarf {

class IntegratorServiceImpl final : public v1::Integrator::Service {
 public:
  IntegratorServiceImpl(const Registry& registry, const InstanceTable& instances)
      : registry_(registry), instances_(instances) {}
  grpc::Status Integrate(grpc::ServerContext*, const v1::IntegrateRequest*, v1::IntegrateReply*) override;

 private:
  const Registry& registry_;
  const InstanceTable& instances_;
};

class RootFinderServiceImpl final : public v1::RootFinder::Service {
 public:
  explicit RootFinderServiceImpl(const InstanceTable& instances) : instances_(instances) {}
  grpc::Status FindRoot(grpc::ServerContext*, const v1::FindRootRequest*, v1::FindRootReply*) override;

 private:
  const InstanceTable& instances_;
};

class SamplerServiceImpl final : public v1::Sampler::Service {
 public:
  explicit SamplerServiceImpl(const InstanceTable& instances) : instances_(instances) {}
  grpc::Status Generate(grpc::ServerContext*, const v1::GenerateSamplesRequest*,
                        v1::GenerateSamplesReply*) override;

 private:
  const InstanceTable& instances_;
};

class GeneratorServiceImpl final : public v1::Generator::Service {
 public:
  explicit GeneratorServiceImpl(const InstanceTable& instances) : instances_(instances) {}
  grpc::Status Next(grpc::ServerContext*, const v1::GeneratorRequest*, v1::GeneratorReply*) override;

 private:
  const InstanceTable& instances_;
};

class WarpServiceImpl final : public v1::Warp::Service {
 public:
  explicit WarpServiceImpl(const InstanceTable& instances) : instances_(instances) {}
  grpc::Status Signature(grpc::ServerContext*, const v1::WarpSignatureRequest*, v1::WarpSignature*) override;
  grpc::Status Forward(grpc::ServerContext*, const v1::WarpRequest*, v1::WarpReply*) override;
  grpc::Status Inverse(grpc::ServerContext*, const v1::WarpRequest*, v1::WarpReply*) override;
  grpc::Status Pdf(grpc::ServerContext*, const v1::WarpRequest*, v1::WarpReply*) override;

 private:
  const InstanceTable& instances_;
};

class SurfaceModelServiceImpl final : public v1::SurfaceModel::Service {
 public:
  explicit SurfaceModelServiceImpl(const InstanceTable& instances) : instances_(instances) {}
  grpc::Status Evaluate(grpc::ServerContext*, const v1::SurfaceQuery*, v1::EvaluateSurfaceReply*) override;
  grpc::Status Sample(grpc::ServerContext*, const v1::SampleSurfaceRequest*, v1::SampleSurfaceReply*) override;
  grpc::Status Pdf(grpc::ServerContext*, const v1::SurfaceQuery*, v1::PdfSurfaceReply*) override;
  grpc::Status Lobes(grpc::ServerContext*, const v1::LobesRequest*, v1::LobesReply*) override;

 private:
  const InstanceTable& instances_;
};

class EmitterServiceImpl final : public v1::Emitter::Service {
 public:
  explicit EmitterServiceImpl(const InstanceTable& instances) : instances_(instances) {}
  grpc::Status Radiance(grpc::ServerContext*, const v1::RadianceRequest*, v1::RadianceReply*) override;
  grpc::Status SampleDirection(grpc::ServerContext*, const v1::SampleDirectionRequest*,
                               v1::SampleDirectionReply*) override;
  grpc::Status PdfDirection(grpc::ServerContext*, const v1::PdfDirectionRequest*,
                            v1::PdfDirectionReply*) override;

 private:
  const InstanceTable& instances_;
};

// Media made by Factory.Create, and those of running jobs' scenes
// (SceneView's Layout names them).
class MediumServiceImpl final : public v1::Medium::Service {
 public:
  explicit MediumServiceImpl(const InstanceTable& instances) : instances_(instances) {}
  grpc::Status Majorants(grpc::ServerContext*, const v1::MajorantsRequest*, v1::MajorantsReply*) override;
  grpc::Status Coefficients(grpc::ServerContext*, const v1::CoefficientsRequest*, v1::CoefficientsReply*) override;
  grpc::Status Emits(grpc::ServerContext*, const v1::EmitsRequest*, v1::EmitsReply*) override;
  grpc::Status EvaluatePhase(grpc::ServerContext*, const v1::PhaseQuery*, v1::EvaluatePhaseReply*) override;
  grpc::Status SamplePhase(grpc::ServerContext*, const v1::SamplePhaseRequest*, v1::SamplePhaseReply*) override;

 private:
  const InstanceTable& instances_;
};

}  // namespace yarf
