#include "kernel/mesh_io.h"

#include <tiny_obj_loader.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <span>
#include <sstream>

#include "yarf/error.h"

namespace yarf {
namespace {

// The lines of an OBJ file that make a mesh: `v` and `f` (tested as
// tinyobjloader tests them). Everything else is dropped before parsing:
// tinyobjloader allocates up to 8192 values for a `t` line of twenty
// bytes, converts out-of-range `vw` weights with undefined behaviour, and
// keeps normals, texture coordinates and groups yarf does not use.
struct ObjGeometry {
  std::string text;
  uint64_t vertices = 0, faces = 0, face_vertices = 0;
};

ObjGeometry ObjGeometryLines(std::string_view bytes) {
  ObjGeometry geometry;
  size_t at = 0;
  while (at < bytes.size()) {
    const size_t end = std::min(bytes.find_first_of("\r\n", at), bytes.size());
    std::string_view line = bytes.substr(at, end - at);
    at = end + 1;
    const size_t first = line.find_first_not_of(" \t");
    if (first == std::string_view::npos || line.size() - first < 2) continue;
    line.remove_prefix(first);
    if ((line[0] != 'v' && line[0] != 'f') || (line[1] != ' ' && line[1] != '\t')) continue;
    if (line[0] == 'v') {
      ++geometry.vertices;
    } else {
      ++geometry.faces;
      for (size_t k = 1; k < line.size(); ++k)
        if ((line[k - 1] == ' ' || line[k - 1] == '\t') && line[k] != ' ' && line[k] != '\t') ++geometry.face_vertices;
    }
    geometry.text.append(line).push_back('\n');
  }
  return geometry;
}

// tinyobjloader's memory for what it parses, in bytes: a vertex as
// positions and colours; a face vertex as its parsed triple (twice,
// counting vector growth), the copy made when its face is stored and the
// exported index; a face as its vector and per-face arrays. A small file
// of many short faces can need forty times its size, so the estimate is
// checked before parsing.
constexpr uint64_t kObjBytesPerVertex = 40, kObjBytesPerFaceVertex = 64, kObjBytesPerFace = 96;
constexpr uint64_t kMaxObjParseBytes = uint64_t(16) << 30;

std::string FirstLine(const std::string& text) { return text.substr(0, std::min(text.find('\n'), size_t(1024))); }

// tinyobjloader keeps a face's vertex count in a byte, so larger faces
// cannot be told apart: they are refused (see the sum check below).
constexpr size_t kMaxObjFaceVertices = 255;

// Triangles as they are; quads split along their shorter diagonal (as
// tinyobjloader does); larger polygons as a fan. tinyobjloader's own
// triangulation of n-gons (ear clipping) takes time cubic in n.
void AppendFace(std::span<const uint32_t> face, const std::vector<Vec3>& positions, std::vector<uint32_t>& out) {
  if (face.size() == 4) {
    const Vec3 d02 = positions[face[2]] - positions[face[0]], d13 = positions[face[3]] - positions[face[1]];
    if (Dot(d02, d02) < Dot(d13, d13))
      out.insert(out.end(), {face[0], face[1], face[2], face[0], face[2], face[3]});
    else
      out.insert(out.end(), {face[0], face[1], face[3], face[1], face[2], face[3]});
    return;
  }
  for (size_t k = 1; k + 1 < face.size(); ++k) out.insert(out.end(), {face[0], face[k], face[k + 1]});
}

TriangleMesh ParseObj(std::string_view bytes, const std::string& name) {
  ObjGeometry geometry = ObjGeometryLines(bytes);
  const uint64_t parse_bytes = geometry.vertices * kObjBytesPerVertex +
                               geometry.face_vertices * kObjBytesPerFaceVertex + geometry.faces * kObjBytesPerFace;
  if (parse_bytes > kMaxObjParseBytes)
    throw Error("mesh '" + name + "': OBJ file too large to parse (" + std::to_string(geometry.vertices) +
                " vertices, " + std::to_string(geometry.faces) + " faces would need about " +
                std::to_string(parse_bytes >> 20) + " MiB; at most " + std::to_string(kMaxObjParseBytes >> 20) +
                "; a binary PLY file needs far less)");
  std::istringstream stream(std::move(geometry.text));
  tinyobj::attrib_t attrib;
  std::vector<tinyobj::shape_t> shapes;
  std::vector<tinyobj::material_t> materials;
  std::string warning, error;
  // No material reader: `mtllib` lines never open files.
  if (!tinyobj::LoadObj(&attrib, &shapes, &materials, &warning, &error, &stream, nullptr,
                        /*triangulate=*/false, /*default_vcols_fallback=*/false))
    throw Error("mesh '" + name + "': not a valid OBJ file: " + FirstLine(error));
  TriangleMesh mesh;
  mesh.positions.reserve(attrib.vertices.size() / 3);
  for (size_t i = 0; i + 2 < attrib.vertices.size(); i += 3)
    mesh.positions.emplace_back(attrib.vertices[i], attrib.vertices[i + 1], attrib.vertices[i + 2]);
  std::vector<uint32_t> face;
  for (const auto& shape : shapes) {
    const auto& indices = shape.mesh.indices;
    size_t next = 0;
    for (const unsigned char count : shape.mesh.num_face_vertices) {
      // A face of more than 255 vertices has its count cut to a byte.
      if (count < 3 || count > indices.size() - next)
        throw Error("mesh '" + name + "': a face has more than " + std::to_string(kMaxObjFaceVertices) +
                    " vertices");
      face.clear();
      for (size_t k = 0; k < count; ++k) {
        const int index = indices[next + k].vertex_index;
        if (index < 0 || size_t(index) >= mesh.positions.size())
          throw Error("mesh '" + name + "': face vertex index " + std::to_string(int64_t(index) + 1) +
                      " out of range (" + std::to_string(mesh.positions.size()) + " vertices)");
        face.push_back(uint32_t(index));
      }
      next += count;
      AppendFace(face, mesh.positions, mesh.indices);
    }
    if (next != indices.size())
      throw Error("mesh '" + name + "': a face has more than " + std::to_string(kMaxObjFaceVertices) + " vertices");
  }
  if (mesh.indices.empty()) throw Error("mesh '" + name + "': OBJ file has no faces");
  return mesh;
}

// A PLY reader for the subset meshes use: vertex elements with x, y, z and
// face elements with a vertex index list; other elements and properties
// are skipped. ASCII and both binary byte orders.
//
// The header's counts are untrusted: before an element is read, its count
// is checked against the bytes that follow (every entry takes at least a
// known number of them), so a short file with a huge count fails at once
// instead of allocating or looping for it, and every entry read consumes
// bytes.
class PlyReader {
 public:
  PlyReader(std::string_view bytes, const std::string& name) : bytes_(bytes), name_(name) {}

