#include "kernel/mesh_io.h"

#include <tiny_obj_loader.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <span>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

#include "kernel/inflate.h"
#include "yarf/error.h"

namespace yarf {
namespace {

// The lines of an OBJ file that make a mesh: `v`, `vt`, `vn` and `f`
// (tested as tinyobjloader tests them). Everything else is dropped before
// parsing: tinyobjloader allocates up to 8192 values for a `t` line of
// twenty bytes, converts out-of-range `vw` weights with undefined
// behaviour, and keeps groups and materials yarf does not use.
struct ObjGeometry {
  // `vertices` counts `v`, `vt` and `vn` lines; `corner_data` the last two.
  uint64_t vertices = 0, corner_data = 0, faces = 0, face_vertices = 0;

  // tinyobjloader's memory for what it parses.
  uint64_t ParseBytes() const;
};

// Whether a `v`, `vt` or `vn` line has a word where a number goes
// ("nan", "inf"): tinyobjloader reads it as 0, silently.
bool HasWordForNumber(std::string_view line) {
  for (size_t k = line.find_first_of(" \t"); k < line.size(); ++k) {
    if (line[k] == ' ' || line[k] == '\t') continue;
    const size_t digit = line[k] == '+' || line[k] == '-' ? k + 1 : k;
    if (digit < line.size() && std::isalpha(static_cast<unsigned char>(line[digit]))) return true;
    k = std::min(line.find_first_of(" \t", k), line.size());
  }
  return false;
}

// Counts the lines; with `text`, appends them to it.
ObjGeometry ObjGeometryLines(std::string_view bytes, const std::string& name, std::string* text) {
  ObjGeometry geometry;
  size_t at = 0;
  while (at < bytes.size()) {
    const size_t end = std::min(bytes.find_first_of("\r\n", at), bytes.size());
    std::string_view line = bytes.substr(at, end - at);
    at = end + 1;
    const size_t first = line.find_first_not_of(" \t");
    if (first == std::string_view::npos || line.size() - first < 2) continue;
    line.remove_prefix(first);
    const bool attribute = line.size() > 2 && line[0] == 'v' && (line[1] == 't' || line[1] == 'n') &&
                           (line[2] == ' ' || line[2] == '\t');
    if (!attribute && ((line[0] != 'v' && line[0] != 'f') || (line[1] != ' ' && line[1] != '\t'))) continue;
    if (line[0] == 'v') {
      if (HasWordForNumber(line))
        throw Error("mesh '" + name + "': '" + std::string(line.substr(0, 80)) + "': not a finite number");
      ++geometry.vertices;
      geometry.corner_data += attribute;
    } else {
      ++geometry.faces;
      for (size_t k = 1; k < line.size(); ++k)
        if ((line[k - 1] == ' ' || line[k - 1] == '\t') && line[k] != ' ' && line[k] != '\t') ++geometry.face_vertices;
    }
    if (text) text->append(line).push_back('\n');
  }
  return geometry;
}

// tinyobjloader's memory for what it parses, in bytes: a vertex (or
// texture coordinate, or normal) as positions and colours; a face vertex as its parsed triple (twice,
// counting vector growth), the copy made when its face is stored and the
// exported index; a face as its vector and per-face arrays. A small file
// of many short faces can need forty times its size, so the estimate is
// checked before parsing.
constexpr uint64_t kObjBytesPerVertex = 40, kObjBytesPerFaceVertex = 64, kObjBytesPerFace = 96;
constexpr uint64_t kMaxObjParseBytes = uint64_t(16) << 30;

// An entry of ParseObj's table of shared corners (key, value, node, bucket).
constexpr uint64_t kCornerTableBytes = 48;

uint64_t ObjGeometry::ParseBytes() const {
  return vertices * kObjBytesPerVertex + face_vertices * kObjBytesPerFaceVertex + faces * kObjBytesPerFace;
}

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

// A mesh vertex is an OBJ face corner's (position, uv, normal) triple;
// corners sharing a triple share the vertex.
struct ObjCorner {
  int position, uv, normal;
  bool operator==(const ObjCorner&) const = default;
};
struct ObjCornerHash {
  size_t operator()(const ObjCorner& c) const {
    return std::hash<uint64_t>()((uint64_t(uint32_t(c.position)) << 32) ^ (uint64_t(uint32_t(c.uv)) << 16) ^
                                 uint64_t(uint32_t(c.normal)));
  }
};

TriangleMesh ParseObj(std::string_view bytes, const std::string& name, const MeshOptions& options) {
  std::string text;
  const ObjGeometry geometry = ObjGeometryLines(bytes, name, &text);
  const uint64_t parse_bytes = geometry.ParseBytes();
  if (parse_bytes > kMaxObjParseBytes)
    throw Error("mesh '" + name + "': OBJ file too large to parse (" + std::to_string(geometry.vertices) +
                " vertices, " + std::to_string(geometry.faces) + " faces would need about " +
                std::to_string(parse_bytes >> 20) + " MiB; at most " + std::to_string(kMaxObjParseBytes >> 20) +
                "; a binary PLY file needs far less)");
  std::istringstream stream(std::move(text));
  tinyobj::attrib_t attrib;
  std::vector<tinyobj::shape_t> shapes;
  std::vector<tinyobj::material_t> materials;
  std::string warning, error;
  // No material reader: `mtllib` lines never open files.
  if (!tinyobj::LoadObj(&attrib, &shapes, &materials, &warning, &error, &stream, nullptr,
                        /*triangulate=*/false, /*default_vcols_fallback=*/false))
    throw Error("mesh '" + name + "': not a valid OBJ file: " + FirstLine(error));
  const size_t position_count = attrib.vertices.size() / 3, uv_count = attrib.texcoords.size() / 2,
               normal_count = attrib.normals.size() / 3;

  // Normals and texture coordinates only when every corner has one (else
  // the mesh is shaded flat, or parameterised by its barycentrics).
  bool all_normals = true, all_uvs = true;
  for (const auto& shape : shapes)
    for (const tinyobj::index_t& index : shape.mesh.indices) {
      all_normals = all_normals && index.normal_index >= 0;
      all_uvs = all_uvs && index.texcoord_index >= 0;
    }
  const bool with_normals = all_normals && !options.face_normals && normal_count > 0;
  const bool with_uvs = all_uvs && uv_count > 0;

  TriangleMesh mesh;
  std::unordered_map<ObjCorner, uint32_t, ObjCornerHash> vertex_of;
  auto vertex = [&](const tinyobj::index_t& index) -> uint32_t {
    if (index.vertex_index < 0 || size_t(index.vertex_index) >= position_count)
      throw Error("mesh '" + name + "': face vertex index " + std::to_string(int64_t(index.vertex_index) + 1) +
                  " out of range (" + std::to_string(position_count) + " vertices)");
    if (index.texcoord_index >= int64_t(uv_count) || index.normal_index >= int64_t(normal_count))
      throw Error("mesh '" + name + "': a face's texture coordinate or normal index is out of range");
    const ObjCorner corner{index.vertex_index, with_uvs ? index.texcoord_index : -1,
                           with_normals ? index.normal_index : -1};
    const auto [at, added] = vertex_of.try_emplace(corner, uint32_t(mesh.positions.size()));
    if (!added) return at->second;
    const size_t p = size_t(corner.position);
    mesh.positions.emplace_back(attrib.vertices[3 * p], attrib.vertices[3 * p + 1], attrib.vertices[3 * p + 2]);
    if (with_normals) {
      const size_t n = size_t(corner.normal);
      mesh.normals.emplace_back(attrib.normals[3 * n], attrib.normals[3 * n + 1], attrib.normals[3 * n + 2]);
    }
    if (with_uvs) {
      const float u = attrib.texcoords[2 * size_t(corner.uv)], v = attrib.texcoords[2 * size_t(corner.uv) + 1];
      mesh.uvs.insert(mesh.uvs.end(), {u, options.flip_tex_coords ? 1 - v : v});
    }
    return at->second;
  };

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
      for (size_t k = 0; k < count; ++k) face.push_back(vertex(indices[next + k]));
      next += count;
      AppendFace(face, mesh.positions, mesh.indices);
    }
    if (next != indices.size())
      throw Error("mesh '" + name + "': a face has more than " + std::to_string(kMaxObjFaceVertices) + " vertices");
  }
  if (mesh.indices.empty()) throw Error("mesh '" + name + "': OBJ file has no faces");
  return mesh;
}

