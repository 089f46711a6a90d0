// yarf.v1.SceneView, Intersect and the Shape services for the scenes of running jobs:
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

class SceneViewServiceImpl final : public v1::SceneView::Service {
 public:
  explicit SceneViewServiceImpl(const JobScenes& scenes) : scenes_(scenes) {}
  grpc::Status Layout(grpc::ServerContext*, const v1::SceneViewRequest*, v1::SceneLayout*) override;
  grpc::Status CameraRays(grpc::ServerContext*, const v1::CameraRaysRequest*, v1::RayBatch*) override;
  grpc::Status ShutterTimes(grpc::ServerContext*, const v1::ShutterTimesRequest*, v1::ShutterTimesReply*) override;
  grpc::Status SampleLights(grpc::ServerContext*, const v1::SampleLightsRequest*, v1::SampleLightsReply*) override;
  grpc::Status LightPoints(grpc::ServerContext*, const v1::LightPointsRequest*, v1::SampleLightsReply*) override;
  grpc::Status SampleLightPoints(grpc::ServerContext*, const v1::SampleLightPointsRequest*,
                                 v1::LightPointsReply*) override;
  grpc::Status LightPdfArea(grpc::ServerContext*, const v1::LightPdfAreaRequest*, v1::LightPdfAreaReply*) override;
  grpc::Status InfiniteLightOrigins(grpc::ServerContext*, const v1::InfiniteLightOriginsRequest*,
                                    v1::InfiniteLightOriginsReply*) override;
  grpc::Status Emission(grpc::ServerContext*, const v1::EmissionRequest*, v1::EmissionReply*) override;
  grpc::Status ConnectToCamera(grpc::ServerContext*, const v1::ConnectToCameraRequest*,
                               v1::ConnectToCameraReply*) override;
  grpc::Status CameraDirectionPdf(grpc::ServerContext*, const v1::CameraDirectionPdfRequest*,
                                  v1::CameraDirectionPdfReply*) override;
  grpc::Status SampleSpacing(grpc::ServerContext*, const v1::SampleSpacingRequest*,
                             v1::SampleSpacingReply*) override;
  grpc::Status Triangles(grpc::ServerContext*, const v1::TrianglesRequest*, v1::TrianglesReply*) override;

 private:
  const JobScenes& scenes_;
};

}  // namespace yarf
