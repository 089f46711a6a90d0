// Remote<Texture>: values over a surface served by another process.
// Channels (with the mesh attributes the texture reads) and Mean are asked
// once, when the texture is made; Evaluate is one call per batch of
// points, carrying what SurfacePoints knows of them.
#pragma once

#include <string>
#include <vector>

#include "components/remote_instance.h"
#include "yarf/texture.h"
#include "yarf/v1/texture.grpc.pb.h"

namespace yarf {

template <>
class Remote<Texture> final : public Texture {
 public:
  explicit Remote(std::unique_ptr<RemoteInstance> instance);

  uint32_t Channels() const override { return channels_; }
  bool ReadsPositions() const override { return true; }
  void Evaluate(const SurfacePoints& at, std::span<float> value) const override;
  std::vector<float> Mean() const override { return mean_; }

 private:
  std::unique_ptr<RemoteInstance> instance_;
  std::unique_ptr<v1::Texture::Stub> stub_;
  uint32_t channels_ = 0;
  // The mesh attributes sent with every lookup (ChannelsReply.attributes).
  std::vector<std::string> attributes_;
  std::vector<float> mean_;
};

}  // namespace yarf