// A PLY reader for the subset meshes use: vertex elements with x, y, z
// (and optionally nx, ny, nz; u, v or s, t; red, green, blue) and face
// elements with a vertex index list. Other scalar properties of vertices
// and faces become attributes "vertex_NAME" and "face_NAME" (colours
// "vertex_color" and "face_color"), as Mitsuba's reader names them; other
// elements and lists are skipped. ASCII and both binary byte orders, any
// property order.
//
// The header's counts are untrusted: before an element is read, its count
// is checked against the bytes that follow (every entry takes at least a
// known number of them), so a short file with a huge count fails at once
// instead of allocating or looping for it, and every entry read consumes
// bytes.
class PlyReader {
 public:
  PlyReader(std::string_view bytes, const std::string& name, const MeshOptions& options)
      : bytes_(bytes), name_(name), options_(options) {}

  TriangleMesh Read() {
    TriangleMesh mesh;
    ReadInto(mesh);
    if (options_.face_normals) mesh.normals.clear();
    return mesh;
  }

  // Reads the whole file, checking it as Read does, but keeps only counts.
  MeshCounts Count() {
    counting_ = true;
    TriangleMesh attributes_only;
    ReadInto(attributes_only);
    counts_.attribute_values = attribute_values_;
    return counts_;
  }

