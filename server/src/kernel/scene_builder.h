// From the proto Scene to a KernelScene: validation, mesh loading,
// component creation, flattening of nested instancing.
#pragma once

#include <filesystem>
#include <memory>

#include "components/make_component.h"
#include "kernel/scene.h"
#include "yarf/v1/scene.pb.h"

namespace yarf {

struct SceneLimits {
  static constexpr uint32_t kMaxFilmSide = 16384;
  static constexpr uint64_t kMaxPixels = uint64_t(1) << 26;
  static constexpr int kMaxInstanceDepth = 16;
  static constexpr uint64_t kMaxPlacements = 1'000'000;
};

// Cheap checks run before a job is accepted; throws Error naming the part.
void ValidateScene(const v1::Scene& scene);

struct SceneSources {
  ComponentSources components;
  const EmbreeDevice& device;
  // Folder that mesh `file` references resolve in; empty: none allowed.
  std::filesystem::path asset_root;
};

std::unique_ptr<KernelScene> BuildScene(const v1::Scene& scene, const SceneSources& sources);

}  // namespace yarf
