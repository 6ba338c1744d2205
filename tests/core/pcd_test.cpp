// PCD reader/writer: round trips (binary, ascii), PCL's real test files (binary_compressed,
// organized Kinect scene), hand-made LZF streams (valid and corrupt) and rejected headers.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <limits>

#include "core/io/lzf.hpp"
#include "core/io/point_cloud_io.hpp"
#include "tests/cli_util.hpp"
#include "tests/core/io_test_util.hpp"

namespace lasercell::io {
namespace {

using test::AsFloat;
using test::Bytes;
using test::FileErrorMessage;
using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::Not;

constexpr const char* kXyzHeader =
    "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 4\nHEIGHT 1\n"
    "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 4\nDATA binary_compressed\n";

/// A 4-point x y z binary_compressed file around the LZF stream `lzf`.
std::string CompressedPcd(const Bytes& lzf, std::uint32_t uncompressed = 48) {
  return Bytes()
      .Text(kXyzHeader)
      .Le(static_cast<std::uint32_t>(lzf.str().size()))
      .Le(uncompressed)
      .Text(lzf.str())
      .str();
}

/// x = 1 1 1 1 (a literal and an overlapping back reference), y = 2 3 4 5 (a literal),
/// z = 1 1 2 3 (a back reference to the start of x, then a literal).
Bytes ValidLzf() {
  return Bytes()
      .Raw({3})
      .Le(1.f)
      .Raw({0xE0, 3, 3})  // length 7 + 3 + 2 = 12, distance 3 + 1 = 4: repeats the 1.0f
      .Raw({15})
      .Le(2.f, 3.f, 4.f, 5.f)
      .Raw({0xC0, 31})  // length 6 + 2 = 8, distance 32: the first two x values
      .Raw({7})
      .Le(2.f, 3.f);
}

void ExpectSameCloud(const PointCloud& written, const PointCloud& read, bool double_positions) {
  ASSERT_EQ(read.size(), written.size());
  ASSERT_EQ(read.FieldNames(), written.FieldNames());
  for (std::size_t i = 0; i < written.size(); ++i) {
    const Eigen::Vector3d p =
        double_positions ? written.positions[i] : AsFloat(written.positions[i]);
    ASSERT_EQ(read.positions[i], p) << "point " << i;
    ASSERT_EQ(read.normals[i], AsFloat(written.normals[i])) << "point " << i;
    ASSERT_EQ(read.intensity[i], written.intensity[i]);
    ASSERT_EQ(read.profile[i], written.profile[i]);
    ASSERT_EQ(read.column[i], written.column[i]);
    ASSERT_EQ(read.timestamp_s[i], written.timestamp_s[i]);
  }
  EXPECT_EQ(read.grid_rows, written.grid_rows);
  EXPECT_EQ(read.grid_cols, written.grid_cols);
}

TEST(PcdRoundTrip, BinaryAndAsciiAllAttributes) {
  const PointCloud cloud = test::MakeFullCloud(400, 9);
  for (const bool binary : {true, false}) {
    for (const bool as_double : {false, true}) {
      SCOPED_TRACE(std::string(binary ? "binary" : "ascii") + (as_double ? " double" : " float"));
      WriteOptions options;
      options.pcd_binary = binary;
      options.positions_as_double = as_double;
      ReadReport report;
      const PointCloud read = ParsePcd(EncodePcd(cloud, options), "mem.pcd", &report);
      ExpectSameCloud(cloud, read, as_double);
      EXPECT_TRUE(read.IsOrganized());
      EXPECT_EQ(report.format, binary ? "pcd binary" : "pcd ascii");
      EXPECT_EQ(report.lasercell_format_version, 1);
      EXPECT_TRUE(report.ignored_fields.empty());
    }
  }
}

TEST(PcdRoundTrip, ThroughFileWithPlainCloud) {
  const ::lasercell::test::TestDir dir("io");
  PointCloud cloud;
  cloud.positions = {{1.5, -2.25, 3}, {400, 500, 600.125}};
  const std::string path = dir.File("plain.PCD");  // extension is case-insensitive
  WritePointCloud(path, cloud);
  ReadReport report;
  const PointCloud read = ReadPointCloud(path, &report);
  EXPECT_EQ(read.positions, cloud.positions);
  EXPECT_EQ(read.FieldNames(), "x y z");
  EXPECT_EQ(read.grid_rows, 0);
}

TEST(PcdWrite, HeaderDeclaresFieldsSizesTypes) {
  const std::string pcd = EncodePcd(test::MakeFullCloud(3, 3), {});
  EXPECT_THAT(pcd, HasSubstr("# lasercell_format 1\n# lasercell_grid 1 3\nVERSION 0.7\n"));
  EXPECT_THAT(pcd, HasSubstr("FIELDS x y z normal_x normal_y normal_z intensity profile column "
                             "timestamp\nSIZE 4 4 4 4 4 4 4 4 4 8\nTYPE F F F F F F F I I F\n"));
  EXPECT_THAT(pcd,
              HasSubstr("WIDTH 3\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA binary\n"));
}

TEST(PcdReal, MilkCompressed) {
  LASERCELL_REAL_FILE(path, "pcl", "milk.pcd");
  ReadReport report;
  const PointCloud cloud = ReadPointCloud(path, &report);
  EXPECT_EQ(report.format, "pcd binary_compressed");
  ASSERT_EQ(cloud.size(), 13704u);
  // Reference values from PCL 1.13 pcl::io::loadPCDFile on the same file.
  EXPECT_EQ(cloud.positions[0], AsFloat({-0.131607607, -0.2095429, 0.772000015}));
  double sum_x = 0;
  for (const auto& p : cloud.positions) sum_x += p.x();
  EXPECT_NEAR(sum_x, -770.304111, 1e-5);
  EXPECT_THAT(report.unit_hint, HasSubstr("looks like metres"));
}

TEST(PcdReal, KinectSceneOrganizedWithNansDropped) {
  LASERCELL_REAL_FILE(path, "pcl", "milk_cartoon_all_small_clorox.pcd");
  ReadReport report;
  const PointCloud cloud = ReadPointCloud(path, &report);
  EXPECT_EQ(report.points_in_file, 640u * 480u);
  // PCL counts 241407 finite points of 307200.
  ASSERT_EQ(cloud.size(), 241407u);
  EXPECT_EQ(report.dropped_non_finite, 307200u - 241407u);
  EXPECT_TRUE(cloud.IsOrganized());
  EXPECT_EQ(cloud.grid_rows, 480);
  EXPECT_EQ(cloud.grid_cols, 640);
  EXPECT_THAT(report.ignored_fields, ElementsAre("rgba"));
  // First finite point is PCL's index 10814 = row 16, column 574.
  EXPECT_EQ(cloud.profile[0], 16);
  EXPECT_EQ(cloud.column[0], 574);
  EXPECT_EQ(cloud.positions[0], AsFloat({0.965645671, -0.848022878, 1.99199998}));
  double sum_x = 0;
  for (const auto& p : cloud.positions) sum_x += p.x();
  EXPECT_NEAR(sum_x, 2189.21545, 1e-4);
  const BoundingBox box = cloud.Bounds();  // a table-top scene 0.5 - 2.1 m from a Kinect
  EXPECT_GT(box.min.z(), 0.4);
  EXPECT_LT(box.max.z(), 2.2);
}

TEST(PcdReal, BunnyViewsAscii) {
  LASERCELL_REAL_FILE(bun0, "pcl", "bun0.pcd");
  LASERCELL_REAL_FILE(bun4, "pcl", "bun4.pcd");
  ReadReport report;
  const PointCloud view0 = ReadPointCloud(bun0, &report);
  EXPECT_EQ(view0.size(), 397u);
  EXPECT_TRUE(view0.HasNormals());
  EXPECT_THAT(report.ignored_fields, ElementsAre("curvature"));
  EXPECT_EQ(view0.positions[0], AsFloat({0.0054215998, 0.11349, 0.040748999}));
  const PointCloud view4 = ReadPointCloud(bun4, &report);  // PCD v.5: no VIEWPOINT line
  EXPECT_EQ(view4.size(), 361u);
  EXPECT_FALSE(view4.HasNormals());
  EXPECT_LT(view4.Bounds().Diagonal(), 0.3);  // metres: a ~15 cm bunny
}

TEST(PcdRead, CompressedBackReferences) {
  ReadReport report;
  const PointCloud cloud = ParsePcd(CompressedPcd(ValidLzf()), "lzf.pcd", &report);
  EXPECT_THAT(cloud.positions, ElementsAre(Eigen::Vector3d(1, 2, 1), Eigen::Vector3d(1, 3, 1),
                                           Eigen::Vector3d(1, 4, 2), Eigen::Vector3d(1, 5, 3)));
}

TEST(PcdRead, OrganizedAsciiGridCellsKeptNansDropped) {
  const std::string pcd =
      "# .PCD v.7\nVERSION .7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\n"
      "WIDTH 3\nHEIGHT 2\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 6\nDATA ascii\n"
      "1 2 3 4278190080\nnan nan nan 0\n4 5 6 1\n7 8 9 2\n10 11 nan 3\n13 14 15 4\n";
  ReadReport report;
  const PointCloud cloud = ParsePcd(pcd, "grid.pcd", &report);
  ASSERT_EQ(cloud.size(), 4u);
  EXPECT_EQ(report.dropped_non_finite, 2u);
  EXPECT_EQ(cloud.grid_rows, 2);
  EXPECT_EQ(cloud.grid_cols, 3);
  EXPECT_THAT(cloud.profile, ElementsAre(0, 0, 1, 1));
  EXPECT_THAT(cloud.column, ElementsAre(0, 2, 0, 2));
  EXPECT_EQ(cloud.positions[3], Eigen::Vector3d(13, 14, 15));
  EXPECT_THAT(report.ignored_fields, ElementsAre("rgb"));
}

// A grid of HEIGHT rows and no columns holds no point: the cloud is empty and not organized, so
// writing and reading it again gives the same bytes (a fuzzer's finding).
TEST(PcdRead, HeightWithoutWidthIsAnEmptyUnorganizedCloud) {
  const std::string pcd =
      "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nHEIGHT 2\n"
      "VIEWPOINT 0 0 0 1 0 0 0\nDATA ascii\n";
  const PointCloud cloud = ParsePcd(pcd, "no_width.pcd");
  EXPECT_EQ(cloud.size(), 0u);
  EXPECT_EQ(cloud.grid_rows, 0);
  EXPECT_EQ(cloud.grid_cols, 0);
  const std::string written = EncodePcd(cloud);
  EXPECT_THAT(written, Not(HasSubstr("lasercell_grid")));
  EXPECT_EQ(EncodePcd(ParsePcd(written, "written.pcd")), written);
}

// A grid size with a zero dimension is not a grid: neither writer records it, so both files
// read back (the PLY reader refuses a grid comment with a zero).
TEST(PointCloudWrite, AGridWithNoColumnsIsNotWritten) {
  PointCloud cloud;
  cloud.positions = {{1, 2, 3}, {4, 5, 6}};
  cloud.grid_rows = 2;
  const std::string pcd = EncodePcd(cloud);
  const std::string ply = EncodePly({cloud, {}});
  EXPECT_THAT(pcd, Not(HasSubstr("lasercell_grid")));
  EXPECT_THAT(ply, Not(HasSubstr("lasercell_grid")));
  EXPECT_EQ(ParsePcd(pcd, "rows_only.pcd").size(), 2u);
  EXPECT_EQ(ParsePly(ply, "rows_only.ply").vertices.size(), 2u);
}

TEST(PcdRead, BinaryMixedTypesAndMultiValueFields) {
  const std::string pcd = Bytes()
                              .Text(
                                  "VERSION 0.7\nFIELDS hist x y z intensity _\n"
                                  "SIZE 4 1 2 8 4 8\nTYPE F I U F U I\nCOUNT 3 1 1 1 1 1\n"
                                  "WIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA binary\n")
                              .Le(0.1f, 0.2f, 0.3f, std::int8_t{-5}, std::uint16_t{65535}, 0.125,
                                  std::uint32_t{7}, std::int64_t{-1})
                              .Le(0.4f, 0.5f, 0.6f, std::int8_t{127}, std::uint16_t{0}, -1e300,
                                  std::uint32_t{9}, std::int64_t{1})
                              .str();
  ReadReport report;
  const PointCloud cloud = ParsePcd(pcd, "types.pcd", &report);
  EXPECT_THAT(cloud.positions,
              ElementsAre(Eigen::Vector3d(-5, 65535, 0.125), Eigen::Vector3d(127, 0, -1e300)));
  EXPECT_THAT(cloud.intensity, ElementsAre(7.f, 9.f));
  EXPECT_THAT(report.ignored_fields, ElementsAre("hist", "_"));
  EXPECT_THAT(report.fields_in_file, ElementsAre("hist", "x", "y", "z", "intensity", "_"));
}

TEST(PcdRead, ViewpointValidatedNotApplied) {
  const std::string pcd =
      "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nHEIGHT 1\n"
      "VIEWPOINT 10 0 0 0.7071068 0 0.7071068 0\nPOINTS 1\nDATA ascii\n1 2 3\n";
  ReadReport report;
  const PointCloud cloud = ParsePcd(pcd, "vp.pcd", &report);
  EXPECT_EQ(cloud.positions[0], Eigen::Vector3d(1, 2, 3));
  ASSERT_EQ(report.notes.size(), 1u);
  EXPECT_THAT(report.notes[0], HasSubstr("VIEWPOINT is not identity; it was not applied"));
  const std::string bad =
      "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nHEIGHT 1\n"
      "VIEWPOINT 0 0 0 1 0 0\nPOINTS 1\nDATA ascii\n1 2 3\n";
  EXPECT_THAT(FileErrorMessage([&] { ParsePcd(bad, "vp.pcd"); }),
              HasSubstr("vp.pcd: header line 7: VIEWPOINT needs 7 finite numbers"));
}

TEST(PcdLzf, DecoderDirect) {
  const std::string stream = ValidLzf().str();
  std::vector<unsigned char> out(48);
  EXPECT_EQ(detail::LzfDecompress(
                {reinterpret_cast<const unsigned char*>(stream.data()), stream.size()}, out),
            "");
  std::vector<unsigned char> small(47);
  EXPECT_THAT(detail::LzfDecompress(
                  {reinterpret_cast<const unsigned char*>(stream.data()), stream.size()}, small),
              HasSubstr("would write past the declared uncompressed size 47"));
}

TEST(PcdLzf, CorruptStreamsRejected) {
  struct Case {
    Bytes lzf;
    std::uint32_t size;
    const char* problem;
  };
  const Case cases[] = {
      {Bytes().Raw({0x20, 5}), 48, "points 6 bytes back but only 0 bytes have been decompressed"},
      {Bytes().Raw({31}).Le(1.f), 48,
       "literal run of 32 bytes at input offset 0 runs past the end"},
      {Bytes().Raw({3}).Le(1.f).Raw({0xE0}), 48, "is cut off by the end of the compressed data"},
      {Bytes().Raw({3}).Le(1.f).Raw({0xE0, 200, 3}), 48,
       "would write past the declared uncompressed size 48"},
      {Bytes().Raw({3}).Le(1.f).Raw({0xE0, 3, 3}), 48,
       "decompressed to 16 bytes but the header declares 48"},
  };
  for (const Case& c : cases) {
    const std::string message =
        FileErrorMessage([&] { ParsePcd(CompressedPcd(c.lzf, c.size), "z.pcd"); });
    EXPECT_THAT(message, HasSubstr("z.pcd: corrupt binary_compressed (LZF) data: "));
    EXPECT_THAT(message, HasSubstr(c.problem));
  }
}

TEST(PcdLzf, BadBlockSizesRejected) {
  EXPECT_THAT(FileErrorMessage([] { ParsePcd(CompressedPcd(ValidLzf(), 40), "s.pcd"); }),
              HasSubstr("s.pcd: binary_compressed block decompresses to 40 bytes but POINTS 4"));
  const std::string truncated = CompressedPcd(ValidLzf());
  EXPECT_THAT(
      FileErrorMessage([&] { ParsePcd(truncated.substr(0, truncated.size() - 3), "t.pcd"); }),
      HasSubstr("t.pcd: binary_compressed block declares 36 bytes but only 33 follow"));
  // 1e8 points = 1.2 GB claimed from 36 compressed bytes: refused before allocating.
  std::string huge = CompressedPcd(ValidLzf(), 1200000000);
  huge.replace(huge.find("WIDTH 4"), 7, "WIDTH 100000000");
  huge.replace(huge.find("POINTS 4"), 8, "POINTS 100000000");
  EXPECT_THAT(FileErrorMessage([&] { ParsePcd(huge, "h.pcd"); }),
              HasSubstr("h.pcd: binary_compressed block claims 1200000000 bytes from 36 "
                        "compressed bytes, more than LZF can produce"));
}

TEST(PcdRead, CorruptedFilesFailCleanly) {
  const PointCloud cloud = test::MakeFullCloud(20, 5);
  WriteOptions ascii;
  ascii.pcd_binary = false;
  for (const std::string& pcd :
       {EncodePcd(cloud), EncodePcd(cloud, ascii), CompressedPcd(ValidLzf())}) {
    test::ExpectCorruptionsRejectedCleanly(pcd, [](const std::string& bytes) {
      ParsePcd(bytes, "corrupt.pcd").Validate();  // whatever is accepted must be valid
    });
  }
}

// ---- rejected headers and data: each message names the file and the problem ----

std::string Header(const std::string& fields, const std::string& points, const std::string& data) {
  return "VERSION 0.7\n" + fields + "WIDTH " + points + "\nHEIGHT 1\nPOINTS " + points + "\nDATA " +
         data + "\n";
}
constexpr const char* kXyz = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n";

TEST(PcdReject, HeaderProblems) {
  struct Case {
    std::string pcd;
    const char* problem;
  };
  const Case cases[] = {
      {"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\n", "missing 'DATA' line"},
      {"\x89PNG\r\n", "header line 1: not a PCD file"},
      {Header("FIELDS x y z\nSIZE 4 4\nTYPE F F F\n", "1", "ascii"),
       "FIELDS lists 3 fields but SIZE has 2"},
      {Header("FIELDS x y z\nSIZE 4 4 4\nTYPE F F D\n", "1", "ascii"),
       "field 'z' has TYPE 'D' with SIZE '4'"},
      {Header("FIELDS x y z\nSIZE 4 4 2\nTYPE F F F\n", "1", "ascii"),
       "field 'z' has TYPE 'F' with SIZE '2'"},
      {Header("FIELDS w y z\nSIZE 4 4 4\nTYPE F F F\n", "1", "ascii"),
       "FIELDS has no single-valued field 'x'"},
      {Header("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 2 1 1\n", "1", "ascii"),
       "FIELDS has no single-valued field 'x'"},
      {"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 4\nHEIGHT 1\nPOINTS 5\n"
       "DATA ascii\n",
       "POINTS 5 does not equal WIDTH 4 x HEIGHT 1"},
      {Header(kXyz, "1", "binary_zipped"), "DATA must be ascii, binary or binary_compressed"},
      {"VERSION 0.7\nFIELDS x y z\nSIZES 4 4 4\n", "header line 3: unknown keyword 'SIZES'"},
  };
  for (const Case& c : cases) {
    const std::string message = FileErrorMessage([&] { ParsePcd(c.pcd, "h.pcd"); });
    EXPECT_THAT(message, HasSubstr("h.pcd: "));
    EXPECT_THAT(message, HasSubstr(c.problem));
  }
}

// A 4e9-point header in a tiny file: reserving first would throw std::bad_alloc (or abort
// under ASan) instead of the FileError these tests expect.
TEST(PcdReject, HugePointCountRejectedBeforeAllocation) {
  const std::string binary = Header(kXyz, "4000000000", "binary") + "0123456789ab";
  EXPECT_THAT(FileErrorMessage([&] { ParsePcd(binary, "huge.pcd"); }),
              HasSubstr("huge.pcd: POINTS 4000000000 of 12 bytes need more than the 12 bytes"));
  const std::string ascii = Header(kXyz, "4000000000", "ascii") + "1 2 3\n";
  EXPECT_THAT(FileErrorMessage([&] { ParsePcd(ascii, "huge.pcd"); }),
              HasSubstr("huge.pcd: POINTS 4000000000 with 3 values each cannot fit in 6 bytes"));
}

TEST(PcdReject, TruncatedBinary) {
  const std::string pcd =
      Bytes().Text(Header(kXyz, "3", "binary")).Le(1.f, 2.f, 3.f, 4.f, 5.f, 6.f, 7.f, 8.f).str();
  EXPECT_THAT(FileErrorMessage([&] { ParsePcd(pcd, "cut.pcd"); }),
              HasSubstr("cut.pcd: POINTS 3 of 12 bytes need more than the 32 bytes of binary "
                        "data; the file is truncated"));
}

TEST(PcdReject, TruncatedAndMalformedAscii) {
  const std::string cut =
      Header(kXyz, "3", "ascii") + "1.25 2.25 3.25\n4.25 5.25 6.25\n7.25 8.25\n";
  EXPECT_THAT(FileErrorMessage([&] { ParsePcd(cut, "cut.pcd"); }),
              HasSubstr("cut.pcd: data ends at point 2 of 3 (field 'z')"));
  const std::string bad = Header(kXyz, "2", "ascii") + "1 2 3\n4 5,5 6\n";
  EXPECT_THAT(FileErrorMessage([&] { ParsePcd(bad, "bad.pcd"); }),
              HasSubstr("bad.pcd: point 1 (line 11): malformed number '5,5' for field 'y'"));
}

}  // namespace
}  // namespace lasercell::io