 private:
  void ReadInto(TriangleMesh& mesh) {
    ReadHeader();
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
      const size_t first_attribute = mesh.attributes.size();
      for (const auto& [name, channels] : element.attributes) mesh.attributes.push_back({name, channels, {}});
      // Safe after the check: at most one vertex per `least` bytes.
      if (is_vertex && !counting_) mesh.positions.reserve(mesh.positions.size() + element.count);
      std::vector<float> values(element.properties.size());
      for (uint64_t i = 0; i < element.count; ++i) {
        size_t triangles = 0;
        for (size_t k = 0; k < element.properties.size(); ++k) {
          const Property& p = element.properties[k];
          if (p.is_list) {
            triangles += ReadList(p, is_face, mesh);
            continue;
          }
          const double v = ReadNumber(p.scalar);
          if (p.target == Target::kNone) continue;
          // Converting a double beyond float's range is undefined.
          if (!(std::abs(v) <= std::numeric_limits<float>::max()))
            Fail("non-finite value of property '" + p.name + "'");
          values[k] = float(v * p.scale);
        }
        counts_.triangles += triangles;
        if (is_vertex) {
          ++counts_.vertices;
          if (!counting_) StoreVertex(element, values, mesh);
        }
        StoreAttributes(element, values, is_vertex ? 1 : triangles, first_attribute, mesh);
      }
    }
    if (counts_.triangles == 0) Fail("no faces");
  }

  enum class Encoding { kAscii, kLittle, kBig };
  static constexpr int kMaxPolygonVertices = 1024;
  static constexpr size_t kMaxAttributes = 16;
  // Attribute floats a mesh may hold (1 GiB): a face's values are stored
  // once per triangle, so a short file could otherwise ask for far more.
  static constexpr uint64_t kMaxAttributeValues = uint64_t(1) << 28;
  // What a scalar property's value is.
  enum class Target { kNone, kPosition, kNormal, kUv, kAttribute };
  // A scalar type, named once in the header: values are read by it.
  enum class Scalar { kUnknown, kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };
  struct Property {
    std::string name, type, count_type;  // as the header spells them
    Scalar scalar = Scalar::kUnknown, count_scalar = Scalar::kUnknown;
    bool is_list = false;
    bool is_vertex_indices = false;
    Target target = Target::kNone;
    int component = 0;     // of the position, normal, uv or attribute
    size_t attribute = 0;  // index in its element's attributes
    double scale = 1;      // integer colours become 0–1
  };
  struct Element {
    std::string name;
    uint64_t count = 0;
    std::vector<Property> properties;
    std::vector<std::pair<std::string, uint32_t>> attributes;  // name, channels
    bool has_normals = false, has_uvs = false;
  };

  [[noreturn]] void Fail(const std::string& why) const {
    throw Error("mesh '" + name_ + "': not a valid PLY file: " + why);
  }

  static std::string FormatNumber(double v) {
    std::ostringstream out;
    out << v;
    return out.str();
  }

  // Reads one list property; a face's vertex indices become triangles (a
  // fan), whose number it returns. Other lists are read and dropped.
  size_t ReadList(const Property& p, bool is_face, TriangleMesh& mesh) {
    const double n = ReadNumber(p.count_scalar);
    if (!(n >= 0 && n <= kMaxPolygonVertices) || n != std::floor(n))
      Fail("a list has " + FormatNumber(n) + " entries (at most " + std::to_string(kMaxPolygonVertices) + ")");
    const bool indices = is_face && p.is_vertex_indices;
    indices_.clear();
    for (int k = 0; k < int(n); ++k) {
      const double v = ReadNumber(p.scalar);
      if (!indices) continue;
      if (!(v >= 0 && v < 4294967296.0) || v != std::floor(v))
        Fail("face vertex index " + FormatNumber(v) + " is not an index");
      indices_.push_back(uint32_t(v));
    }
    if (!counting_)
      for (size_t k = 1; k + 1 < indices_.size(); ++k)
        mesh.indices.insert(mesh.indices.end(), {indices_[0], indices_[k], indices_[k + 1]});
    return indices_.size() >= 3 ? indices_.size() - 2 : 0;
  }

  void StoreVertex(const Element& element, const std::vector<float>& values, TriangleMesh& mesh) const {
    float position[3] = {0, 0, 0}, normal[3] = {0, 0, 0}, uv[2] = {0, 0};
    for (size_t k = 0; k < element.properties.size(); ++k) {
      const Property& p = element.properties[k];
      if (p.target == Target::kPosition) position[p.component] = values[k];
      else if (p.target == Target::kNormal) normal[p.component] = values[k];
      else if (p.target == Target::kUv) uv[p.component] = values[k];
    }
    mesh.positions.push_back(Vec3::Load(position));
    if (element.has_normals) mesh.normals.push_back(Vec3::Load(normal));
    if (element.has_uvs) mesh.uvs.insert(mesh.uvs.end(), {uv[0], uv[1]});
  }

  // Appends each attribute's value `copies` times (a face's once per
  // triangle); channels the file lacks are 0.
  void StoreAttributes(const Element& element, const std::vector<float>& values, size_t copies,
                       size_t first_attribute, TriangleMesh& mesh) {
    for (size_t a = 0; a < element.attributes.size(); ++a) {
      float tuple[3] = {0, 0, 0};
      for (size_t k = 0; k < element.properties.size(); ++k) {
        const Property& p = element.properties[k];
        if (p.target == Target::kAttribute && p.attribute == a) tuple[p.component] = values[k];
      }
      const uint32_t channels = element.attributes[a].second;
      attribute_values_ += uint64_t(copies) * channels;
      if (attribute_values_ > kMaxAttributeValues)
        Fail("attributes would hold more than " + std::to_string(kMaxAttributeValues) + " values");
      if (counting_) continue;
      std::vector<float>& out = mesh.attributes[first_attribute + a].values;
      for (size_t c = 0; c < copies; ++c) out.insert(out.end(), tuple, tuple + channels);
    }
  }

  // The fewest bytes one entry of `element` can take.
  uint64_t MinimumEntryBytes(const Element& element) const {
    uint64_t least = 0;
    for (const Property& p : element.properties) {
      if (encoding_ == Encoding::kAscii) least += 2;  // a digit and a separator
      else least += p.is_list ? SizeOf(p.count_scalar) : SizeOf(p.scalar);
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
        p.scalar = ScalarOf(p.type);
        if (p.is_list) p.count_scalar = ScalarOf(p.count_type);
        if (p.scalar == Scalar::kUnknown) Fail("property '" + p.name + "' has unknown type '" + p.type + "'");
        if (p.is_list && !IsInteger(p.count_scalar))
          Fail("list property '" + p.name + "' has count type '" + p.count_type + "' (an integer type is needed)");
        p.is_vertex_indices = p.is_list && (p.name == "vertex_indices" || p.name == "vertex_index");
        if (p.is_vertex_indices && !IsInteger(p.scalar))
          Fail("list property '" + p.name + "' has index type '" + p.type + "' (an integer type is needed)");
        for (const Property& q : element.properties)
          if (q.name == p.name) Fail("element '" + element.name + "' has two properties '" + p.name + "'");
        if (!p.is_list) Classify(element, p);
        element.properties.push_back(p);
      }
    }
    if (!has_format) Fail("no format line");
    for (Element& e : elements_) {
      if (e.name != "vertex") continue;
      if (e.count > 0 && Components(e, Target::kPosition) != 3) Fail("element 'vertex' lacks an x, y or z property");
      // Normals and uvs only when complete.
      e.has_normals = Components(e, Target::kNormal) == 3;
      e.has_uvs = Components(e, Target::kUv) == 2;
    }
    pos_ = at;
  }

  static int Components(const Element& e, Target target) {
    int count = 0;
    for (const Property& p : e.properties) count += p.target == target;
    return count;
  }

  // What a scalar property's value is, by its name (the spellings
  // Mitsuba's and pbrt's readers accept); a second spelling of a
  // component already present is dropped.
  void Classify(Element& element, Property& p) {
    const bool is_vertex = element.name == "vertex";
    if (!is_vertex && element.name != "face") return;
    struct Name {
      const char* name;
      Target target;
      int component;
    };
    static constexpr Name kVertexNames[] = {
        {"x", Target::kPosition, 0},   {"y", Target::kPosition, 1},  {"z", Target::kPosition, 2},
        {"nx", Target::kNormal, 0},    {"ny", Target::kNormal, 1},   {"nz", Target::kNormal, 2},
        {"u", Target::kUv, 0},         {"v", Target::kUv, 1},        {"s", Target::kUv, 0},
        {"t", Target::kUv, 1},         {"texture_u", Target::kUv, 0}, {"texture_v", Target::kUv, 1},
        {"texture_s", Target::kUv, 0}, {"texture_t", Target::kUv, 1}};
    auto taken = [&](Target target, int component, size_t attribute = 0) {
      for (const Property& q : element.properties)
        if (q.target == target && q.component == component && q.attribute == attribute) return true;
      return false;
    };
    if (is_vertex)
      for (const Name& n : kVertexNames)
        if (p.name == n.name) {
          if (!taken(n.target, n.component)) p.target = n.target, p.component = n.component;
          return;
        }
    if (p.name == "alpha" || p.name == "a") return;
    static constexpr std::pair<const char*, int> kColours[] = {{"red", 0}, {"green", 1}, {"blue", 2},
                                                              {"r", 0},   {"g", 1},     {"b", 2}};
    std::string attribute = (is_vertex ? "vertex_" : "face_") + p.name;
    uint32_t channels = 1;
    for (const auto& [name, component] : kColours)
      if (p.name == name) {
        attribute = is_vertex ? "vertex_color" : "face_color", channels = 3, p.component = component;
        // Integer colours are stored in their type's range.
        if (IsInteger(p.scalar)) p.scale = 1.0 / (std::ldexp(1.0, 8 * int(SizeOf(p.scalar))) - 1);
      }
    size_t index = 0;
    while (index < element.attributes.size() && element.attributes[index].first != attribute) ++index;
    if (index == element.attributes.size()) {
      if (index == kMaxAttributes)
        Fail("element '" + element.name + "' has more than " + std::to_string(kMaxAttributes) + " attributes");
      element.attributes.emplace_back(attribute, channels);
    }
    if (taken(Target::kAttribute, p.component, index)) return;
    p.target = Target::kAttribute, p.attribute = index;
  }

  static Scalar ScalarOf(const std::string& type) {
    static constexpr std::pair<const char*, Scalar> kNames[] = {
        {"char", Scalar::kInt8},     {"int8", Scalar::kInt8},       {"uchar", Scalar::kUint8},
        {"uint8", Scalar::kUint8},   {"short", Scalar::kInt16},     {"int16", Scalar::kInt16},
        {"ushort", Scalar::kUint16}, {"uint16", Scalar::kUint16},   {"int", Scalar::kInt32},
        {"int32", Scalar::kInt32},   {"uint", Scalar::kUint32},     {"uint32", Scalar::kUint32},
        {"float", Scalar::kFloat32}, {"float32", Scalar::kFloat32}, {"double", Scalar::kFloat64},
        {"float64", Scalar::kFloat64}};
    for (const auto& [name, scalar] : kNames)
      if (type == name) return scalar;
    return Scalar::kUnknown;
  }

  static size_t SizeOf(Scalar type) {
    switch (type) {
      case Scalar::kInt8:
      case Scalar::kUint8:
        return 1;
      case Scalar::kInt16:
      case Scalar::kUint16:
        return 2;
      case Scalar::kInt32:
      case Scalar::kUint32:
      case Scalar::kFloat32:
        return 4;
      case Scalar::kFloat64:
        return 8;
      case Scalar::kUnknown:
        break;
    }
    return 0;
  }

  static bool IsInteger(Scalar type) {
    return type != Scalar::kUnknown && type != Scalar::kFloat32 && type != Scalar::kFloat64;
  }

  double ReadNumber(Scalar type) {
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
    switch (type) {
      case Scalar::kInt8: return as.operator()<int8_t>();
      case Scalar::kUint8: return as.operator()<uint8_t>();
      case Scalar::kInt16: return as.operator()<int16_t>();
      case Scalar::kUint16: return as.operator()<uint16_t>();
      case Scalar::kInt32: return as.operator()<int32_t>();
      case Scalar::kUint32: return as.operator()<uint32_t>();
      case Scalar::kFloat32: return as.operator()<float>();
      default: return as.operator()<double>();
    }
  }

  std::string_view bytes_;
  std::string name_;
  MeshOptions options_;
  Encoding encoding_ = Encoding::kAscii;
  std::vector<Element> elements_;
  std::vector<uint32_t> indices_;
  std::vector<float> entry_;  // the current entry's values, by slot
  uint64_t attribute_values_ = 0;
  size_t pos_ = 0;
  // Counting keeps no vertices, indices or attribute values.
  bool counting_ = false;
  MeshCounts counts_;
};