  TriangleMesh Read() {
    ReadHeader();
    TriangleMesh mesh;
    for (const Element& element : elements_) {
      // Entries without properties take no bytes and carry nothing.
      if (element.properties.empty()) continue;
      const uint64_t remaining = bytes_.size() - pos_;
      const uint64_t least = MinimumEntryBytes(element);
      // The last ASCII value may lack its trailing separator.
      const uint64_t slack = encoding_ == Encoding::kAscii ? 1 : 0;
      if (element.count > (remaining + slack) / least)
        Fail("element '" + element.name + "' declares " + std::to_string(element.count) +
             " entries but only " + std::to_string(remaining) + " bytes follow");
      const bool is_vertex = element.name == "vertex", is_face = element.name == "face";
      // Safe after the check: at most one position per `least` bytes.
      if (is_vertex) mesh.positions.reserve(mesh.positions.size() + element.count);
      for (uint64_t i = 0; i < element.count; ++i) {
        float xyz[3] = {0, 0, 0};
        for (const Property& p : element.properties) {
          if (p.is_list) {
            const double n = ReadNumber(p.count_type);
            if (!(n >= 0 && n <= kMaxPolygonVertices) || n != std::floor(n))
              Fail("a list of element '" + element.name + "' has " + FormatNumber(n) + " entries (at most " +
                   std::to_string(kMaxPolygonVertices) + ")");
            const bool indices = is_face && p.is_vertex_indices;
            indices_.clear();
            for (int k = 0; k < int(n); ++k) {
              const double v = ReadNumber(p.type);
              if (!indices) continue;
              if (!(v >= 0 && v < 4294967296.0) || v != std::floor(v))
                Fail("face vertex index " + FormatNumber(v) + " is not an index");
              indices_.push_back(uint32_t(v));
            }
            for (size_t k = 1; k + 1 < indices_.size(); ++k)
              mesh.indices.insert(mesh.indices.end(), {indices_[0], indices_[k], indices_[k + 1]});
          } else {
            const double v = ReadNumber(p.type);
            if (is_vertex && p.axis >= 0) {
              // Converting a double beyond float's range is undefined.
              if (!(std::abs(v) <= std::numeric_limits<float>::max())) Fail("non-finite vertex position");
              xyz[p.axis] = float(v);
            }
          }
        }
        if (is_vertex) mesh.positions.emplace_back(xyz[0], xyz[1], xyz[2]);
      }
    }
    if (mesh.indices.empty()) Fail("no faces");
    return mesh;
  }

