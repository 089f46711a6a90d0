#include "components/remote_texture.h"

#include <cmath>

#include "components/array_codec.h"

namespace yarf {
namespace {

// Where the points lie: shape and primitive [N] and barycentrics [N,2].
void SetLocations(v1::TextureQuery& request, std::span<const SurfaceLocation> location) {
  const uint32_t n = uint32_t(location.size());
  std::vector<uint32_t> shape(n), primitive(n);
  std::vector<float> barycentrics(2 * size_t(n));
  for (uint32_t k = 0; k < n; ++k) {
    shape[k] = location[k].shape;
    primitive[k] = location[k].primitive;
    barycentrics[2 * k] = location[k].b1;
    barycentrics[2 * k + 1] = location[k].b2;
  }
  *request.mutable_shape() = Uint32Array(shape, {n});
  *request.mutable_primitive() = Uint32Array(primitive, {n});
  SetFloats(request.mutable_barycentrics(), barycentrics, {n, 2});
}

// The attributes `names` at the points, [N,3] each.
void SetAttributes(v1::TextureQuery& request, const std::vector<std::string>& names,
                   const SurfaceAttributes& attributes, std::span<const SurfaceLocation> location) {
  const uint32_t n = uint32_t(location.size());
  std::vector<float> rgb(3 * size_t(n));
  for (const std::string& name : names) {
    attributes.Attribute(name, location, rgb);
    SetFloats(&(*request.mutable_attributes())[name], rgb, {n, 3});
  }
}

}  // namespace

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
  for (const std::string& name : channels.attributes()) {
    // The names mesh_attribute accepts: anything else would read 0 everywhere.
    if (!name.starts_with("vertex_") && !name.starts_with("face_"))
      throw instance_->BadReply("Channels", "attribute '" + name + "' (\"vertex_…\" or \"face_…\" expected)");
    attributes_.push_back(name);
  }
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
  if (at.position.size() >= 3 * size_t(n))
    SetFloats(request.mutable_position(), at.position.first(3 * size_t(n)), {n, 3});
  // Attributes are read at a location: without one they stay absent.
  if (at.location.size() >= n) {
    SetLocations(request, at.location.first(n));
    if (at.attributes != nullptr) SetAttributes(request, attributes_, *at.attributes, at.location.first(n));
  }
  v1::TextureReply reply;
  instance_->Call("Evaluate", [&](grpc::ClientContext& context, uint64_t handle) {
    request.set_handle(handle);
    return stub_->Evaluate(&context, request, &reply);
  });
  instance_->CopyFloats("Evaluate", "value", reply.value(), n, {channels_}, value.first(size_t(n) * channels_));
}

}  // namespace yarf