std::string UnknownFormat(const std::string& name, std::string_view format) {
  return "mesh '" + name + "': unknown format '" + std::string(format) + "' (obj or ply)";
}

// A gzip-compressed mesh file (pbrt's .ply.gz) inflates to at most this.
constexpr uint64_t kMaxInflatedMeshBytes = uint64_t(4) << 30;

// The file a gzip-compressed mesh file holds, up to `limit` bytes of it
// (complete says whether that was all); more than kMaxInflatedMeshBytes
// is refused.
Inflated InflatedMesh(std::string_view bytes, const std::string& name, uint64_t limit) {
  Inflated inflated;
  try {
    inflated = Inflate(bytes, std::min(limit, kMaxInflatedMeshBytes));
  } catch (const std::runtime_error& e) {
    throw Error("mesh '" + name + "': gzip file: " + e.what());
  }
  if (!inflated.complete && limit >= kMaxInflatedMeshBytes)
    throw Error("mesh '" + name + "': gzip file inflates to more than " +
                std::to_string(kMaxInflatedMeshBytes >> 20) + " MiB");
  if (IsGzip(inflated.bytes)) throw Error("mesh '" + name + "': a gzip file inside a gzip file");
  return inflated;
}

}  // namespace

TriangleMesh ParseMesh(std::string_view bytes, std::string_view format, const std::string& name,
                       const MeshOptions& options) {
  if (IsGzip(bytes)) {
    const Inflated inflated = InflatedMesh(bytes, name, kMaxInflatedMeshBytes);
    return ParseMesh(inflated.bytes, format, name, options);
  }
  TriangleMesh mesh;
  if (format == "obj") mesh = ParseObj(bytes, name, options);
  else if (format == "ply") mesh = PlyReader(bytes, name, options).Read();
  else throw Error(UnknownFormat(name, format));
  ValidateMesh(mesh, name);
  return mesh;
}

