#include "kernel/mesh_io.h"

#include <tiny_obj_loader.h>

#include <cstring>
#include <sstream>

#include "yarf/error.h"

namespace yarf {
namespace {

TriangleMesh ParseObj(std::string_view bytes, const std::string& name) {
  tinyobj::ObjReaderConfig config;
  config.triangulate = true;
  config.vertex_color = false;
  tinyobj::ObjReader reader;
  if (!reader.ParseFromString(std::string(bytes), "", config))
    throw Error("mesh '" + name + "': not a valid OBJ file: " + reader.Error());
  const auto& attrib = reader.GetAttrib();
  TriangleMesh mesh;
  mesh.positions.reserve(attrib.vertices.size() / 3);
  for (size_t i = 0; i + 2 < attrib.vertices.size(); i += 3)
    mesh.positions.emplace_back(attrib.vertices[i], attrib.vertices[i + 1], attrib.vertices[i + 2]);
  for (const auto& shape : reader.GetShapes())
    for (const auto& index : shape.mesh.indices) {
      if (index.vertex_index < 0) throw Error("mesh '" + name + "': negative vertex index");
      mesh.indices.push_back(uint32_t(index.vertex_index));
    }
  if (mesh.indices.empty()) throw Error("mesh '" + name + "': OBJ file has no faces");
  return mesh;
}

// A PLY reader for the subset meshes use: one vertex element with x, y, z
// and one face element with a vertex index list; other elements and
// properties are skipped. ASCII and both binary byte orders.
class PlyReader {
 public:
  PlyReader(std::string_view bytes, const std::string& name) : bytes_(bytes), name_(name) {}

  TriangleMesh Read() {
    ReadHeader();
    TriangleMesh mesh;
    for (const Element& element : elements_) {
      for (uint64_t i = 0; i < element.count; ++i) {
        float xyz[3] = {0, 0, 0};
        for (const Property& p : element.properties) {
          if (p.is_list) {
            const uint64_t n = uint64_t(ReadNumber(p.count_type));
            if (n > 1024) Fail("face with " + std::to_string(n) + " vertices");
            indices_.clear();
            for (uint64_t k = 0; k < n; ++k) indices_.push_back(uint32_t(ReadNumber(p.type)));
            if (element.name == "face" && (p.name == "vertex_indices" || p.name == "vertex_index"))
              for (size_t k = 1; k + 1 < indices_.size(); ++k)
                mesh.indices.insert(mesh.indices.end(), {indices_[0], indices_[k], indices_[k + 1]});
          } else {
            const double v = ReadNumber(p.type);
            if (element.name == "vertex" && p.name.size() == 1 && p.name[0] >= 'x' && p.name[0] <= 'z')
              xyz[p.name[0] - 'x'] = float(v);
          }
        }
        if (element.name == "vertex") mesh.positions.emplace_back(xyz[0], xyz[1], xyz[2]);
      }
    }
    if (mesh.indices.empty()) Fail("no faces");
    return mesh;
  }

 private:
  enum class Encoding { kAscii, kLittle, kBig };
  struct Property {
    std::string name, type, count_type;
    bool is_list = false;
  };
  struct Element {
    std::string name;
    uint64_t count = 0;
    std::vector<Property> properties;
  };

  [[noreturn]] void Fail(const std::string& why) const {
    throw Error("mesh '" + name_ + "': not a valid PLY file: " + why);
  }

  void ReadHeader() {
    const size_t end = bytes_.find("end_header");
    if (bytes_.substr(0, 3) != "ply" || end == std::string_view::npos) Fail("missing header");
    std::istringstream header{std::string(bytes_.substr(0, end))};
    std::string line;
    while (std::getline(header, line)) {
      std::istringstream words(line);
      std::string keyword;
      words >> keyword;
      if (keyword == "format") {
        std::string kind;
        words >> kind;
        if (kind == "ascii") encoding_ = Encoding::kAscii;
        else if (kind == "binary_little_endian") encoding_ = Encoding::kLittle;
        else if (kind == "binary_big_endian") encoding_ = Encoding::kBig;
        else Fail("unknown format '" + kind + "'");
      } else if (keyword == "element") {
        Element e;
        words >> e.name >> e.count;
        if (!words) Fail("bad element line");
        elements_.push_back(e);
      } else if (keyword == "property") {
        if (elements_.empty()) Fail("property before element");
        Property p;
        words >> p.type;
        if (p.type == "list") {
          p.is_list = true;
          words >> p.count_type >> p.type;
        }
        words >> p.name;
        if (!words) Fail("bad property line");
        elements_.back().properties.push_back(p);
      }
    }
    pos_ = bytes_.find('\n', end);
    if (pos_ == std::string_view::npos) Fail("truncated header");
    ++pos_;
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

  double ReadNumber(const std::string& type) {
    if (encoding_ == Encoding::kAscii) {
      while (pos_ < bytes_.size() && std::isspace(static_cast<unsigned char>(bytes_[pos_]))) ++pos_;
      size_t start = pos_;
      while (pos_ < bytes_.size() && !std::isspace(static_cast<unsigned char>(bytes_[pos_]))) ++pos_;
      if (start == pos_) Fail("unexpected end of data");
      try {
        return std::stod(std::string(bytes_.substr(start, pos_ - start)));
      } catch (const std::exception&) {
        Fail("bad number");
      }
    }
    const size_t size = SizeOf(type);
    if (size == 0) Fail("unknown property type '" + type + "'");
    if (pos_ + size > bytes_.size()) Fail("unexpected end of data");
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
