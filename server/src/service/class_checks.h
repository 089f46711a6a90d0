// Submit's check of the components a request names: each class must be
// one this server can make (a plugin's, or a component process's that
// registered), and its properties those the class declares, so that a
// misspelt class or property is refused at once, not when the job runs.
#pragma once

#include <vector>

#include "yarf/component.h"
#include "yarf/v1/render.pb.h"

namespace yarf {

// Throws Error for the first component of `request` (a ComponentSpec or a
// Material without an address) whose class is not in `known`, or whose
// properties its class's declared parameters refuse, naming where it is
// (`scene.materials[2] ('red').properties.roughnes`) and the nearest
// known name.
void CheckComponents(const v1::SubmitRequest& request, const std::vector<ComponentInfo>& known);

}  // namespace yarf