MeshCounts CountMesh(std::string_view bytes, std::string_view format, const std::string& name,
                     uint64_t max_inflated) {
  if (IsGzip(bytes)) {
    const Inflated inflated = InflatedMesh(bytes, name, max_inflated);
    if (!inflated.complete) return {.parse_bytes = max_inflated + 1};
    MeshCounts counts = CountMesh(inflated.bytes, format, name, max_inflated);
    counts.parse_bytes += inflated.bytes.size();
    return counts;
  }
  if (format == "ply") return PlyReader(bytes, name, {}).Count();
  if (format != "obj") throw Error(UnknownFormat(name, format));
  const ObjGeometry geometry = ObjGeometryLines(bytes, name, nullptr);
  MeshCounts counts;
  // A vertex per distinct corner: per position when corners are positions alone.
  counts.vertices = geometry.corner_data == 0 ? std::min(geometry.vertices, geometry.face_vertices)
                                              : geometry.face_vertices;
  counts.triangles = geometry.face_vertices > 2 * geometry.faces ? geometry.face_vertices - 2 * geometry.faces : 0;
  // The filtered text tinyobjloader reads is another copy of the file; the
  // table of shared corners an entry per vertex.
  counts.parse_bytes = geometry.ParseBytes() + bytes.size() + counts.vertices * kCornerTableBytes;
  return counts;
}

