#include "importers/serialized_mesh.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#include "kernel/inflate.h"

namespace yarf::importers {
namespace {

constexpr uint16_t kMagic = 0x041C;
constexpr uint32_t kHasNormals = 0x0001, kHasTexcoords = 0x0002, kHasColors = 0x0008,
                   kDoublePrecision = 0x2000;
// How far one shape's zlib stream may inflate. Only the bytes the shape's
// own counts call for are inflated, so this bounds both the memory and
// the time a small file can cost; a shape needing more is refused before
// any of it is inflated. 1 GiB holds 40 million vertices and 50 million
// triangles at single precision.
constexpr uint64_t kMaxInflatedBytes = uint64_t(1) << 30;
// Deflate never inflates more than 1032 to 1 (a run of 258 bytes per
// two-bit code): counts that need more than that from the bytes present
// cannot be true, and fail without inflating anything.
constexpr uint64_t kMaxDeflateRatio = 1032;
// Version 4 names each shape; longer names are refused.
constexpr size_t kMaxNameBytes = 64 << 10;

template <typename T>
T Load(std::string_view bytes, size_t offset) {
  T value;
  std::memcpy(&value, bytes.data() + offset, sizeof(T));
  return value;  // the format is little-endian, as every machine yarf runs on
}

// Reads fields in order from an inflated buffer, failing on truncation.
class Reader {
 public:
  Reader(std::string_view data, const SourceLocation& where) : data_(data), where_(where) {}

  template <typename T>
  T Read() {
    Need(sizeof(T));
    const T value = Load<T>(data_, offset_);
    offset_ += sizeof(T);
    return value;
  }
  void Skip(uint64_t bytes) {
    Need(bytes);
    offset_ += bytes;
  }
  void Need(uint64_t bytes) const {
    if (bytes > data_.size() - offset_) Fail(where_, "serialized mesh: data ends early");
  }

