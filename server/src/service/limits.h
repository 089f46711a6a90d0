// The error of a request that would pass a limit of the server's or of the
// caller's share (jobs queued, instances, Watch streams, a job's memory):
// RESOURCE_EXHAUSTED, unlike bad input (INVALID_ARGUMENT).
#pragma once

#include "yarf/error.h"

namespace yarf {

class LimitReached : public Error {
 public:
  using Error::Error;
};

}  // namespace yarf