namespace {

bool IsFinite(std::span<const float> values) {
  return std::all_of(values.begin(), values.end(), [](float v) { return std::isfinite(v); });
}

// Unit vertex normals; a zero or non-finite one becomes the area-weighted
// mean of its faces' normals (zero when they are all degenerate, which
// the kernel shades flat).
void RepairNormals(TriangleMesh& mesh) {
  std::vector<size_t> bad;
  for (size_t i = 0; i < mesh.normals.size(); ++i) {
    Vec3& n = mesh.normals[i];
    const float length = std::sqrt(Dot(n, n));
    if (std::isfinite(length) && length > 0) n = n * (1 / length);
    else bad.push_back(i);
  }
  if (bad.empty()) return;
  std::vector<Vec3> face_sum(mesh.positions.size());
  for (size_t t = 0; t < mesh.TriangleCount(); ++t) {
    const uint32_t* v = &mesh.indices[3 * t];
    const Vec3 n = Cross(mesh.positions[v[1]] - mesh.positions[v[0]], mesh.positions[v[2]] - mesh.positions[v[0]]);
    for (int k = 0; k < 3; ++k) face_sum[v[k]] = face_sum[v[k]] + n;
  }
  for (size_t i : bad) {
    const Vec3 n = face_sum[i];
    const float length = std::sqrt(Dot(n, n));
    mesh.normals[i] = std::isfinite(length) && length > 0 ? n * (1 / length) : Vec3{};
  }
}

}  // namespace

