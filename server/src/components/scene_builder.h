// From the proto Scene to a KernelScene: validation, mesh loading,
// component creation, flattening of nested instancing.
#pragma once

#include <atomic>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "components/make_component.h"
#include "kernel/scene.h"
#include "yarf/v1/scene.pb.h"

namespace yarf {

struct SceneLimits {
  static constexpr uint32_t kMaxFilmSide = 16384;
  static constexpr uint64_t kMaxPixels = uint64_t(1) << 26;
  static constexpr int kMaxInstanceDepth = 16;
  static constexpr uint64_t kMaxPlacements = 1'000'000;
  // Parts one lookup of a texture or material may evaluate: itself and
  // what it refers to, a part shared by two references counted twice.
  static constexpr uint64_t kMaxReferenceTree = 1024;
};

// Mesh files uploaded by content (Mesh.asset), named by their SHA-256.
// The service's AssetStore implements it; the kernel only reads.
class AssetSource {
 public:
  virtual ~AssetSource() = default;
  // `sha256` is 64 lowercase hex digits.
  virtual bool Has(const std::string& sha256) const = 0;
  // The asset's bytes; throws Error when it is not held.
  virtual std::string Read(const std::string& sha256) const = 0;
  // The asset's file, for readers that open files themselves (images);
  // throws Error when it is not held.
  virtual std::filesystem::path FileOf(const std::string& sha256) const = 0;
};

// The hashes of the assets the scene names: its shapes' and groups'
// meshes, its textures' files.
std::vector<std::string> SceneAssets(const v1::Scene& scene);

// The files the scene's components read themselves (textures' images,
// environment maps, media's grids), one entry per component that names
// one, resolved as the build resolves them: a `filename` under
// `asset_root`, an `asset` in `assets`. Those that would not resolve are
// left out: the build refuses them, naming them.
std::vector<std::filesystem::path> ComponentFiles(const v1::Scene& scene, const std::filesystem::path& asset_root,
                                                  const AssetSource* assets);

// The format of a mesh given as bytes: its `format`, else its file's
// extension (before .gz: a gzip file is read inflated).
std::string MeshFormat(const v1::Mesh& mesh);

// The bytes of a mesh given as a `file` under `asset_root` (confined to
// it) or an `asset` in `assets`; throws Error naming `what` when they
// cannot be read.
std::string ReadMeshBytes(const v1::Mesh& mesh, const std::filesystem::path& asset_root, const AssetSource* assets,
                          const std::string& what);

// Whether `text` is a SHA-256 as assets are named: 64 lowercase hex digits.
bool IsSha256(const std::string& text);

// Cheap checks run before a job is accepted; throws Error naming the part.
// With `assets`, every mesh asset the scene names must be held there: a
// job is refused at once rather than failing when it runs.
void ValidateScene(const v1::Scene& scene, const AssetSource* assets = nullptr);

struct SceneSources {
  ComponentSources components;
  const EmbreeDevice& device;
  // Folder that mesh `file` references resolve in; empty: none allowed.
  std::filesystem::path asset_root;
  // Where mesh `asset` references are read; null: none allowed.
  const AssetSource* assets = nullptr;
  // Set when the job stops: building ends early with Error, and the
  // scene's Intersect throws once it is set (KernelScene::StopWhen).
  const std::atomic<bool>* stop = nullptr;
};

std::unique_ptr<KernelScene> BuildScene(const v1::Scene& scene, const SceneSources& sources);

}  // namespace yarf
