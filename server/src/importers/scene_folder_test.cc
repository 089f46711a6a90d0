#include "importers/scene_folder.h"

#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <filesystem>
#include <fstream>

#include "importers/import_error.h"

namespace yarf::importers {
namespace {

namespace fs = std::filesystem;

const SourceLocation kHere{"scene.pbrt", 7};

// A fresh folder, removed at the end.
class TempFolder {
 public:
  TempFolder() {
    std::string pattern = (fs::temp_directory_path() / "yarf-scene-folder-XXXXXX").string();
    path_ = ::mkdtemp(pattern.data());
  }
  ~TempFolder() { fs::remove_all(path_); }
  fs::path File(const std::string& name, const std::string& bytes) const {
    std::ofstream(path_ / name, std::ios::binary) << bytes;
    return path_ / name;
  }
  fs::path Gzip(const std::string& name, const std::string& bytes) const {
    const fs::path file = path_ / name;
    gzFile out = gzopen(file.c_str(), "wb");
    EXPECT_EQ(gzwrite(out, bytes.data(), unsigned(bytes.size())), int(bytes.size()));
    gzclose(out);
    return file;
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

// The message of the ImportError `read` throws, or "" if it throws none.
template <typename Read>
std::string RefusalOf(Read read) {
  try {
    read();
  } catch (const ImportError& e) {
    return e.what();
  }
  return "";
}

std::string Text() {
  std::string text;
  for (int i = 0; i < 20000; ++i) text += "line " + std::to_string(i) + "\n";
  return text;
}

TEST(SceneFiles, AHeadIsTheFirstBytesOfTheFileOrOfWhatItInflatesTo) {
  const TempFolder folder;
  const std::string text = Text();
  EXPECT_EQ(ReadFileHead(folder.File("mesh.ply", text), 1000, kHere), text.substr(0, 1000));
  EXPECT_EQ(ReadFileHead(folder.Gzip("mesh.ply.gz", text), 1000, kHere), text.substr(0, 1000));
  // A file shorter than the head asked for is read whole.
  EXPECT_EQ(ReadFileHead(folder.File("short.ply", "ply\n"), 1000, kHere), "ply\n");
  EXPECT_EQ(ReadFileHead(folder.Gzip("short.ply.gz", "ply\n"), 1000, kHere), "ply\n");
}

TEST(SceneFiles, ATextFileIsReadWholeAndInflatedWhenCompressed) {
  const TempFolder folder;
  const std::string text = Text();
  EXPECT_EQ(ReadTextFile(folder.File("scene.pbrt", text), kHere), text);
  EXPECT_EQ(ReadTextFile(folder.Gzip("scene.pbrt.gz", text), kHere), text);
  EXPECT_EQ(ReadTextFile(folder.File("empty.pbrt", ""), kHere), "");
}

TEST(SceneFiles, FilesThatCannotBeReadAreRefusedWithTheirNameAndWhere) {
  const TempFolder folder;
  for (const auto read : {+[](const fs::path& f) { ReadTextFile(f, kHere); },
                          +[](const fs::path& f) { ReadFileHead(f, 64, kHere); }}) {
    const std::string missing = RefusalOf([&] { read(folder.path() / "missing.pbrt"); });
    EXPECT_NE(missing.find("scene.pbrt:7"), std::string::npos) << missing;
    EXPECT_NE(missing.find("missing.pbrt' not found"), std::string::npos) << missing;
    EXPECT_NE(RefusalOf([&] { read(folder.path()); }).find("not found"), std::string::npos);
    // A gzip header followed by bytes that are no deflate stream.
    const fs::path damaged = folder.File("damaged.pbrt.gz", std::string("\x1f\x8b\x08\x00", 4) + "not deflate");
    EXPECT_NE(RefusalOf([&] { read(damaged); }).find("gzip file '" + damaged.string() + "'"), std::string::npos);
  }
}

}  // namespace
}  // namespace yarf::importers
