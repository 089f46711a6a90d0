#include "kernel/mesh_io.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <bit>
#include <cstring>
#include <string>
#include <vector>

#include "yarf/error.h"

namespace yarf {
namespace {

// The message ParseMesh throws for `bytes`, or "" when it parses.
std::string ErrorOf(const std::string& bytes, const std::string& format) {
  try {
    ParseMesh(bytes, format, "x." + format);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

std::vector<float> Flat(const TriangleMesh& mesh) {
  std::vector<float> out;
  for (const Vec3& p : mesh.positions) out.insert(out.end(), {p.x, p.y, p.z});
  return out;
}

// Binary PLY data in either byte order.
class Bytes {
 public:
  explicit Bytes(bool big_endian) : big_(big_endian) {}
  template <typename T>
  Bytes& Put(T value) {
    char raw[sizeof(T)];
    std::memcpy(raw, &value, sizeof(T));
    if (big_ != (std::endian::native == std::endian::big)) std::reverse(raw, raw + sizeof(T));
    text.append(raw, sizeof(T));
    return *this;
  }
  std::string text;

 private:
  bool big_;
};

// --- hostile PLY headers -------------------------------------------------

TEST(PlyReader, RefusesAnElementOfTwoToTheSixtyFourEntriesWithoutProperties) {
  // Once looped forever: one pass per declared entry, none consuming a byte.
  const std::string ply = "ply\nformat ascii 1.0\nelement vertex 18446744073709551615\nend_header\n";
  EXPECT_NE(ErrorOf(ply, "ply").find("element 'vertex' lacks an x, y or z property"), std::string::npos)
      << ErrorOf(ply, "ply");
  const std::string other = "ply\nformat binary_little_endian 1.0\nelement foo 18446744073709551615\nend_header\n";
  EXPECT_EQ(ErrorOf(other, "ply"), "mesh 'x.ply': not a valid PLY file: no faces");
}

TEST(PlyReader, RefusesCountsTheBytesCannotHold) {
  // Once allocated gigabytes for 2·10⁹ vertices declared in 120 bytes.
  std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 2000000000\n"
      "property float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n1 0 0\n";
  ASSERT_EQ(ply.size(), 121u);
  EXPECT_EQ(ErrorOf(ply, "ply"),
            "mesh 'x.ply': not a valid PLY file: element 'vertex' declares 2000000000 entries but only 12 bytes follow");
  std::string binary =
      "ply\nformat binary_big_endian 1.0\nelement vertex 2000000000\n"
      "property float x\nproperty float y\nproperty float z\nend_header\n";
  binary.resize(binary.size() + 54, '\0');
  EXPECT_EQ(ErrorOf(binary, "ply"),
            "mesh 'x.ply': not a valid PLY file: element 'vertex' declares 2000000000 entries but only 54 bytes follow");
  const std::string faces =
      "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 18446744073709551615\nproperty list uchar int vertex_indices\nend_header\n3 0 1 2\n";
  EXPECT_NE(ErrorOf(faces, "ply").find("element 'face' declares 18446744073709551615 entries but only 8 bytes"),
            std::string::npos)
      << ErrorOf(faces, "ply");
}

TEST(PlyReader, RefusesUnknownTypesInTheHeader) {
  const std::string head = "ply\nformat binary_little_endian 1.0\nelement vertex 1\n";
  EXPECT_NE(ErrorOf(head + "property int128 x\nend_header\n", "ply").find("property 'x' has unknown type 'int128'"),
            std::string::npos);
  EXPECT_NE(ErrorOf(head + "property list float int vertex_indices\nend_header\n", "ply").find("count type 'float'"),
            std::string::npos);
  EXPECT_NE(ErrorOf(head + "property list uchar\nend_header\n", "ply").find("bad property line"), std::string::npos);
  EXPECT_NE(ErrorOf("ply\nformat ascii 1.0\nelement vertex -1\nend_header\n", "ply").find("bad element line"),
            std::string::npos);
  EXPECT_NE(ErrorOf("ply\nformat ascii 1.0\nelement vertex 1\n", "ply").find("truncated header"), std::string::npos);
  EXPECT_NE(ErrorOf("ply\nelement vertex 1\nend_header\n", "ply").find("no format line"), std::string::npos);
}

TEST(PlyReader, RefusesBadListsAndIndices) {
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n";
  EXPECT_EQ(ErrorOf(head + "3 0 1 2\n", "ply"), "");
  EXPECT_NE(ErrorOf(head + "3 0 -1 2\n", "ply").find("face vertex index -1 is not an index"), std::string::npos);
  EXPECT_NE(ErrorOf(head + "3 0 1 7\n", "ply").find("index 7 out of range (3 vertices)"), std::string::npos);
  EXPECT_NE(ErrorOf(head + "3 0 1.5 2\n", "ply").find("is not an index"), std::string::npos);
  EXPECT_NE(ErrorOf(head + "2000 0 1 2\n", "ply").find("has 2000 entries (at most 1024)"), std::string::npos);
  EXPECT_NE(ErrorOf(head + "3 0 1\n", "ply").find("unexpected end of data"), std::string::npos);
  EXPECT_NE(ErrorOf(head + "3 0 1 x\n", "ply").find("bad number 'x'"), std::string::npos);
  Bytes data(false);
  data.Put<float>(1e30f).Put<float>(0).Put<float>(0).Put<uint8_t>(3).Put<int32_t>(0).Put<int32_t>(0);
  const std::string truncated =
      "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n" + data.text;
  EXPECT_NE(ErrorOf(truncated, "ply").find("unexpected end of data"), std::string::npos);
  const std::string huge_double =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n1e300 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  EXPECT_NE(ErrorOf(huge_double, "ply").find("non-finite value of property 'x'"), std::string::npos);
}

// --- PLY files that must keep working --------------------------------------

TEST(PlyReader, ReadsBinaryBigEndianWithExtraPropertiesAndElements) {
  Bytes data(true);
  const float xyz[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 2, 0}, {0, 2, 0.5f}};
  for (int i = 0; i < 4; ++i)
    data.Put<double>(-1).Put<float>(xyz[i][0]).Put<uint8_t>(200).Put<float>(xyz[i][1]).Put<float>(xyz[i][2]);
  // One quad, then one triangle, each with a list that is not indices.
  data.Put<uint8_t>(2).Put<float>(0.5f).Put<float>(0.25f).Put<uint8_t>(4);
  for (int32_t i : {0, 1, 2, 3}) data.Put(i);
  data.Put<uint8_t>(0).Put<uint8_t>(3);
  for (int32_t i : {2, 3, 0}) data.Put(i);
  data.Put<int16_t>(7).Put<int16_t>(-7);  // the edge element
  const std::string ply =
      "ply\r\nformat binary_big_endian 1.0\ncomment not end_header\nobj_info any\nelement vertex 4\n"
      "property double nx\nproperty float x\nproperty uchar red\nproperty float y\nproperty float z\n"
      "element face 2\nproperty list uchar float texcoord\nproperty list uchar int vertex_indices\n"
      "element edge 1\nproperty short a\nproperty int16 b\nelement empty 5\nend_header\n" + data.text;
  const TriangleMesh mesh = ParseMesh(ply, "ply", "x.ply");
  EXPECT_EQ(Flat(mesh), (std::vector<float>{0, 0, 0, 1, 0, 0, 1, 2, 0, 0, 2, 0.5f}));
  EXPECT_EQ(mesh.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3, 2, 3, 0}));
}

TEST(PlyReader, ReadsAsciiWithPropertiesInAnyOrder) {
  const std::string ply =
      "ply\nformat ascii 1.0\nelement material 1\nproperty float shine\n"
      "element vertex 5\nproperty float z\nproperty float nx\nproperty float x\nproperty uint id\nproperty float y\n"
      "element face 1\nproperty uchar flags\nproperty list uint8 uint32 vertex_index\nproperty float area\n"
      "end_header\n0.5\n"
      "3 9 0 0 1\n+3 9 1 1 2.5e0\n3 9 2 2 4\n3 9 3 3 5\n3 9 4 4 6\n"
      "1 5 0 1 2 3 4 -0.25";  // no final line break
  const TriangleMesh mesh = ParseMesh(ply, "ply", "x.ply");
  EXPECT_EQ(Flat(mesh), (std::vector<float>{0, 1, 3, 1, 2.5f, 3, 2, 4, 3, 3, 5, 3, 4, 6, 3}));
  // A pentagon as a fan.
  EXPECT_EQ(mesh.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3, 0, 3, 4}));
}

