#include "components/remote_transport.h"

#include <cstring>
#include <vector>

namespace yarf {
namespace {

// Film coordinates, lens, time and the unused one come first.
constexpr uint32_t kMaxDimensions = 4096;

}  // namespace

Remote<Transport>::Remote(std::unique_ptr<RemoteInstance> instance)
    : instance_(std::move(instance)), stub_(v1::Transport::NewStub(instance_->channel())) {
  v1::TransportDimensionsReply reply;
  instance_->Call("Dimensions", [&](grpc::ClientContext& context, uint64_t handle) {
    v1::TransportDimensionsRequest request;
    request.set_handle(handle);
    return stub_->Dimensions(&context, request, &reply);
  });
  if (reply.dimensions() < kTransportDimension || reply.dimensions() > kMaxDimensions)
    throw instance_->BadReply("Dimensions", std::to_string(reply.dimensions()) + " (expected " +
                                                std::to_string(kTransportDimension) + " to " +
                                                std::to_string(kMaxDimensions) + ")");
  dimensions_ = reply.dimensions();
}

uint64_t Remote<Transport>::ServedHandle(const SceneView& scene) const {
  if (scene.ServiceHandle() == 0)
    throw Error(instance_->Name() + ": a remote transport needs its job's scene served by the server");
  return scene.ServiceHandle();
}

void Remote<Transport>::Prepare(const SceneView& scene) {
  v1::PrepareRequest request;
  request.set_scene_handle(ServedHandle(scene));
  v1::PrepareReply reply;
  instance_->Call("Prepare", [&](grpc::ClientContext& context, uint64_t handle) {
    request.set_handle(handle);
    return stub_->Prepare(&context, request, &reply);
  });
}

void Remote<Transport>::Evaluate(const SceneView& scene, const PrimarySamples& points, FilmSamples& out) {
  const uint32_t n = uint32_t(points.Count());
  if (n == 0) return;
  std::vector<float> coordinates(size_t(n) * dimensions_);
  for (uint32_t i = 0; i < n; ++i)
    for (uint32_t d = 0; d < dimensions_; ++d) coordinates[size_t(i) * dimensions_ + d] = points.Get(i, d);
  v1::TransportRequest request;
  request.set_scene_handle(ServedHandle(scene));
  SetFloats(request.mutable_points(), coordinates, {n, dimensions_});
  v1::TransportReply reply;
  instance_->Call("Evaluate", [&](grpc::ClientContext& context, uint64_t handle) {
    request.set_handle(handle);
    return stub_->Evaluate(&context, request, &reply);
  });
  out.splats = reply.splats();
  // An empty array (no rows, or no shape at all) is no contribution.
  if (reply.contributions().data().empty()) return;
  const uint32_t m = reply.contributions().shape_size() > 0 ? reply.contributions().shape(0) : 0;
  std::vector<float> rows(size_t(m) * 5);
  instance_->CopyFloats("Evaluate", "contributions", reply.contributions(), m, {5}, rows);
  std::vector<uint32_t> from(m);
  if (reply.has_points()) {
    instance_->CopyUints("Evaluate", "points", reply.points(), m, from);
  } else {
    if (m != n && m != 0)
      throw instance_->BadReply("Evaluate", std::to_string(m) + " contributions for " + std::to_string(n) +
                                                " points and no `points` saying where each came from");
    for (uint32_t k = 0; k < m; ++k) from[k] = k;
  }
  const float width = float(scene.FilmWidth()), height = float(scene.FilmHeight());
  for (uint32_t k = 0; k < m; ++k) {
    const float* row = &rows[size_t(k) * 5];
    if (from[k] >= n)
      throw instance_->BadReply("Evaluate", "point " + std::to_string(from[k]) + " of a batch of " + std::to_string(n));
    // Off-film positions are an error of the component, not light to drop.
    if (!(row[0] >= 0 && row[0] <= width && row[1] >= 0 && row[1] <= height))
      throw instance_->BadReply("Evaluate", "a contribution off the film at (" + std::to_string(row[0]) + ", " +
                                                std::to_string(row[1]) + ")");
    if (row[2] < 0 || row[3] < 0 || row[4] < 0)
      throw instance_->BadReply("Evaluate", "negative radiance at contribution " + std::to_string(k));
    out.Add(from[k], row[0], row[1], Vec3(row[2], row[3], row[4]));
  }
}

}  // namespace yarf