void ValidateMesh(TriangleMesh& mesh, const std::string& name) {
  const std::string what = "mesh '" + name + "': ";
  if (mesh.indices.size() % 3 != 0) throw Error(what + "index count is not a multiple of 3");
  for (uint32_t i : mesh.indices)
    if (i >= mesh.positions.size())
      throw Error(what + "index " + std::to_string(i) + " out of range (" + std::to_string(mesh.positions.size()) +
                  " vertices)");
  for (const Vec3& p : mesh.positions)
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw Error(what + "non-finite vertex position");
  const size_t vertices = mesh.positions.size(), triangles = mesh.TriangleCount();
  if (!mesh.normals.empty() && mesh.normals.size() != vertices)
    throw Error(what + std::to_string(mesh.normals.size()) + " normals for " + std::to_string(vertices) +
                " vertices");
  if (!mesh.uvs.empty() && mesh.uvs.size() != 2 * vertices)
    throw Error(what + std::to_string(mesh.uvs.size() / 2) + " texture coordinates for " +
                std::to_string(vertices) + " vertices");
  if (!IsFinite(mesh.uvs)) throw Error(what + "non-finite texture coordinate");
  for (const MeshAttribute& a : mesh.attributes) {
    if (!a.name.starts_with("vertex_") && !a.name.starts_with("face_"))
      throw Error(what + "attribute '" + a.name + "' is named neither vertex_* nor face_*");
    if (a.channels != 1 && a.channels != 3)
      throw Error(what + "attribute '" + a.name + "' has " + std::to_string(a.channels) + " channels (1 or 3)");
    const size_t count = a.PerFace() ? triangles : vertices;
    if (a.values.size() != count * a.channels)
      throw Error(what + "attribute '" + a.name + "' has " + std::to_string(a.values.size()) + " values, not " +
                  std::to_string(count * a.channels) + " (" + std::to_string(a.channels) + " per " +
                  (a.PerFace() ? "face" : "vertex") + ")");
    if (!IsFinite(a.values)) throw Error(what + "attribute '" + a.name + "' has a non-finite value");
  }
  RepairNormals(mesh);
}