TEST(PlyReader, SplitsQuadsOfTheTestScenes) {
  const std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "-1 -1 0\n1 -1 0\n1 1 0\n-1 1 0\n4 0 1 2 3\n";
  const TriangleMesh mesh = ParseMesh(ply, "ply", "x.ply");
  EXPECT_EQ(mesh.positions.size(), 4u);
  EXPECT_EQ(mesh.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3}));
}

// --- OBJ --------------------------------------------------------------------

const std::string kObjVertices = "v 0 0 0\nv 1 0 0\nv 1 2 0\nv 0 2 0\n";

TEST(ObjReader, ReadsTrianglesQuadsRelativeIndicesAndPolygons) {
  const TriangleMesh mesh =
      ParseMesh(kObjVertices + "vn 0 0 1\nvt 0 0\ng a\nusemtl m\nf 1/1/1 2/1/1 3/1/1\ng b\nf -4 -3 -2 -1\n"
                "f 1 2 3 4 1 2\n",
                "obj", "x.obj");
  EXPECT_EQ(Flat(mesh), (std::vector<float>{0, 0, 0, 1, 0, 0, 1, 2, 0, 0, 2, 0}));
  // The quad along its shorter diagonal (both are equal here: 1-3); the
  // hexagon as a fan.
  EXPECT_EQ(mesh.indices, (std::vector<uint32_t>{0, 1, 2, 0, 1, 3, 1, 2, 3, 0, 1, 2, 0, 2, 3, 0, 3, 0, 0, 0, 1}));
  const TriangleMesh skewed = ParseMesh("v 0 0 0\nv 1 0 0\nv 5 1 0\nv 0 1 0\nf 1 2 3 4\n", "obj", "x.obj");
  EXPECT_EQ(skewed.indices, (std::vector<uint32_t>{0, 1, 3, 1, 2, 3}));
}