 private:
  enum class Encoding { kAscii, kLittle, kBig };
  static constexpr int kMaxPolygonVertices = 1024;
  struct Property {
    std::string name, type, count_type;
    bool is_list = false;
    bool is_vertex_indices = false;
    int axis = -1;  // 0, 1, 2 for x, y, z
  };
  struct Element {
    std::string name;
    uint64_t count = 0;
    std::vector<Property> properties;
  };

  [[noreturn]] void Fail(const std::string& why) const {
    throw Error("mesh '" + name_ + "': not a valid PLY file: " + why);
  }

  static std::string FormatNumber(double v) {
    std::ostringstream out;
    out << v;
    return out.str();
  }

  // The fewest bytes one entry of `element` can take.
  uint64_t MinimumEntryBytes(const Element& element) const {
    uint64_t least = 0;
    for (const Property& p : element.properties) {
      if (encoding_ == Encoding::kAscii) least += 2;  // a digit and a separator
      else least += p.is_list ? SizeOf(p.count_type) : SizeOf(p.type);
    }
    return least;
  }

  void ReadHeader() {
    if (bytes_.substr(0, 4) != "ply\n" && bytes_.substr(0, 5) != "ply\r\n") Fail("missing header");
    bool has_format = false;
    size_t at = 0;
    for (;;) {
      const size_t end = bytes_.find('\n', at);
      if (end == std::string_view::npos) Fail("truncated header (no end_header line)");
      std::istringstream words{std::string(bytes_.substr(at, end - at))};
      at = end + 1;
      std::string keyword;
      words >> keyword;
      if (keyword == "end_header") break;
      if (keyword == "format") {
        std::string kind;
        words >> kind;
        if (kind == "ascii") encoding_ = Encoding::kAscii;
        else if (kind == "binary_little_endian") encoding_ = Encoding::kLittle;
        else if (kind == "binary_big_endian") encoding_ = Encoding::kBig;
        else Fail("unknown format '" + kind + "'");
        has_format = true;
      } else if (keyword == "element") {
        Element e;
        std::string count;
        words >> e.name >> count;
        const auto [end_of_count, error] = std::from_chars(count.data(), count.data() + count.size(), e.count);
        if (!words || error != std::errc() || end_of_count != count.data() + count.size())
          Fail("bad element line (expected `element NAME COUNT`)");
        elements_.push_back(e);
      } else if (keyword == "property") {
        if (elements_.empty()) Fail("property before element");
        Element& element = elements_.back();
        Property p;
        words >> p.type;
        if (p.type == "list") {
          p.is_list = true;
          words >> p.count_type >> p.type;
        }
        words >> p.name;
        if (!words) Fail("bad property line");
        if (SizeOf(p.type) == 0) Fail("property '" + p.name + "' has unknown type '" + p.type + "'");
        if (p.is_list && !IsInteger(p.count_type))
          Fail("list property '" + p.name + "' has count type '" + p.count_type + "' (an integer type is needed)");
        p.is_vertex_indices = p.is_list && (p.name == "vertex_indices" || p.name == "vertex_index");
        if (p.is_vertex_indices && !IsInteger(p.type))
          Fail("list property '" + p.name + "' has index type '" + p.type + "' (an integer type is needed)");
        if (!p.is_list && p.name.size() == 1 && p.name[0] >= 'x' && p.name[0] <= 'z') p.axis = p.name[0] - 'x';
        element.properties.push_back(p);
      }
    }
    if (!has_format) Fail("no format line");
    for (const Element& e : elements_) {
      if (e.name != "vertex" || e.count == 0) continue;
      bool axes[3] = {false, false, false};
      for (const Property& p : e.properties)
        if (p.axis >= 0) axes[p.axis] = true;
      if (!axes[0] || !axes[1] || !axes[2]) Fail("element 'vertex' lacks an x, y or z property");
    }
    pos_ = at;
  }

