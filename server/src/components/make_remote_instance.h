// Factory.Create on yarfd for a class of a component process: the
// instance is made there, and yarfd's own interface services call it
// through Remote<I> (a caller reaches a Python warp, root finder or
// integrator by yarfd's address, as it reaches the C++ ones).
#pragma once

#include <memory>
#include <string>

#include "components/remote_instance.h"
#include "yarf/component.h"
#include "yarf/v1/component.pb.h"

namespace yarf {

// An instance of `info`'s class at `address`, behind the Remote<I> of the
// one interface of the class this server can call. Throws Error when the
// class serves none of them, or several (which one to call would be a
// guess).
std::unique_ptr<Component> MakeRemoteInstance(const ComponentInfo& info, const std::string& address,
                                              const v1::Properties& properties, const RemoteOptions& options);

}  // namespace yarf