TEST(ObjReader, ReadsUvsAndNormalsSplittingVerticesWhereCornersDiffer) {
  // A quad of two triangles sharing the edge 1-3, with a seam: corner 1 has
  // different uvs in the two faces.
  const std::string obj = kObjVertices +
                          "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 0.5\nvn 0 0 2\n"
                          "f 1/1/1 2/2/1 3/3/1\nf 1/5/1 3/3/1 4/4/1\n";
  const TriangleMesh flipped = ParseMesh(obj, "obj", "x.obj");
  ASSERT_EQ(flipped.positions.size(), 5u);  // four corners, one split at the seam
  EXPECT_EQ(flipped.indices, (std::vector<uint32_t>{0, 1, 2, 3, 2, 4}));
  // v flipped (Mitsuba's default): an image's top row at v = 0.
  EXPECT_EQ(flipped.uvs, (std::vector<float>{0, 1, 1, 1, 1, 0, 0.5f, 0.5f, 0, 0}));
  ASSERT_EQ(flipped.normals.size(), 5u);
  EXPECT_EQ(flipped.normals[3].z, 1.0f);  // made unit length
  const TriangleMesh kept = ParseMesh(obj, "obj", "x.obj", {.flip_tex_coords = false});
  EXPECT_EQ(kept.uvs, (std::vector<float>{0, 0, 1, 0, 1, 1, 0.5f, 0.5f, 0, 1}));
  EXPECT_TRUE(ParseMesh(obj, "obj", "x.obj", {.face_normals = true}).normals.empty());
  // A face without uvs: the mesh has none.
  EXPECT_TRUE(ParseMesh(obj + "f 1 2 3\n", "obj", "x.obj").uvs.empty());
  EXPECT_NE(ErrorOf(kObjVertices + "vt 0 0\nf 1/1 2/7 3/1\n", "obj").find("out of range"), std::string::npos);
}

TEST(Mesh, FaceNormalsAreDroppedAndOthersKept) {
  // Two triangles of the plane z = 0, wound toward +z.
  TriangleMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  mesh.indices = {0, 1, 2, 0, 2, 3};
  mesh.normals.assign(4, Vec3(0, 0, 1));
  TriangleMesh flat = mesh;
  DropFaceNormals(flat);
  EXPECT_TRUE(flat.normals.empty());
  TriangleMesh opposite = mesh;  // normals that decide the side stay
  opposite.normals.assign(4, Vec3(0, 0, -1));
  DropFaceNormals(opposite);
  EXPECT_EQ(opposite.normals.size(), 4u);
  TriangleMesh smooth = mesh;  // one tilted corner: smooth shading
  smooth.normals[2] = Normalize(Vec3(0.1f, 0, 1));
  DropFaceNormals(smooth);
  EXPECT_EQ(smooth.normals.size(), 4u);
}

