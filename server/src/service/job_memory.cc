#include "service/job_memory.h"

#include <unistd.h>

#include <system_error>

namespace yarf {
namespace {

// Per pixel: the film's double accumulators (88 bytes), splat images
// (72), a float snapshot with variances (24), the checkpoint's bytes (88)
// and slack for the filter's scratch.
constexpr uint64_t kBytesPerPixel = 320;
// A mesh file's bytes, parsed into positions and indices and then into
// Embree's BVH, take up to this many times their size.
constexpr uint64_t kMeshExpansion = 4;
// Inline positions and indices: 4 bytes each, copied into the kernel and
// the BVH.
constexpr uint64_t kInlineExpansion = 4;
constexpr uint64_t kBytesPerPlacement = 512;

uint64_t FileSize(const std::filesystem::path& path) {
  std::error_code error;
  const uintmax_t size = std::filesystem::file_size(path, error);
  return error ? 0 : uint64_t(size);
}

uint64_t MeshBytes(const v1::Mesh& mesh, const AssetStore* assets, const std::filesystem::path& asset_root) {
  switch (mesh.source_case()) {
    case v1::Mesh::kData:
      return mesh.data().size() * kMeshExpansion;
    case v1::Mesh::kAsset:
      return assets && assets->Has(mesh.asset()) ? FileSize(assets->PathOf(mesh.asset())) * kMeshExpansion : 0;
    case v1::Mesh::kFile:
      // Confinement to the root is checked when the file is read.
      return asset_root.empty() ? 0 : FileSize(asset_root / mesh.file()) * kMeshExpansion;
    default:
      return uint64_t(mesh.positions_size() + mesh.indices_size()) * 4 * kInlineExpansion;
  }
}

uint64_t ShapesBytes(const google::protobuf::RepeatedPtrField<v1::SceneShape>& shapes, const AssetStore* assets,
                     const std::filesystem::path& asset_root) {
  uint64_t bytes = 0;
  for (const v1::SceneShape& shape : shapes)
    if (shape.has_mesh()) bytes += MeshBytes(shape.mesh(), assets, asset_root);
  return bytes;
}

}  // namespace

uint64_t EstimateJobBytes(const v1::SubmitRequest& request, const AssetStore* assets,
                          const std::filesystem::path& asset_root) {
  const v1::Scene& scene = request.scene();
  uint64_t bytes = uint64_t(scene.film().width()) * scene.film().height() * kBytesPerPixel;
  bytes += ShapesBytes(scene.shapes(), assets, asset_root);
  for (const v1::Group& group : scene.groups()) bytes += ShapesBytes(group.shapes(), assets, asset_root);
  bytes += uint64_t(scene.instances_size()) * kBytesPerPlacement;
  // The request itself, kept with the job.
  return bytes + request.ByteSizeLong();
}

uint64_t DefaultMaxJobBytes() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  return pages > 0 && page > 0 ? uint64_t(pages) * uint64_t(page) / 2 : uint64_t(8) << 30;
}

}  // namespace yarf
