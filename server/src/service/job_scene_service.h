// yarf.v1.JobScene and yarf.v1.Intersect for the scenes of running jobs:
// what a transport algorithm in another process traces and shades with.
#pragma once

#include "service/job_scenes.h"
#include "yarf/v1/geometry.grpc.pb.h"
#include "yarf/v1/transport.grpc.pb.h"

namespace yarf {

class IntersectServiceImpl final : public v1::Intersect::Service {
 public:
  explicit IntersectServiceImpl(const JobScenes& scenes) : scenes_(scenes) {}
  grpc::Status Intersect(grpc::ServerContext*, const v1::IntersectRequest*, v1::IntersectReply*) override;
  grpc::Status Occluded(grpc::ServerContext*, const v1::IntersectRequest*, v1::OccludedReply*) override;
  grpc::Status CrossSection(grpc::ServerContext*, const v1::IntersectRequest*, v1::CrossSectionReply*) override;

 private:
  const JobScenes& scenes_;
};

// Shape, SampleSurfaceArea and SampleSurfaceDirection for the shapes of
// running jobs: the kernel's own surfaces and densities.
class ShapeServiceImpl final : public v1::Shape::Service {
 public:
  explicit ShapeServiceImpl(const JobScenes& scenes) : scenes_(scenes) {}
  grpc::Status Bounds(grpc::ServerContext*, const v1::ShapeRequest*, v1::BoundsReply*) override;
  grpc::Status Area(grpc::ServerContext*, const v1::ShapeRequest*, v1::AreaReply*) override;

 private:
  const JobScenes& scenes_;
};

class SampleSurfaceAreaServiceImpl final : public v1::SampleSurfaceArea::Service {
 public:
  explicit SampleSurfaceAreaServiceImpl(const JobScenes& scenes) : scenes_(scenes) {}
  grpc::Status Sample(grpc::ServerContext*, const v1::SurfaceSampleRequest*, v1::SurfaceSampleReply*) override;

 private:
  const JobScenes& scenes_;
};

class SampleSurfaceDirectionServiceImpl final : public v1::SampleSurfaceDirection::Service {
 public:
  explicit SampleSurfaceDirectionServiceImpl(const JobScenes& scenes) : scenes_(scenes) {}
  grpc::Status Sample(grpc::ServerContext*, const v1::SurfaceSampleRequest*, v1::SurfaceSampleReply*) override;
  grpc::Status Pdf(grpc::ServerContext*, const v1::SurfacePdfRequest*, v1::SurfacePdfReply*) override;

 private:
  const JobScenes& scenes_;
};

class JobSceneServiceImpl final : public v1::JobScene::Service {
 public:
  explicit JobSceneServiceImpl(const JobScenes& scenes) : scenes_(scenes) {}
  grpc::Status Layout(grpc::ServerContext*, const v1::JobSceneRequest*, v1::SceneLayout*) override;
  grpc::Status CameraRays(grpc::ServerContext*, const v1::CameraRaysRequest*, v1::RayBatch*) override;
  grpc::Status SampleLights(grpc::ServerContext*, const v1::SampleLightsRequest*, v1::SampleLightsReply*) override;
  grpc::Status Emission(grpc::ServerContext*, const v1::EmissionRequest*, v1::EmissionReply*) override;
  grpc::Status Splat(grpc::ServerContext*, const v1::SplatRequest*, v1::SplatReply*) override;

 private:
  const JobScenes& scenes_;
};

}  // namespace yarf