 private:
  std::string_view data_;
  size_t offset_ = 0;
  const SourceLocation& where_;
};

// The first `limit` bytes the zlib stream `compressed` inflates to (all of
// them when it holds fewer); fails on a damaged stream.
std::string InflateShape(std::string_view compressed, uint64_t limit, const SourceLocation& where) {
  try {
    return Inflate(compressed, limit).bytes;
  } catch (const std::runtime_error& e) {
    Fail(where, std::string("serialized mesh: ") + e.what());
  }
}

// What a shape's data starts with.
struct ShapeHeader {
  uint32_t flags = 0;
  std::string name;
  uint64_t vertices = 0, triangles = 0;
  uint64_t size = 0;  // of the header's bytes
};

ShapeHeader ReadShapeHeader(std::string_view data, uint16_t version, const SourceLocation& where) {
  Reader in(data, where);
  ShapeHeader header;
  header.flags = in.Read<uint32_t>();
  if (version == 4)
    for (char c = in.Read<char>(); c != '\0'; c = in.Read<char>()) {
      if (header.name.size() == kMaxNameBytes)
        Fail(where, "serialized mesh: a shape name longer than " + std::to_string(kMaxNameBytes) + " bytes");
      header.name += c;
    }
  header.vertices = in.Read<uint64_t>();
  header.triangles = in.Read<uint64_t>();
  header.size = 4 + (version == 4 ? header.name.size() + 1 : 0) + 16;
  return header;
}

}  // namespace

SerializedMesh DecodeSerializedMesh(std::string_view bytes, uint64_t shape_index,
                                    const SourceLocation& where) {
  if (bytes.size() < 4 || Load<uint16_t>(bytes, 0) != kMagic)
    Fail(where, "not a Mitsuba serialized mesh file (bad header)");
  const uint16_t version = Load<uint16_t>(bytes, 2);
  if (version != 3 && version != 4)
    Fail(where, "serialized mesh: unsupported format version " + std::to_string(version));

  uint64_t offset = 0;
  if (shape_index > 0) {
    // The end of the file holds the offset of every shape, then their count.
    const uint64_t entry = version == 4 ? 8 : 4;
    if (bytes.size() < 4) Fail(where, "serialized mesh: no shape table");
    const uint32_t count = Load<uint32_t>(bytes, bytes.size() - 4);
    if (shape_index >= count)
      Fail(where, "serialized mesh: shape_index " + std::to_string(shape_index) + " but the file has " +
                      std::to_string(count) + " shape" + (count == 1 ? "" : "s"));
    const uint64_t table = uint64_t(count) * entry + 4;
    if (table > bytes.size()) Fail(where, "serialized mesh: truncated shape table");
    const size_t at = bytes.size() - table + shape_index * entry;
    offset = version == 4 ? Load<uint64_t>(bytes, at) : Load<uint32_t>(bytes, at);
    if (offset > bytes.size() - 4 || Load<uint16_t>(bytes, offset) != kMagic)
      Fail(where, "serialized mesh: bad offset of shape " + std::to_string(shape_index));
  }

  const std::string_view compressed = bytes.substr(offset + 4);
  const ShapeHeader header =
      ReadShapeHeader(InflateShape(compressed, 4 + kMaxNameBytes + 1 + 16, where), version, where);
  const uint64_t vertices = header.vertices, triangles = header.triangles;
  const uint64_t real = header.flags & kDoublePrecision ? 8 : 4;
  // Check the counts against the limits and the bytes present before
  // inflating or allocating anything for them.
  if (vertices > UINT32_MAX || triangles > kMaxInflatedBytes)
    Fail(where, "serialized mesh: " + std::to_string(vertices) + " vertices and " + std::to_string(triangles) +
                    " triangles are more than a shape may hold");
  const uint64_t reals_per_vertex = 3 + (header.flags & kHasNormals ? 3 : 0) +
                                    (header.flags & kHasTexcoords ? 2 : 0) + (header.flags & kHasColors ? 3 : 0);
  const uint64_t size = header.size + vertices * reals_per_vertex * real + triangles * 3 * 4;
  if (size > kMaxInflatedBytes)
    Fail(where, "serialized mesh: the shape's " + std::to_string(vertices) + " vertices and " +
                    std::to_string(triangles) + " triangles need " + std::to_string(size) +
                    " bytes, more than the limit of " + std::to_string(kMaxInflatedBytes));
  if (size > compressed.size() * kMaxDeflateRatio + 64)
    Fail(where, "serialized mesh: the shape declares " + std::to_string(vertices) + " vertices and " +
                    std::to_string(triangles) + " triangles, but its " + std::to_string(compressed.size()) +
                    " bytes of zlib data cannot hold them");
  const std::string data = InflateShape(compressed, size, where);
  if (data.size() < size)
    Fail(where, "serialized mesh: data ends early (" + std::to_string(data.size()) + " of " +
                    std::to_string(size) + " bytes)");
  Reader in(data, where);
  in.Skip(header.size);
  SerializedMesh mesh;
  mesh.name = header.name;
  // Positions, then each optional block in the file's order.
  const auto read_block = [&](std::vector<float>& out, uint64_t per_vertex, const char* what) {
    out.reserve(vertices * per_vertex);
    for (uint64_t i = 0; i < vertices * per_vertex; ++i) {
      const double v = real == 8 ? in.Read<double>() : in.Read<float>();
      // Converting a double beyond float's range is undefined.
      if (!(std::abs(v) <= std::numeric_limits<float>::max()))
        Fail(where, std::string("serialized mesh: a vertex ") + what + " is not finite");
      out.push_back(float(v));
    }
  };
  read_block(mesh.positions, 3, "position");
  if (header.flags & kHasNormals) read_block(mesh.normals, 3, "normal");
  if (header.flags & kHasTexcoords) read_block(mesh.uvs, 2, "texture coordinate");
  if (header.flags & kHasColors) read_block(mesh.colors, 3, "colour");
  mesh.indices.reserve(triangles * 3);
  for (uint64_t i = 0; i < triangles * 3; ++i) {
    const uint32_t index = in.Read<uint32_t>();
    if (index >= vertices) Fail(where, "serialized mesh: a triangle index is out of range");
    mesh.indices.push_back(index);
  }
  if (triangles == 0) Fail(where, "serialized mesh: the shape has no triangles");
  return mesh;
}

}  // namespace yarf::importers
