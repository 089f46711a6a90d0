// The one exception type components and the kernel throw for bad input.
#pragma once

#include <stdexcept>
#include <string>

namespace yarf {

// Bad input or a failed component call. The message is shown to the user
// as it is, so it names what failed (a property, a file, a component).
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace yarf