TEST(PlyReader, ReadsNormalsUvsColoursAndAttributesInAnyOrder) {
  const std::string ply =
      "ply\nformat ascii 1.0\n"
      "element vertex 3\nproperty uchar blue\nproperty float s\nproperty float x\nproperty float nz\n"
      "property float y\nproperty float t\nproperty float z\nproperty uchar red\nproperty float ny\n"
      "property float nx\nproperty float temperature\nproperty uchar green\n"
      "element face 1\nproperty float weight\nproperty list uchar int vertex_indices\nend_header\n"
      "255 0 0 1 0 0.25 0 0 0 0 10 51\n0 1 1 3 0 0.5 0 255 0 0 20 0\n0 0 0 0 1 1 0 0 0 0 30 0\n"
      "0.75 4 0 1 2 2\n";
  const TriangleMesh mesh = ParseMesh(ply, "ply", "x.ply");
  EXPECT_EQ(Flat(mesh), (std::vector<float>{0, 0, 0, 1, 0, 0, 0, 1, 0}));
  EXPECT_EQ(mesh.uvs, (std::vector<float>{0, 0.25f, 1, 0.5f, 0, 1}));  // not flipped
  ASSERT_EQ(mesh.normals.size(), 3u);
  EXPECT_EQ(mesh.normals[1].z, 1.0f);  // (0, 0, 3) made unit
  // The third vertex's normal was zero: the face's own (+z) replaces it.
  EXPECT_EQ(mesh.normals[2].z, 1.0f);
  ASSERT_EQ(mesh.attributes.size(), 3u);
  const auto attribute = [&](const std::string& name) -> const MeshAttribute& {
    for (const MeshAttribute& a : mesh.attributes)
      if (a.name == name) return a;
    throw Error("no attribute " + name);
  };
  const MeshAttribute& colour = attribute("vertex_color");
  EXPECT_EQ(colour.channels, 3u);
  EXPECT_EQ(colour.values, (std::vector<float>{0, 0.2f, 1, 1, 0, 0, 0, 0, 0}));
  EXPECT_EQ(attribute("vertex_temperature").values, (std::vector<float>{10, 20, 30}));
  // A quad (4 0 1 2 2) is two triangles: its value once per triangle.
  EXPECT_EQ(attribute("face_weight").values, (std::vector<float>{0.75f, 0.75f}));
  EXPECT_TRUE(attribute("face_weight").PerFace());
}

TEST(PlyReader, RefusesTooManyAttributesAndRepeatedProperties) {
  std::string header = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n";
  std::string many = header;
  for (int k = 0; k < 17; ++k) many += "property float a" + std::to_string(k) + "\n";
  EXPECT_NE(ErrorOf(many + "end_header\n", "ply").find("more than 16 attributes"), std::string::npos);
  EXPECT_NE(ErrorOf(header + "property float x\nend_header\n", "ply").find("two properties 'x'"), std::string::npos);
}

TEST(ObjReader, RefusesIndicesOutOfRange) {
  for (const std::string face : {"f 1 2 99999999999\n", "f 1 2 5\n", "f -1 -2 -5\n", "f 1 2 -2147483648\n",
                                 "f 1 2 3 9\n", "f 0 1 2\n"})
    EXPECT_NE(ErrorOf(kObjVertices + face, "obj"), "") << face;
  EXPECT_NE(ErrorOf("f -1 -2 -3\n", "obj").find("out of range (0 vertices)"), std::string::npos);
  EXPECT_NE(ErrorOf(kObjVertices + "l 1 2\np 1\n", "obj").find("has no faces"), std::string::npos);
}

TEST(ObjReader, RefusesWordsWhereNumbersGo) {
  // tinyobjloader reads "nan" and "inf" as 0: the vertex moved, silently.
  for (const std::string line : {"v nan 0 0\n", "v 0 -inf 0\n", "vt 0 NaN\n", "vn 0 0 +Infinity\n"}) {
    const std::string error = ErrorOf(line + kObjVertices + "f 1 2 3\n", "obj");
    EXPECT_NE(error.find("not a finite number"), std::string::npos) << line << ": " << error;
  }
  // Numbers in every spelling tinyobjloader reads still are.
  EXPECT_EQ(ErrorOf("v -1e-3 +2.5 .5\n" + kObjVertices + "f 2 3 4\n", "obj"), "");
}

