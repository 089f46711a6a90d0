#include "service/job_memory.h"

#include <unistd.h>

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <functional>
#include <map>
#include <string>
#include <system_error>

#include "components/scene_builder.h"
#include "kernel/mesh_io.h"
#include "yarf/error.h"

namespace yarf {
namespace {

// Per pixel: the film's double accumulators (88 bytes), splat images
// (72), a float snapshot with variances (24), the checkpoint's bytes (88)
// and slack for the filter's scratch.
constexpr uint64_t kBytesPerPixel = 320;
// A mesh's memory in the kernel and in Embree's BVH (the build's
// primitive references included), per vertex (position, normal, uv) and
// per triangle. Measured: 5.06 M triangles of 255-vertex fans peaked at
// 693 MB read from a binary PLY, 869 MB from an OBJ.
constexpr uint64_t kBytesPerVertex = 64;
constexpr uint64_t kBytesPerTriangle = 192;
// Each placement of a group copies the records of the group's shapes
// (two transforms, a name, a look) and adds an Embree instance.
constexpr uint64_t kBytesPerPlacement = 512;
constexpr uint64_t kBytesPerPlacedShape = 400;
// Counts stop growing here: far past any limit, and never overflowing.
constexpr uint64_t kSaturated = uint64_t(1) << 50;

uint64_t Saturating(uint64_t a, uint64_t b) { return std::min(a + b, kSaturated); }
uint64_t Saturating(uint64_t a, uint64_t b, uint64_t factor) {
  a = std::min(a, kSaturated);
  return factor != 0 && b > (kSaturated - a) / factor ? kSaturated : a + b * factor;
}

// Placements and placed shape records nested instancing expands to (the
// scene is checked already: groups exist, no cycles, bounded depth).
struct Expansion {
  uint64_t placements = 0, shapes = 0;
};

Expansion Expand(const v1::Scene& scene) {
  std::map<std::string, const v1::Group*> groups;
  for (const v1::Group& group : scene.groups()) groups.emplace(group.name(), &group);
  std::map<std::string, Expansion> memo;
  std::function<Expansion(const std::string&)> expand = [&](const std::string& name) {
    if (auto it = memo.find(name); it != memo.end()) return it->second;
    const auto group = groups.find(name);
    Expansion out{1, 0};
    if (group == groups.end()) return out;
    out.shapes = uint64_t(group->second->shapes_size());
    for (const v1::Instance& child : group->second->instances()) {
      const Expansion inner = expand(child.group());
      out.placements = Saturating(out.placements, inner.placements);
      out.shapes = Saturating(out.shapes, inner.shapes);
    }
    return memo[name] = out;
  };
  Expansion total;
  for (const v1::Instance& instance : scene.instances()) {
    const Expansion placed = expand(instance.group());
    total.placements = Saturating(total.placements, placed.placements);
    total.shapes = Saturating(total.shapes, placed.shapes);
  }
  return total;
}

// The reader's memory is freed before the BVH is built: the peak is the
// larger of the two.
uint64_t CountedMeshBytes(const MeshCounts& counts) {
  const uint64_t built = Saturating(Saturating(0, counts.vertices, kBytesPerVertex), counts.triangles,
                                    kBytesPerTriangle);
  return Saturating(std::max(counts.parse_bytes, built), counts.attribute_values, sizeof(float));
}

// Mesh files are counted, not sized: an OBJ or PLY of long fans makes a
// triangle every byte or two. A file that cannot be read or counted counts
// its size: the build refuses it, naming it. Past `limit` nothing more is
// read or inflated: the job is refused anyway.
uint64_t FileMeshBytes(std::string_view bytes, const std::string& format, uint64_t limit) {
  try {
    return Saturating(bytes.size(), CountedMeshBytes(CountMesh(bytes, format, "", limit)));
  } catch (const Error&) {
    return bytes.size();
  }
}

uint64_t FileSize(const std::filesystem::path& path) {
  std::error_code error;
  const uintmax_t size = std::filesystem::file_size(path, error);
  return error ? 0 : uint64_t(size);
}

uint64_t MeshBytes(const v1::Mesh& mesh, const AssetStore* assets, const std::filesystem::path& asset_root,
                   uint64_t limit) {
  switch (mesh.source_case()) {
    case v1::Mesh::kData:
      return FileMeshBytes(mesh.data(), mesh.format(), limit);
    case v1::Mesh::kAsset:
    case v1::Mesh::kFile: {
      const uint64_t size = mesh.source_case() == v1::Mesh::kAsset
                                ? (assets && assets->Has(mesh.asset()) ? FileSize(assets->PathOf(mesh.asset())) : 0)
                                : (asset_root.empty() ? 0 : FileSize(asset_root / mesh.file()));
      if (size > limit) return size;
      try {
        return FileMeshBytes(ReadMeshBytes(mesh, asset_root, assets, ""), MeshFormat(mesh), limit);
      } catch (const Error&) {
        return 0;  // not held, or outside the folder: the build refuses it
      }
    }
    default:
      return CountedMeshBytes({.vertices = uint64_t(mesh.positions_size() / 3),
                               .triangles = uint64_t(mesh.indices_size() / 3)});
  }
}

uint64_t ShapesBytes(const google::protobuf::RepeatedPtrField<v1::SceneShape>& shapes, const AssetStore* assets,
                     const std::filesystem::path& asset_root, uint64_t limit) {
  uint64_t bytes = 0;
  for (const v1::SceneShape& shape : shapes) {
    if (shape.has_mesh()) bytes = Saturating(bytes, MeshBytes(shape.mesh(), assets, asset_root, limit));
    // A curve's control point counted as a vertex, its segment (a BVH
    // reference and leaf) as a triangle.
    if (shape.has_curves())
      bytes = Saturating(bytes, CountedMeshBytes({.vertices = uint64_t(shape.curves().points_size() / 4),
                                                  .triangles = uint64_t(shape.curves().segments_size())}));
  }
  return bytes;
}

// A file a component decodes (a texture's or an environment map's image,
// a medium's OpenVDB grid, which OpenImageIO reads as a volume): its
// texels or voxels as floats, grey or RGB, from its header alone. A file
// OpenImageIO cannot read counts 0 here.
uint64_t DecodedImageBytes(const std::filesystem::path& file) {
  const auto input = OIIO::ImageInput::open(file.string());
  if (!input) {
    OIIO::geterror();  // clears the message the failed open left
    return 0;
  }
  const OIIO::ImageSpec& spec = input->spec();
  const uint64_t channels = spec.nchannels >= 3 ? 3 : 1;
  return uint64_t(std::max(spec.width, 0)) * uint64_t(std::max(spec.height, 0)) *
         uint64_t(std::max(spec.depth, 1)) * channels * sizeof(float);
}

// Every component that names a file decodes its own copy of it: eight
// textures of one 8192² image are eight of them.
uint64_t ComponentImageBytes(const v1::Scene& scene, const AssetStore* assets,
                             const std::filesystem::path& asset_root) {
  std::map<std::filesystem::path, uint64_t> decoded;
  uint64_t bytes = 0;
  for (const std::filesystem::path& file : ComponentFiles(scene, asset_root, assets)) {
    const auto [it, added] = decoded.try_emplace(file, 0);
    if (added) it->second = DecodedImageBytes(file);
    bytes = Saturating(bytes, it->second);
  }
  return bytes;
}

}  // namespace

uint64_t EstimateJobBytes(const v1::SubmitRequest& request, const AssetStore* assets,
                          const std::filesystem::path& asset_root, uint64_t limit) {
  const v1::Scene& scene = request.scene();
  uint64_t bytes = uint64_t(scene.film().width()) * scene.film().height() * kBytesPerPixel;
  bytes = Saturating(bytes, ShapesBytes(scene.shapes(), assets, asset_root, limit));
  for (const v1::Group& group : scene.groups())
    bytes = Saturating(bytes, ShapesBytes(group.shapes(), assets, asset_root, limit));
  const Expansion placed = Expand(scene);
  bytes = Saturating(bytes, placed.placements, kBytesPerPlacement);
  bytes = Saturating(bytes, placed.shapes, kBytesPerPlacedShape);
  bytes = Saturating(bytes, ComponentImageBytes(scene, assets, asset_root));
  // The request itself, kept with the job.
  return bytes + request.ByteSizeLong();
}

uint64_t DefaultMaxJobBytes() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  return pages > 0 && page > 0 ? uint64_t(pages) * uint64_t(page) / 2 : uint64_t(8) << 30;
}

}  // namespace yarf
