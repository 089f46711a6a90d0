// What GetJob tells of a job's scene: its size and what it holds, the
// parts a person checks first on a job page.
#pragma once

#include "yarf/v1/render.pb.h"
#include "yarf/v1/scene.pb.h"

namespace yarf {

v1::SceneSummary SummarizeScene(const v1::Scene& scene);

}  // namespace yarf