TEST(ObjReader, RefusesFacesOfMoreThan255Vertices) {
  for (int n : {255, 256, 258, 1000, 5000}) {
    std::string obj = kObjVertices + "f";
    for (int k = 0; k < n; ++k) obj.append(1, ' ').append(std::to_string(k % 4 + 1));
    obj += "\n";
    const std::string error = ErrorOf(obj, "obj");
    if (n == 255) EXPECT_EQ(error, "");
    else EXPECT_NE(error.find("a face has more than 255 vertices"), std::string::npos) << n << ": " << error;
  }
}

TEST(ObjReader, IgnoresLinesItDoesNotUse) {
  // `t` lines once cost tinyobjloader 300 KB each; `vw` weights beyond an
  // int were converted with undefined behaviour.
  std::string obj = kObjVertices + "mtllib /etc/passwd\nvw 0 1e30 1\n";
  for (int i = 0; i < 2000; ++i) obj += "t crease 8192/8192/8192\n";
  obj += "# " + std::string(1 << 20, 'x') + "\nf 1 2 3\n";
  EXPECT_EQ(ParseMesh(obj, "obj", "x.obj").indices, (std::vector<uint32_t>{0, 1, 2}));
}

// --- counting what a file makes ------------------------------------------

// A binary PLY of `fans` faces of 255 indices each, uchar counts and
// indices: a triangle per byte.
std::string PlyOfFans(int fans) {
  Bytes data(false);
  for (int i = 0; i < 255; ++i) data.Put<float>(std::cos(i * 0.0246f)).Put<float>(std::sin(i * 0.0246f)).Put<float>(0);
  for (int f = 0; f < fans; ++f) {
    data.Put<uint8_t>(255);
    for (int i = 0; i < 255; ++i) data.Put<uint8_t>(uint8_t(i));
  }
  return "ply\nformat binary_little_endian 1.0\nelement vertex 255\nproperty float x\nproperty float y\n"
         "property float z\nelement face " + std::to_string(fans) +
         "\nproperty list uchar uchar vertex_indices\nproperty float weight\nend_header\n" + data.text;
}

TEST(CountMesh, CountsTheTrianglesAndVerticesParseMeshMakes) {
  // Fans, a face attribute stored once per triangle, and the PLY's bytes.
  std::string ply = PlyOfFans(40);
  // The weight each face ends with.
  for (size_t at = ply.find("end_header\n") + 11 + 255 * 12 + 256; at <= ply.size(); at += 256 + 4)
    ply.insert(at, std::string(4, '\0'));
  const TriangleMesh parsed = ParseMesh(ply, "ply", "fans.ply");
  const MeshCounts counted = CountMesh(ply, "ply", "fans.ply");
  EXPECT_EQ(counted.triangles, 40u * 253);
  EXPECT_EQ(counted.triangles, parsed.TriangleCount());
  EXPECT_EQ(counted.vertices, parsed.positions.size());
  EXPECT_EQ(counted.attribute_values, 40u * 253);

  // OBJ: corners of positions alone are the positions; with uvs, each
  // corner may be a vertex of its own (an upper bound).
  const std::string quad_and_pentagon = kObjVertices + "v 3 3 3\nf 1 2 3 4\nf 1 2 3 4 5\n";
  const MeshCounts obj = CountMesh(quad_and_pentagon, "obj", "x.obj");
  EXPECT_EQ(obj.triangles, 5u);
  EXPECT_EQ(obj.triangles, ParseMesh(quad_and_pentagon, "obj", "x.obj").TriangleCount());
  EXPECT_EQ(obj.vertices, 5u);
  const std::string with_uvs = kObjVertices + "vt 0 0\nvt 1 0\nf 1/1 2/2 3/1\nf 1/2 3/1 4/2\n";
  EXPECT_EQ(CountMesh(with_uvs, "obj", "x.obj").vertices, 6u);
  EXPECT_GE(CountMesh(with_uvs, "obj", "x.obj").vertices, ParseMesh(with_uvs, "obj", "x.obj").positions.size());
  // The reader's memory grows with the faces, not only the file.
  EXPECT_GT(obj.parse_bytes, quad_and_pentagon.size());
}

