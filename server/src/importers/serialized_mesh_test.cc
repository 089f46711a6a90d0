#include "importers/serialized_mesh.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <cstring>

#include "importers/importer_test_support.h"
#include "importers/scene_folder.h"

namespace yarf::importers {
namespace {

const SourceLocation kHere{"test.xml", 3};

// A serialized file of one shape: its header, then `data` compressed.
std::string OneShape(const std::string& data, uint16_t version = 4) {
  std::string file = {char(0x1C), char(0x04), char(version & 0xFF), char(version >> 8)};
  uLongf size = compressBound(uLong(data.size()));
  std::string compressed(size, '\0');
  EXPECT_EQ(compress2(reinterpret_cast<Bytef*>(compressed.data()), &size,
                      reinterpret_cast<const Bytef*>(data.data()), uLong(data.size()), 9),
            Z_OK);
  compressed.resize(size);
  return file + compressed;
}

template <typename T>
void Put(std::string& out, T value) {
  out.append(reinterpret_cast<const char*>(&value), sizeof(T));
}

// A shape's uncompressed data: flags, name (version 4), counts.
std::string ShapeData(uint32_t flags, const std::string& name, uint64_t vertices, uint64_t triangles) {
  std::string data;
  Put(data, flags);
  data += name;
  data += '\0';
  Put(data, vertices);
  Put(data, triangles);
  return data;
}

// One triangle at single precision.
std::string Triangle() {
  std::string data = ShapeData(0, "t", 3, 1);
  for (float v : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) Put(data, v);
  for (uint32_t i : {0u, 1u, 2u}) Put(data, i);
  return data;
}

std::string ErrorOf(const std::string& file, uint64_t shape_index = 0) {
  try {
    DecodeSerializedMesh(file, shape_index, kHere);
  } catch (const ImportError& e) {
    return e.what();
  }
  return "";
}

std::string TwoShapes() { return ReadTextFile(testing::TestScene("assets/two_shapes.serialized"), kHere); }

TEST(SerializedMesh, DecodesEachShapeOfTheFile) {
  const SerializedMesh first = DecodeSerializedMesh(TwoShapes(), 0, kHere);
  EXPECT_EQ(first.name, "triangle");
  EXPECT_EQ(first.positions, (std::vector<float>{0, 0, 0, 1, 0, 0, 0, 1, 0}));
  EXPECT_EQ(first.indices, (std::vector<uint32_t>{0, 1, 2}));
  const SerializedMesh second = DecodeSerializedMesh(TwoShapes(), 1, kHere);  // double precision
  EXPECT_EQ(second.name, "square");
  EXPECT_EQ(second.positions.size(), 12u);
  EXPECT_EQ(second.positions[3], 2.0f);
  EXPECT_EQ(second.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3}));
}

TEST(SerializedMesh, RejectsMissingShapesAndDamagedData) {
  EXPECT_THROW(DecodeSerializedMesh(TwoShapes(), 2, kHere), ImportError);
  EXPECT_THROW(DecodeSerializedMesh("not a mesh", 0, kHere), ImportError);
  std::string cut = TwoShapes();
  cut.resize(30);  // inside the first shape's zlib stream
  EXPECT_THROW(DecodeSerializedMesh(cut, 0, kHere), ImportError);
  try {
    DecodeSerializedMesh("", 0, kHere);
    FAIL();
  } catch (const ImportError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("test.xml:3: ", 0), 0u) << e.what();
  }
}

TEST(SerializedMesh, ReadsAShapeBuiltHere) {
  const SerializedMesh mesh = DecodeSerializedMesh(OneShape(Triangle()), 0, kHere);
  EXPECT_EQ(mesh.name, "t");
  EXPECT_EQ(mesh.positions, (std::vector<float>{0, 0, 0, 1, 0, 0, 0, 1, 0}));
  EXPECT_EQ(mesh.indices, (std::vector<uint32_t>{0, 1, 2}));
}

TEST(SerializedMesh, RefusesCountsTheCompressedBytesCannotHold) {
  // 2·10⁹ vertices in a few dozen bytes: refused before inflating.
  const std::string error = ErrorOf(OneShape(ShapeData(0, "big", 2000000000, 1)));
  EXPECT_NE(error.find("more than the limit"), std::string::npos) << error;
  const std::string claims = ErrorOf(OneShape(ShapeData(0, "big", 1000000, 1)));
  EXPECT_NE(claims.find("declares 1000000 vertices and 1 triangles, but its"), std::string::npos) << claims;
  EXPECT_NE(ErrorOf(OneShape(ShapeData(0, "", uint64_t(1) << 40, 1))).find("more than a shape may hold"),
            std::string::npos);
  EXPECT_NE(ErrorOf(OneShape(ShapeData(0, "", 3, uint64_t(-1)))).find("more than a shape may hold"),
            std::string::npos);
}

TEST(SerializedMesh, RefusesShapesThatInflateBeyondTheLimit) {
  // Counts that call for 3 GiB are refused before inflating any of it
  // (the reader once inflated up to 4 GiB before reading the counts).
  std::string data = ShapeData(0x2000, "", uint64_t(1) << 27, 1);  // 3 GiB of doubles
  const std::string error = ErrorOf(OneShape(data));
  EXPECT_NE(error.find("more than the limit of 1073741824"), std::string::npos) << error;
}

TEST(SerializedMesh, InflatesOnlyWhatTheCountsNeed) {
  // A valid shape followed by 64 MiB of zeros in the same stream.
  std::string data = Triangle();
  data.append(64 << 20, '\0');
  EXPECT_EQ(DecodeSerializedMesh(OneShape(data), 0, kHere).indices, (std::vector<uint32_t>{0, 1, 2}));
  // A stream that ends before the counts' bytes.
  std::string cut = Triangle();
  cut.resize(cut.size() - 1);
  EXPECT_NE(ErrorOf(OneShape(cut)).find("data ends early"), std::string::npos) << ErrorOf(OneShape(cut));
}

TEST(SerializedMesh, RefusesBadValuesNamesAndOffsets) {
  std::string far = ShapeData(0x2000, "", 3, 1);
  for (double v : {1e300, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0}) Put(far, v);
  for (uint32_t i : {0u, 1u, 2u}) Put(far, i);
  EXPECT_NE(ErrorOf(OneShape(far)).find("not finite"), std::string::npos);
  std::string out_of_range = Triangle();
  out_of_range[out_of_range.size() - 1] = 3;
  EXPECT_NE(ErrorOf(OneShape(out_of_range)).find("index is out of range"), std::string::npos);
  // A name that never ends.
  std::string name = ShapeData(0, "", 3, 1);
  name.resize(4);
  name.append(1 << 20, 'n');
  EXPECT_NE(ErrorOf(OneShape(name)).find("shape name longer than 65536 bytes"), std::string::npos);
  // Shape tables whose count or offsets point outside the file.
  std::string table = OneShape(Triangle());
  Put(table, uint64_t(0));
  Put(table, uint64_t(1) << 40);
  Put(table, uint32_t(2));
  EXPECT_NE(ErrorOf(table, 1).find("bad offset of shape 1"), std::string::npos) << ErrorOf(table, 1);
  std::string huge_count = OneShape(Triangle());
  Put(huge_count, uint32_t(0xFFFFFFFF));
  EXPECT_NE(ErrorOf(huge_count, 5).find("truncated shape table"), std::string::npos);
  EXPECT_NE(ErrorOf(huge_count, uint64_t(1) << 40).find("but the file has"), std::string::npos);
}

}  // namespace
}  // namespace yarf::importers
