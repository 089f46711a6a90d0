// Grid files: Mitsuba's binary .vol format and, in builds with OpenVDB,
// OpenVDB's .vdb files, read into a dense VolumeGrid. Which one a file is
// comes from its first bytes, not its name.
//
// A .vol file (Mitsuba 0.6 and 3, little-endian): "VOL", the version byte
// 3, the encoding as int32 (1: float32, the only one either renderer
// reads), the resolution xres, yres, zres and the channel count (1 or 3)
// as int32, a bounding box of 6 float32 (xmin, ymin, zmin, xmax, ymax,
// zmax), then the voxels, x fastest, then y, then z, channels innermost.
//
// A .vdb file: one float or vec3 grid, named, sampled at every voxel of
// its active bounding box (each voxel value exactly, background outside
// the active voxels); the grid's linear index-to-world transform places
// it (VolumeGrid::unit_to_file).
#pragma once

#include <bit>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "volume_grid.h"
#include "yarf/error.h"

#ifdef YARF_HAVE_OPENVDB
// Plugins hide their symbols; OpenVDB's templates must keep the default
// visibility, or initialize() crashes registering grid types that are
// then different types in the plugin and in the library.
#pragma GCC visibility push(default)
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#pragma GCC visibility pop
#endif

namespace yarf {

inline VolumeGrid ReadVolFile(const std::filesystem::path& path, const std::string& what) {
  static_assert(std::endian::native == std::endian::little, ".vol files are little-endian");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(what + ": cannot open grid file '" + path.string() + "'");
  std::error_code error;
  const uint64_t file_size = std::filesystem::file_size(path, error);
  if (error) throw Error(what + ": cannot read grid file '" + path.string() + "': " + error.message());
  constexpr uint64_t kHeader = 48;
  char header[kHeader];
  if (file_size < kHeader || !in.read(header, kHeader))
    throw Error(what + ": '" + path.string() + "' is truncated: a .vol header has 48 bytes");
  if (std::memcmp(header, "VOL", 3) != 0) throw Error(what + ": '" + path.string() + "' is not a .vol grid file");
  if (header[3] != 3)
    throw Error(what + ": '" + path.string() + "' is a .vol file of version " + std::to_string(int(header[3])) +
                "; only version 3 is read");
  int32_t ints[5];
  std::memcpy(ints, header + 4, sizeof ints);
  if (ints[0] != 1)
    throw Error(what + ": '" + path.string() + "' has .vol encoding " + std::to_string(ints[0]) +
                "; only 1 (float32) is read");
  VolumeGrid grid;
  const uint64_t voxels = GridVoxelCount(ints[1], ints[2], ints[3], what + ": '" + path.string() + "'");
  grid.nx = ints[1];
  grid.ny = ints[2];
  grid.nz = ints[3];
  if (ints[4] != 1 && ints[4] != 3)
    throw Error(what + ": '" + path.string() + "' has " + std::to_string(ints[4]) +
                " channels; a grid has 1 or 3");
  grid.channels = ints[4];
  float box[6];
  std::memcpy(box, header + 24, sizeof box);
  bool box_usable = true;
  for (int a = 0; a < 3; ++a)
    box_usable = box_usable && std::isfinite(box[a]) && std::isfinite(box[a + 3]) && box[a] < box[a + 3];
  if (box_usable) {
    for (int a = 0; a < 3; ++a) {
      grid.unit_to_file.m[5 * a] = double(box[a + 3]) - double(box[a]);
      grid.unit_to_file.m[4 * a + 3] = box[a];
    }
    grid.has_placement = true;
  }
  const uint64_t bytes = voxels * uint64_t(grid.channels) * sizeof(float);
  if (file_size < kHeader + bytes)
    throw Error(what + ": '" + path.string() + "' is truncated: " + std::to_string(grid.nx) + " x " +
                std::to_string(grid.ny) + " x " + std::to_string(grid.nz) + " voxels of " +
                std::to_string(grid.channels) + " channel(s) need " + std::to_string(kHeader + bytes) +
                " bytes, the file has " + std::to_string(file_size));
  if (file_size > kHeader + bytes)
    throw Error(what + ": '" + path.string() + "' has " + std::to_string(file_size - kHeader - bytes) +
                " bytes more than its header announces");
  grid.values.resize(voxels * uint64_t(grid.channels));
  if (!in.read(reinterpret_cast<char*>(grid.values.data()), std::streamsize(bytes)))
    throw Error(what + ": cannot read the voxels of '" + path.string() + "'");
  return grid;
}

#ifdef YARF_HAVE_OPENVDB
namespace vdb_detail {

template <typename GridType>
void Sample(const GridType& source, const openvdb::CoordBBox& box, VolumeGrid& grid) {
  const auto accessor = source.getConstAccessor();
  size_t i = 0;
  for (int z = box.min().z(); z <= box.max().z(); ++z)
    for (int y = box.min().y(); y <= box.max().y(); ++y)
      for (int x = box.min().x(); x <= box.max().x(); ++x) {
        const auto value = accessor.getValue(openvdb::Coord(x, y, z));
        if constexpr (std::is_same_v<typename GridType::ValueType, float>) {
          grid.values[i++] = value;
        } else {
          for (int c = 0; c < 3; ++c) grid.values[i++] = float(value[c]);
        }
      }
}

}  // namespace vdb_detail
#endif

inline VolumeGrid ReadVdbFile(const std::filesystem::path& path, const std::string& grid_name,
                              const std::string& what) {
#ifdef YARF_HAVE_OPENVDB
  const std::string where = what + ": '" + path.string() + "'";
  openvdb::GridBase::Ptr base;
  try {
    openvdb::initialize();
    openvdb::io::File file(path.string());
    file.open(false);
    if (!file.hasGrid(grid_name)) {
      std::string names;
      for (auto it = file.beginName(); it != file.endName(); ++it) names += (names.empty() ? "" : ", ") + *it;
      throw Error(where + " has no grid named '" + grid_name + "' (it has: " + (names.empty() ? "none" : names) +
                  ")");
    }
    base = file.readGrid(grid_name);
    file.close();
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw Error(where + " is not a readable OpenVDB file: " + e.what());
  }
  const bool is_float = base->isType<openvdb::FloatGrid>(), is_vec3 = base->isType<openvdb::Vec3SGrid>();
  if (!is_float && !is_vec3)
    throw Error(where + ": grid '" + grid_name + "' holds " + base->valueType() +
                " values; a float or vec3s grid is read");
  if (!base->transform().isLinear())
    throw Error(where + ": grid '" + grid_name + "' has a frustum transform; only linear ones are read");
  const openvdb::CoordBBox box = base->evalActiveVoxelBoundingBox();
  if (box.empty()) throw Error(where + ": grid '" + grid_name + "' has no active voxels");
  const openvdb::Coord dim = box.dim();
  VolumeGrid grid;
  const uint64_t voxels = GridVoxelCount(dim.x(), dim.y(), dim.z(), where + ": grid '" + grid_name + "'");
  grid.nx = dim.x();
  grid.ny = dim.y();
  grid.nz = dim.z();
  grid.channels = is_float ? 1 : 3;
  grid.values.resize(voxels * uint64_t(grid.channels));
  if (is_float)
    vdb_detail::Sample(*openvdb::gridConstPtrCast<openvdb::FloatGrid>(base), box, grid);
  else
    vdb_detail::Sample(*openvdb::gridConstPtrCast<openvdb::Vec3SGrid>(base), box, grid);
  // Voxel centres sit at integer index coordinates: the unit cube spans
  // the index box [min − ½, max + ½], which the grid's transform places.
  const openvdb::Vec3d corner = box.min().asVec3d() - openvdb::Vec3d(0.5);
  const openvdb::Vec3d origin = base->transform().indexToWorld(corner);
  for (int a = 0; a < 3; ++a) {
    openvdb::Vec3d step(0.0);
    step[a] = dim[a];
    const openvdb::Vec3d axis = base->transform().indexToWorld(corner + step) - origin;
    for (int r = 0; r < 3; ++r) grid.unit_to_file.m[4 * r + a] = axis[r];
  }
  for (int r = 0; r < 3; ++r) grid.unit_to_file.m[4 * r + 3] = origin[r];
  grid.has_placement = true;
  return grid;
#else
  throw Error(what + ": '" + path.string() + "' is an OpenVDB file; OpenVDB files are not supported by this build");
#endif
}

// The grid in `path`, a .vol or .vdb file (by its first bytes);
// `grid_name` picks an OpenVDB file's grid.
inline VolumeGrid ReadGridFile(const std::filesystem::path& path, const std::string& grid_name,
                               const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(what + ": cannot open grid file '" + path.string() + "'");
  unsigned char magic[4] = {0, 0, 0, 0};
  in.read(reinterpret_cast<char*>(magic), 4);
  in.close();
  if (std::memcmp(magic, "VOL", 3) == 0) return ReadVolFile(path, what);
  // OpenVDB's magic number 0x56444220, little-endian.
  if (magic[0] == 0x20 && magic[1] == 0x42 && magic[2] == 0x44 && magic[3] == 0x56)
    return ReadVdbFile(path, grid_name, what);
  throw Error(what + ": '" + path.string() + "' is neither a .vol grid nor an OpenVDB file");
}

}  // namespace yarf
