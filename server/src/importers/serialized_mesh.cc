#include "importers/serialized_mesh.h"

#include <zlib.h>

#include <cmath>
#include <cstring>

namespace yarf::importers {
namespace {

constexpr uint16_t kMagic = 0x041C;
constexpr uint32_t kHasNormals = 0x0001, kHasTexcoords = 0x0002, kHasColors = 0x0008,
                   kDoublePrecision = 0x2000;
// Larger shapes than this are refused rather than inflated (a zip bomb
// would otherwise exhaust memory).
constexpr uint64_t kMaxInflatedBytes = uint64_t(1) << 32;

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

std::string Inflate(std::string_view compressed, const SourceLocation& where) {
  z_stream stream{};
  if (inflateInit(&stream) != Z_OK) Fail(where, "serialized mesh: cannot start zlib");
  std::string out;
  char buffer[1 << 16];
  stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(compressed.data()));
  stream.avail_in = uInt(std::min<size_t>(compressed.size(), UINT32_MAX));
  int status = Z_OK;
  while (status == Z_OK) {
    stream.next_out = reinterpret_cast<Bytef*>(buffer);
    stream.avail_out = sizeof(buffer);
    status = inflate(&stream, Z_NO_FLUSH);
    out.append(buffer, sizeof(buffer) - stream.avail_out);
    if (out.size() > kMaxInflatedBytes) status = Z_MEM_ERROR;
    if (status == Z_OK && stream.avail_in == 0 && stream.avail_out != 0) status = Z_BUF_ERROR;
  }
  inflateEnd(&stream);
  if (status != Z_STREAM_END) Fail(where, "serialized mesh: corrupt or truncated zlib data");
  return out;
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

  const std::string data = Inflate(bytes.substr(offset + 4), where);
  Reader in(data, where);
  SerializedMesh mesh;
  const uint32_t flags = in.Read<uint32_t>();
  if (version == 4)
    for (char c = in.Read<char>(); c != '\0'; c = in.Read<char>()) mesh.name += c;
  const uint64_t vertices = in.Read<uint64_t>(), triangles = in.Read<uint64_t>();
  const uint64_t real = flags & kDoublePrecision ? 8 : 4;
  // Check sizes against what is there before allocating anything.
  if (vertices > data.size() || triangles > data.size() || vertices > UINT32_MAX)
    Fail(where, "serialized mesh: vertex or triangle count larger than the data");
  in.Need(vertices * 3 * real);
  mesh.positions.reserve(vertices * 3);
  for (uint64_t i = 0; i < vertices * 3; ++i) {
    const double v = real == 8 ? in.Read<double>() : in.Read<float>();
    if (!std::isfinite(v)) Fail(where, "serialized mesh: a vertex position is not finite");
    mesh.positions.push_back(float(v));
  }
  if (flags & kHasNormals) in.Skip(vertices * 3 * real);
  if (flags & kHasTexcoords) in.Skip(vertices * 2 * real);
  if (flags & kHasColors) in.Skip(vertices * 3 * real);
  in.Need(triangles * 3 * 4);
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