std::vector<Vec3> AngleWeightedNormals(const TriangleMesh& mesh) {
  std::vector<Vec3> normals(mesh.positions.size());
  for (size_t t = 0; t < mesh.TriangleCount(); ++t) {
    const uint32_t* v = &mesh.indices[3 * t];
    const Vec3 p[3] = {mesh.positions[v[0]], mesh.positions[v[1]], mesh.positions[v[2]]};
    const Vec3 n = Cross(p[1] - p[0], p[2] - p[0]);
    const float length = Length(n);
    if (!(length > 0) || !std::isfinite(length)) continue;
    for (int k = 0; k < 3; ++k) {
      // The angle at corner k, well conditioned for small angles too: the
      // cross product of the two edges from any corner is n.
      const float angle = std::atan2(length, Dot(p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]));
      normals[v[k]] += n * (angle / length);
    }
  }
  for (Vec3& n : normals) {
    const float length = Length(n);
    n = length > 0 && std::isfinite(length) ? n / length : Vec3();
  }
  return normals;
}

void DropFaceNormals(TriangleMesh& mesh) {
  if (mesh.normals.empty()) return;
  for (size_t t = 0; t < mesh.TriangleCount(); ++t) {
    const uint32_t* v = &mesh.indices[3 * t];
    const Vec3 n = Cross(mesh.positions[v[1]] - mesh.positions[v[0]], mesh.positions[v[2]] - mesh.positions[v[0]]);
    const float length = std::sqrt(Dot(n, n));
    if (!(length > 0) || !std::isfinite(length)) continue;  // never hit
    for (int k = 0; k < 3; ++k)
      if (!(Dot(mesh.normals[v[k]], n) >= (1 - 1e-6f) * length)) return;
  }
  mesh.normals.clear();
}

}  // namespace yarf
