// Remote<Warp>: a warp served by another process.
#pragma once

#include "components/remote_instance.h"
#include "yarf/math.h"
#include "yarf/v1/math.grpc.pb.h"

namespace yarf {

// Every batch is one call; warped points and preimages are checked for
// shape and finiteness, preimages for lying in the unit cube, densities
// for being non-negative.
template <>
class Remote<Warp> final : public Warp {
 public:
  Remote(std::unique_ptr<RemoteInstance> instance);

  uint32_t DomainDimensions() const override { return domain_dimensions_; }
  uint32_t ImageDimensions() const override { return image_dimensions_; }
  void Forward(std::span<const float> uniform, std::span<float> points, std::span<float> pdf) const override;
  void Inverse(std::span<const float> points, std::span<float> uniform, std::span<float> pdf) const override;
  void Pdf(std::span<const float> points, std::span<float> pdf) const override;

 private:
  // One Forward, Inverse or Pdf call: `in` has `in_dims` columns, `out`
  // (none for Pdf) `out_dims`.
  using Rpc = grpc::Status (v1::Warp::Stub::*)(grpc::ClientContext*, const v1::WarpRequest&, v1::WarpReply*);
  void Call(const char* method, Rpc rpc, std::span<const float> in, uint32_t in_dims, std::span<float> out,
            uint32_t out_dims, std::span<float> pdf) const;

  std::unique_ptr<RemoteInstance> instance_;
  std::unique_ptr<v1::Warp::Stub> stub_;
  uint32_t domain_dimensions_ = 0, image_dimensions_ = 0;
};

}  // namespace yarf
