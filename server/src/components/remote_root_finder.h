// Remote<RootFinder>: a root finder served by another process, calling
// back the function whose root it seeks (served by ServedFunction).
#pragma once

#include "components/remote_instance.h"
#include "yarf/math.h"
#include "yarf/v1/math.grpc.pb.h"

namespace yarf {

// The root is checked to be finite and inside the bracket, the
// iterations to be within the budget.
template <>
class Remote<RootFinder> final : public RootFinder {
 public:
  Remote(std::unique_ptr<RemoteInstance> instance);

  RootResult FindRoot(Function& f, double lower, double upper, double tolerance, uint32_t max_iterations) override;

 private:
  std::unique_ptr<RemoteInstance> instance_;
  std::unique_ptr<v1::RootFinder::Stub> stub_;
};

}  // namespace yarf