  static size_t SizeOf(const std::string& type) {
    if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
    if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
    if (type == "int" || type == "uint" || type == "float" || type == "int32" ||
        type == "uint32" || type == "float32")
      return 4;
    if (type == "double" || type == "float64") return 8;
    return 0;
  }

  static bool IsInteger(const std::string& type) {
    return SizeOf(type) != 0 && type != "float" && type != "float32" && type != "double" && type != "float64";
  }

  double ReadNumber(const std::string& type) {
    if (encoding_ == Encoding::kAscii) {
      while (pos_ < bytes_.size() && std::isspace(static_cast<unsigned char>(bytes_[pos_]))) ++pos_;
      size_t start = pos_;
      while (pos_ < bytes_.size() && !std::isspace(static_cast<unsigned char>(bytes_[pos_]))) ++pos_;
      if (start == pos_) Fail("unexpected end of data");
      if (bytes_[start] == '+') ++start;  // from_chars takes no plus sign
      double value = 0;
      const auto [end, error] = std::from_chars(bytes_.data() + start, bytes_.data() + pos_, value);
      if (error != std::errc() || end != bytes_.data() + pos_)
        Fail("bad number '" + std::string(bytes_.substr(start, std::min<size_t>(pos_ - start, 32))) + "'");
      return value;
    }
    const size_t size = SizeOf(type);
    if (size > bytes_.size() - pos_) Fail("unexpected end of data");
    unsigned char raw[8];
    std::memcpy(raw, bytes_.data() + pos_, size);
    pos_ += size;
    if (encoding_ == Encoding::kBig) std::reverse(raw, raw + size);
    auto as = [&]<typename T>() { T v; std::memcpy(&v, raw, sizeof(T)); return double(v); };
    if (type == "char" || type == "int8") return as.operator()<int8_t>();
    if (type == "uchar" || type == "uint8") return as.operator()<uint8_t>();
    if (type == "short" || type == "int16") return as.operator()<int16_t>();
    if (type == "ushort" || type == "uint16") return as.operator()<uint16_t>();
    if (type == "int" || type == "int32") return as.operator()<int32_t>();
    if (type == "uint" || type == "uint32") return as.operator()<uint32_t>();
    if (type == "float" || type == "float32") return as.operator()<float>();
    return as.operator()<double>();
  }

  std::string_view bytes_;
  std::string name_;
  Encoding encoding_ = Encoding::kAscii;
  std::vector<Element> elements_;
  std::vector<uint32_t> indices_;
  size_t pos_ = 0;
};

}  // namespace

TriangleMesh ParseMesh(std::string_view bytes, std::string_view format, const std::string& name) {
  TriangleMesh mesh;
  if (format == "obj") mesh = ParseObj(bytes, name);
  else if (format == "ply") mesh = PlyReader(bytes, name).Read();
  else throw Error("mesh '" + name + "': unknown format '" + std::string(format) + "' (obj or ply)");
  ValidateMesh(mesh, name);
  return mesh;
}

void ValidateMesh(const TriangleMesh& mesh, const std::string& name) {
  if (mesh.indices.size() % 3 != 0)
    throw Error("mesh '" + name + "': index count is not a multiple of 3");
  for (uint32_t i : mesh.indices)
    if (i >= mesh.positions.size())
      throw Error("mesh '" + name + "': index " + std::to_string(i) + " out of range (" +
                  std::to_string(mesh.positions.size()) + " vertices)");
  for (const Vec3& p : mesh.positions)
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw Error("mesh '" + name + "': non-finite vertex position");
}

}  // namespace yarf
