#include "components/remote_texture.h"

#include <cmath>

namespace yarf {

Remote<Texture>::Remote(std::unique_ptr<RemoteInstance> instance)
    : instance_(std::move(instance)), stub_(v1::Texture::NewStub(instance_->channel())) {
  v1::ChannelsReply channels;
  instance_->Call("Channels", [&](grpc::ClientContext& context, uint64_t handle) {
    v1::ChannelsRequest request;
    request.set_handle(handle);
    return stub_->Channels(&context, request, &channels);
  });
  if (channels.channels() != 1 && channels.channels() != 3)
    throw instance_->BadReply("Channels", std::to_string(channels.channels()) + " channels (1 or 3 expected)");
  channels_ = channels.channels();
  v1::MeanReply mean;
  instance_->Call("Mean", [&](grpc::ClientContext& context, uint64_t handle) {
    v1::MeanRequest request;
    request.set_handle(handle);
    return stub_->Mean(&context, request, &mean);
  });
  if (uint32_t(mean.mean_size()) != channels_)
    throw instance_->BadReply("Mean", std::to_string(mean.mean_size()) + " values for " +
                                          std::to_string(channels_) + " channels");
  for (const float m : mean.mean())
    if (!std::isfinite(m)) throw instance_->BadReply("Mean", "a value that is not finite");
  mean_.assign(mean.mean().begin(), mean.mean().end());
}

void Remote<Texture>::Evaluate(const SurfacePoints& at, std::span<float> value) const {
  const uint32_t n = uint32_t(at.Count());
  if (n == 0) return;
  v1::TextureQuery request;
  SetFloats(request.mutable_uv(), at.uv.first(2 * size_t(n)), {n, 2});
  if (at.footprint.size() >= 4 * size_t(n))
    SetFloats(request.mutable_footprint(), at.footprint.first(4 * size_t(n)), {n, 4});
  v1::TextureReply reply;
  instance_->Call("Evaluate", [&](grpc::ClientContext& context, uint64_t handle) {
    request.set_handle(handle);
    return stub_->Evaluate(&context, request, &reply);
  });
  instance_->CopyFloats("Evaluate", "value", reply.value(), n, {channels_}, value.first(size_t(n) * channels_));
}

}  // namespace yarf
