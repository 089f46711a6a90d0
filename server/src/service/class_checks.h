// Submit's check of the component classes a request names: each must be
// one this server can make (a plugin's, or a component process's that
// registered), so that a misspelt class is refused at once, not when the
// job runs.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "yarf/v1/render.pb.h"

namespace yarf {

// Throws Error for the first class of `request` (a ComponentSpec or a
// Material without an address) not in `known`, naming where it is
// (`scene.materials[2] ('red')`) and the nearest known class.
void CheckClassesKnown(const v1::SubmitRequest& request, const std::vector<std::string>& known);

// The entry of `candidates` nearest to `name` in edit distance, if near
// enough to be a misspelling of it; empty otherwise.
std::string DidYouMean(std::string_view name, const std::vector<std::string>& candidates);

}  // namespace yarf
