#include "importers/serialized_mesh.h"

#include <gtest/gtest.h>

#include "importers/importer_test_support.h"
#include "importers/scene_folder.h"

namespace yarf::importers {
namespace {

const SourceLocation kHere{"test.xml", 3};

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

}  // namespace
}  // namespace yarf::importers
