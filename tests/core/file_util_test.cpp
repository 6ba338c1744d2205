#include "core/io/file_util.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/error.hpp"
#include "tests/cli_util.hpp"

namespace lasercell::io {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

using ::lasercell::test::TestDir;

TEST(FileUtilTest, AtomicWriteReplacesAndReadsBack) {
  const TestDir scratch("fileutil");
  const fs::path& dir = scratch.path();
  const std::string path = (dir / "a.bin").string();
  std::string bytes("abc\0def", 7);
  WriteFileAtomically(path, bytes);
  EXPECT_EQ(ReadFileBytes(path), bytes);
  WriteFileAtomically(path, "second");
  EXPECT_EQ(ReadFileBytes(path), "second");
  int entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++entries;
  EXPECT_EQ(entries, 1) << "temporary file left behind";
}

TEST(FileUtilTest, WriteIntoMissingFolderFailsClearly) {
  try {
    WriteFileAtomically("/nonexistent_lasercell_dir/x.yaml", "x");
    FAIL();
  } catch (const FileError& e) {
    EXPECT_THAT(e.what(), HasSubstr("/nonexistent_lasercell_dir/x.yaml"));
    EXPECT_THAT(e.what(), HasSubstr("does not exist"));
  }
}

TEST(FileUtilTest, ReadMissingOrDirectoryFailsClearly) {
  EXPECT_THROW(ReadFileBytes("/nonexistent_lasercell_file.ply"), FileError);
  try {
    ReadFileBytes(fs::temp_directory_path().string());
    FAIL();
  } catch (const FileError& e) {
    EXPECT_THAT(e.what(), HasSubstr("is a directory"));
  }
}

TEST(FileUtilTest, MappedFileSeesTheBytesAndFailsClearly) {
  const TestDir scratch("mapped");
  const fs::path& dir = scratch.path();
  const std::string path = (dir / "m.bin").string();
  WriteFileAtomically(path, std::string("xyz\0w", 5));
  {
    MappedFile mapped(path);
    EXPECT_EQ(mapped.bytes(), std::string_view("xyz\0w", 5));
    MappedFile moved(std::move(mapped));
    EXPECT_EQ(moved.bytes().size(), 5u);
    EXPECT_TRUE(mapped.bytes().empty());
  }
  WriteFileAtomically(path, "");
  EXPECT_TRUE(MappedFile(path).bytes().empty());
  try {
    MappedFile missing((dir / "missing.ply").string());
    FAIL();
  } catch (const FileError& e) {
    EXPECT_THAT(e.what(), HasSubstr("missing.ply: cannot open"));
  }
}

TEST(FileUtilTest, LowerExtension) {
  EXPECT_EQ(LowerExtension("a/b/Scene.PLY"), ".ply");
  EXPECT_EQ(LowerExtension("x.pcd"), ".pcd");
  EXPECT_EQ(LowerExtension("noext"), "");
}

}  // namespace
}  // namespace lasercell::io
