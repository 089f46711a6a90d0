#include "kernel/inflate.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <stdexcept>
#include <string>

#include "kernel/mesh_io.h"
#include "yarf/error.h"

namespace yarf {
namespace {

// `text` deflated with a gzip header (gzip = true) or a zlib one.
std::string Deflated(const std::string& text, bool gzip) {
  z_stream stream{};
  EXPECT_EQ(deflateInit2(&stream, 9, Z_DEFLATED, gzip ? 16 + 15 : 15, 8, Z_DEFAULT_STRATEGY), Z_OK);
  std::string out(deflateBound(&stream, uLong(text.size())) + 32, '\0');
  stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(text.data()));
  stream.avail_in = uInt(text.size());
  stream.next_out = reinterpret_cast<Bytef*>(out.data());
  stream.avail_out = uInt(out.size());
  EXPECT_EQ(deflate(&stream, Z_FINISH), Z_STREAM_END);
  out.resize(stream.total_out);
  deflateEnd(&stream);
  return out;
}

TEST(Inflate, ReadsGzipFilesOfSeveralMembersAndZlibStreams) {
  const std::string text(100000, 'a');
  EXPECT_TRUE(IsGzip(Deflated(text, true)));
  EXPECT_FALSE(IsGzip(Deflated(text, false)));
  const Inflated gzip = Inflate(Deflated(text, true), 1 << 20);
  EXPECT_EQ(gzip.bytes, text);
  EXPECT_TRUE(gzip.complete);
  EXPECT_EQ(Inflate(Deflated(text, false), 1 << 20).bytes, text);
  // `cat a.gz b.gz` is one gzip file of both.
  EXPECT_EQ(Inflate(Deflated("one ", true) + Deflated("two", true), 100).bytes, "one two");
}

TEST(Inflate, StopsAtTheLimitAndRefusesDamagedData) {
  // 2^24 zeros in about 16 KB: only the limit's worth is inflated.
  const Inflated cut = Inflate(Deflated(std::string(1 << 24, '\0'), true), 1000);
  EXPECT_EQ(cut.bytes.size(), 1000u);
  EXPECT_FALSE(cut.complete);
  const std::string exact = "exactly this";
  EXPECT_TRUE(Inflate(Deflated(exact, true), exact.size()).complete);

  std::string truncated = Deflated(std::string(50000, 'x') + "tail", true);
  truncated.resize(truncated.size() / 2);
  EXPECT_THROW(Inflate(truncated, 1 << 20), std::runtime_error);
  std::string corrupt = Deflated("some text to damage", true);
  corrupt[12] = char(~corrupt[12]);
  EXPECT_THROW(Inflate(corrupt, 1 << 20), std::runtime_error);
}

TEST(Inflate, MeshFilesMayBeGzipped) {
  const std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "-1 -1 0\n1 -1 0\n1 1 0\n-1 1 0\n4 0 1 2 3\n";
  const std::string packed = Deflated(ply, true);
  const TriangleMesh mesh = ParseMesh(packed, "ply", "quad.ply.gz");
  EXPECT_EQ(mesh.indices, ParseMesh(ply, "ply", "quad.ply").indices);
  EXPECT_EQ(mesh.positions.size(), 4u);
  // Counting holds the inflated file too.
  const MeshCounts counts = CountMesh(packed, "ply", "quad.ply.gz");
  EXPECT_EQ(counts.triangles, 2u);
  EXPECT_GE(counts.parse_bytes, ply.size());
  // A gzip inside a gzip is refused (each level could take the limit).
  try {
    ParseMesh(Deflated(packed, true), "ply", "twice.ply.gz");
    ADD_FAILURE() << "a doubly compressed file was read";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("a gzip file inside a gzip file"), std::string::npos) << e.what();
  }
  std::string cut = packed;
  cut.resize(cut.size() - 10);
  EXPECT_THROW(ParseMesh(cut, "ply", "cut.ply.gz"), Error);
}

}  // namespace
}  // namespace yarf
