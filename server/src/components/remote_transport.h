// Remote<Transport>: a light transport algorithm served by another
// process. It traces its paths through the server's SceneView and
// Intersect services, naming the job's scene by its service handle.
#pragma once

#include "components/remote_instance.h"
#include "yarf/transport.h"
#include "yarf/v1/transport.grpc.pb.h"

namespace yarf {

template <>
class Remote<Transport> final : public Transport {
 public:
  Remote(std::unique_ptr<RemoteInstance> instance);

  void Prepare(const SceneView& scene) override;
  uint32_t Dimensions() const override { return dimensions_; }
  // One call per batch: the points travel as a dense [N, d] array.
  void Evaluate(const SceneView& scene, const PrimarySamples& points, FilmSamples& out) override;

 private:
  uint64_t ServedHandle(const SceneView& scene) const;

  std::unique_ptr<RemoteInstance> instance_;
  std::unique_ptr<v1::Transport::Stub> stub_;
  uint32_t dimensions_ = 0;
};

}  // namespace yarf