TEST(CountMesh, RefusesWhatParseMeshRefuses) {
  const auto count_error = [](const std::string& bytes, const std::string& format) -> std::string {
    try {
      CountMesh(bytes, format, "x." + format);
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  };
  // Faces without their weights, the last cut short.
  std::string truncated = PlyOfFans(3);
  truncated.erase(truncated.find("property float weight\n"), 22);
  truncated.resize(truncated.size() - 100);
  EXPECT_EQ(count_error(truncated, "ply"), ErrorOf(truncated, "ply"));
  EXPECT_NE(count_error(truncated, "ply"), "");
  EXPECT_EQ(count_error("v nan 0 0\nf 1 1 1\n", "obj"), ErrorOf("v nan 0 0\nf 1 1 1\n", "obj"));
  EXPECT_EQ(count_error("v 0 0 0\n", "stl"), ErrorOf("v 0 0 0\n", "stl"));
}

TEST(MeshReader, NamesTheFormatItDoesNotKnow) {
  EXPECT_EQ(ErrorOf("", "stl"), "mesh 'x.stl': unknown format 'stl' (obj or ply)");
}

// A unit cube's corner: three right angles, so the normal is the diagonal.
TEST(AngleWeightedNormals, ACubeCornerPointsAlongTheDiagonal) {
  TriangleMesh corner;
  corner.positions = {{0, 0, 0}, {-1, 0, 0}, {0, -1, 0}, {0, 0, -1}, {-1, -1, 0}, {0, -1, -1}, {-1, 0, -1}};
  // Two triangles on each of the faces x = 0, y = 0, z = 0 at the origin,
  // wound to face +x, +y, +z.
  corner.indices = {0, 2, 5, 0, 5, 3, 0, 3, 6, 0, 6, 1, 0, 1, 4, 0, 4, 2};
  const std::vector<Vec3> normals = AngleWeightedNormals(corner);
  const float d = 1 / std::sqrt(3.0f);
  EXPECT_NEAR(normals[0].x, d, 1e-6f);
  EXPECT_NEAR(normals[0].y, d, 1e-6f);
  EXPECT_NEAR(normals[0].z, d, 1e-6f);
}

// The weight is the angle, not the count or area of triangles: neither
// splitting one face into more triangles nor stretching one tilts it.
TEST(AngleWeightedNormals, DependOnTheAnglesAlone) {
  TriangleMesh roof;  // a ridge at the origin: one face tilted 30°, one 60°
  const float c30 = std::cos(0.5236f), s30 = std::sin(0.5236f), c60 = 0.5f, s60 = std::sqrt(3.0f) / 2;
  roof.positions = {{0, 0, 0}, {0, 1, 0}, {c30, 0, -s30}, {c30, 1, -s30}, {-c60, 0, -s60}, {-c60, 1, -s60}};
  roof.indices = {0, 2, 1, 2, 3, 1, 0, 1, 4, 1, 5, 4};
  TriangleMesh split = roof;  // the first face's triangle at the ridge cut in two
  split.positions.push_back({c30, 0.5f, -s30});
  split.indices = {0, 2, 6, 0, 6, 1, 2, 3, 1, 0, 1, 4, 1, 5, 4};
  TriangleMesh stretched = roof;  // the second face three times as wide
  stretched.positions[4] = stretched.positions[4] * 3;
  stretched.positions[5] = {-3 * c60, 1, -3 * s60};
  const Vec3 a = AngleWeightedNormals(roof)[0];
  for (const Vec3 b : {AngleWeightedNormals(split)[0], AngleWeightedNormals(stretched)[0]}) {
    EXPECT_NEAR(a.x, b.x, 1e-5f);
    EXPECT_NEAR(a.y, b.y, 1e-5f);
    EXPECT_NEAR(a.z, b.z, 1e-5f);
  }
  EXPECT_NEAR(Length(a), 1, 1e-5f);
  EXPECT_GT(a.y, -1e-6f);  // the ridge's normal lies in the roof's cross-section
  EXPECT_LT(std::abs(a.y), 1e-5f);
}

TEST(AngleWeightedNormals, SkipDegenerateTrianglesAndLeaveLoneVerticesZero) {
  TriangleMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 0, 0}, {5, 5, 5}};
  mesh.indices = {0, 1, 2, 0, 1, 3};  // the second is a line
  const std::vector<Vec3> normals = AngleWeightedNormals(mesh);
  EXPECT_EQ(normals[0].z, 1.0f);
  EXPECT_EQ(normals[3].x, 0.0f);
  EXPECT_EQ(Length(normals[3]), 0.0f);
  EXPECT_EQ(Length(normals[4]), 0.0f);
}

}  // namespace
}  // namespace yarf
