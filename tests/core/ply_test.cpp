// PLY reader/writer: round trips in all three encodings, real UWA files, meshes, foreign
// layouts (big endian, permuted properties, extra elements, every scalar type) and every
// rejected input with the message it must give.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>

#include "core/io/file_util.hpp"
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

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

/// Every attribute of `read` equals `written` stored as the writer stores it.
void ExpectSameCloud(const PointCloud& written, const PointCloud& read, bool double_positions) {
  ASSERT_EQ(read.size(), written.size());
  ASSERT_EQ(read.FieldNames(), written.FieldNames());
  for (std::size_t i = 0; i < written.size(); ++i) {
    const Eigen::Vector3d p =
        double_positions ? written.positions[i] : AsFloat(written.positions[i]);
    ASSERT_EQ(read.positions[i], p) << "point " << i;  // bit-exact
    ASSERT_EQ(read.normals[i], AsFloat(written.normals[i])) << "point " << i;
    ASSERT_EQ(read.intensity[i], written.intensity[i]);
    ASSERT_EQ(read.profile[i], written.profile[i]);
    ASSERT_EQ(read.column[i], written.column[i]);
    ASSERT_EQ(read.timestamp_s[i], written.timestamp_s[i]);
  }
  EXPECT_EQ(read.grid_rows, written.grid_rows);
  EXPECT_EQ(read.grid_cols, written.grid_cols);
}

class PlyRoundTripTest : public ::testing::TestWithParam<PlyEncoding> {};

TEST_P(PlyRoundTripTest, AllAttributesFloatPositions) {
  const PointCloud cloud = test::MakeFullCloud(500);
  WriteOptions options;
  options.ply_encoding = GetParam();
  ReadReport report;
  const TriangleMesh mesh = ParsePly(EncodePly({cloud, {}}, options), "mem.ply", &report);
  ExpectSameCloud(cloud, mesh.vertices, false);
  EXPECT_TRUE(mesh.vertices.IsOrganized());
  EXPECT_EQ(report.lasercell_format_version, 1);
  EXPECT_EQ(report.points_in_file, 500u);
  EXPECT_EQ(report.dropped_non_finite, 0u);
  EXPECT_TRUE(report.ignored_fields.empty());
  EXPECT_THAT(report.fields_in_file, ElementsAre("x", "y", "z", "nx", "ny", "nz", "intensity",
                                                 "profile", "column", "timestamp"));
}

TEST_P(PlyRoundTripTest, DoublePositionsAreExact) {
  const PointCloud cloud = test::MakeFullCloud(300, 11, 7);
  WriteOptions options;
  options.ply_encoding = GetParam();
  options.positions_as_double = true;
  const TriangleMesh mesh = ParsePly(EncodePly({cloud, {}}, options), "mem.ply");
  ExpectSameCloud(cloud, mesh.vertices, true);
}

TEST_P(PlyRoundTripTest, MeshThroughFile) {
  const ::lasercell::test::TestDir dir("io");
  TriangleMesh mesh;
  mesh.vertices.positions = {{0, 0, 0}, {10, 0, 0}, {10, 10, 0}, {0, 10, 0.5}};
  mesh.faces = {{0, 1, 2}, {0, 2, 3}};
  WriteOptions options;
  options.ply_encoding = GetParam();
  const std::string path = dir.File("mesh.ply");
  WritePlyMesh(path, mesh, options);
  ReadReport report;
  const TriangleMesh read = ReadPlyMesh(path, &report);
  EXPECT_EQ(read.vertices.positions, mesh.vertices.positions);
  EXPECT_EQ(read.faces, mesh.faces);
  EXPECT_EQ(report.faces, 2u);
  EXPECT_EQ(read.vertices.FieldNames(), "x y z");
}

INSTANTIATE_TEST_SUITE_P(PlyEncodings, PlyRoundTripTest,
                         ::testing::Values(PlyEncoding::kBinaryLittleEndian,
                                           PlyEncoding::kBinaryBigEndian, PlyEncoding::kAscii),
                         [](const auto& info) {
                           switch (info.param) {
                             case PlyEncoding::kBinaryLittleEndian:
                               return "BinaryLittleEndian";
                             case PlyEncoding::kBinaryBigEndian:
                               return "BinaryBigEndian";
                             case PlyEncoding::kAscii:
                               return "Ascii";
                           }
                           return "Unknown";
                         });

TEST(PlyWrite, HeaderNamesFormatGridAndTypes) {
  PointCloud cloud = test::MakeFullCloud(4, 2);
  const std::string bytes = EncodePly({cloud, {}}, {});
  EXPECT_THAT(bytes, HasSubstr("format binary_little_endian 1.0\ncomment lasercell_format 1\n"
                               "comment lasercell_grid 2 2\nelement vertex 4\n"
                               "property float x\n"));
  EXPECT_THAT(bytes, HasSubstr("property int profile\nproperty int column\n"
                               "property double timestamp\nend_header\n"));
  WriteOptions ascii;
  ascii.ply_encoding = PlyEncoding::kAscii;
  ascii.positions_as_double = true;
  EXPECT_THAT(EncodePly({cloud, {}}, ascii), HasSubstr("format ascii 1.0\n"));
  EXPECT_THAT(EncodePly({cloud, {}}, ascii), HasSubstr("property double x\n"));
}

TEST(PlyWrite, RejectsInvalidCloudAndLeavesNoFile) {
  const ::lasercell::test::TestDir dir("io");
  PointCloud cloud;
  cloud.positions = {{1, 2, 3}, {kNan, 0, 0}};
  const std::string path = dir.File("bad.ply");
  EXPECT_THROW(WritePointCloud(path, cloud), InputError);
  EXPECT_FALSE(std::filesystem::exists(path));
  TriangleMesh mesh;
  mesh.vertices.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.faces = {{0, 1, 3}};
  try {
    WritePlyMesh(path, mesh);
    ADD_FAILURE() << "face index 3 of 3 vertices accepted";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("references vertex 3"));
  }
}

TEST(PlyReal, Parasaurolophus) {
  LASERCELL_REAL_FILE(path, "uwa", "parasaurolophus_6700.ply");
  ReadReport report;
  const TriangleMesh mesh = ReadPlyMesh(path, &report);
  EXPECT_EQ(report.format, "ply ascii");
  EXPECT_EQ(mesh.vertices.size(), 6700u);
  EXPECT_TRUE(mesh.vertices.HasNormals());
  EXPECT_EQ(mesh.faces.size(), 9140u);
  const BoundingBox box = mesh.vertices.Bounds();
  // A ~23 cm model about 0.6 m in front of the scanner, in mm.
  EXPECT_NEAR(box.min.x(), -55.15, 0.01);
  EXPECT_NEAR(box.max.x(), 174.85, 0.01);
  EXPECT_NEAR(box.min.z(), -686.02, 0.01);
  EXPECT_GT(box.Diagonal(), 200.0);
  EXPECT_LT(box.Diagonal(), 500.0);
  EXPECT_TRUE(report.unit_hint.empty());
  EXPECT_EQ(mesh.vertices.positions[0], AsFloat({-47.1494, -13.58, -686.019}));
}

TEST(PlyReal, Rs1SceneWithNormals) {
  LASERCELL_REAL_FILE(path, "uwa", "rs1_normals.bin.ply");
  ReadReport report;
  const PointCloud cloud = ReadPointCloud(path, &report);
  EXPECT_EQ(cloud.size(), 114373u);
  EXPECT_EQ(report.points_in_file, 114373u);
  EXPECT_EQ(report.faces, 221803u);
  ASSERT_TRUE(cloud.HasNormals());
  EXPECT_EQ(cloud.normals[0], AsFloat({-0.338428, -0.582821, 0.738774}));
  const BoundingBox box = cloud.Bounds();
  EXPECT_NEAR(box.min.z(), -746.39, 0.01);
  EXPECT_NEAR(box.max.z(), -566.38, 0.01);
  EXPECT_TRUE(report.unit_hint.empty());
}

TEST(PlyMesh, PolygonsAreFanned) {
  const std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\n"
      "property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n4 0 1 2 3\n5 0 1 4 2 3\n";
  ReadReport report;
  const TriangleMesh mesh = ParsePly(ply, "quad.ply", &report);
  EXPECT_THAT(mesh.faces, ElementsAre(Eigen::Vector3i(0, 1, 2), Eigen::Vector3i(0, 2, 3),
                                      Eigen::Vector3i(0, 1, 4), Eigen::Vector3i(0, 4, 2),
                                      Eigen::Vector3i(0, 2, 3)));
  EXPECT_EQ(report.faces, 5u);
}

TEST(PlyMesh, VertexIndexNameAndExtraFaceProperties) {
  // "vertex_index" (older writers), a face flag before the list and a texture list after it.
  const std::string ply =
      Bytes()
          .Text(
              "ply\nformat binary_little_endian 1.0\nelement vertex 3\n"
              "property float x\nproperty float y\nproperty float z\n"
              "element face 1\nproperty uchar flags\n"
              "property list uchar uint vertex_index\n"
              "property list uchar float texcoord\nend_header\n")
          .Le(0.f, 0.f, 0.f)  // vertices
          .Le(1.f, 0.f, 0.f)
          .Le(0.f, 1.f, 0.f)
          .Le(std::uint8_t{7})  // flags
          .Le(std::uint8_t{3}, std::uint32_t{2}, std::uint32_t{1}, std::uint32_t{0})
          .Le(std::uint8_t{2}, 0.5f, 0.25f)  // texcoord
          .str();
  const TriangleMesh mesh = ParsePly(ply, "flags.ply");
  EXPECT_THAT(mesh.faces, ElementsAre(Eigen::Vector3i(2, 1, 0)));
}

TEST(PlyMesh, FacesOfDroppedVerticesAreDroppedOthersRemapped) {
  const std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\n"
      "property float z\nelement face 3\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\nnan 1 0\n1 1 0\n0 1 0\n2 0 inf\n3 0 2 3\n3 0 1 2\n3 3 2 0\n";
  ReadReport report;
  const TriangleMesh mesh = ParsePly(ply, "holes.ply", &report);
  ASSERT_EQ(mesh.vertices.size(), 3u);
  EXPECT_EQ(mesh.vertices.positions[1], Eigen::Vector3d(1, 1, 0));
  EXPECT_THAT(mesh.faces, ElementsAre(Eigen::Vector3i(0, 1, 2), Eigen::Vector3i(2, 1, 0)));
  EXPECT_EQ(report.dropped_non_finite, 2u);
  EXPECT_EQ(report.dropped_faces, 1u);
  EXPECT_EQ(report.faces, 2u);
}

TEST(PlyRead, NonFiniteNormalsDropThePoint) {
  const std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nproperty float nx\nproperty float ny\nproperty float nz\nend_header\n"
      "1 2 3 0 0 1\n4 5 6 nan 0 1\n7 8 9 0 -inf 0\n";
  ReadReport report;
  const PointCloud cloud = ParsePly(ply, "n.ply", &report).vertices;
  ASSERT_EQ(cloud.size(), 1u);
  EXPECT_EQ(cloud.positions[0], Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(report.dropped_non_finite, 2u);
  EXPECT_EQ(report.points_in_file, 3u);
}

TEST(PlyRead, NormalsAreMadeUnitAndZeroNormalsDropThePoint) {
  const std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nproperty float nx\nproperty float ny\nproperty float nz\nend_header\n"
      "1 2 3 0 0 2.7\n4 5 6 0 0 0\n7 8 9 0.6 0.8 0\n";
  ReadReport report;
  const PointCloud cloud = ParsePly(ply, "n.ply", &report).vertices;
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(cloud.normals[0], Eigen::Vector3d(0, 0, 1));
  EXPECT_NEAR(cloud.normals[1].norm(), 1.0, 1e-7);
  EXPECT_EQ(report.dropped_non_finite, 1u);
}

TEST(PlyReal, ParasaurolophusNormalsAreUnit) {
  LASERCELL_REAL_FILE(path, "uwa", "parasaurolophus_6700.ply");
  const PointCloud cloud = ReadPointCloud(path);
  for (const auto& n : cloud.normals) ASSERT_NEAR(n.norm(), 1.0, 1e-6);
}

TEST(PlyRead, BigEndianFileWithMixedTypes) {
  const std::string ply = Bytes()
                              .Text(
                                  "ply\nformat binary_big_endian 1.0\nelement vertex 2\n"
                                  "property double x\nproperty float32 y\nproperty short z\n"
                                  "property uchar intensity\nend_header\n")
                              .Be(1.25, -2.5f, std::int16_t{-300}, std::uint8_t{200})
                              .Be(1e6, 0.1f, std::int16_t{32767}, std::uint8_t{0})
                              .str();
  ReadReport report;
  const PointCloud cloud = ParsePly(ply, "be.ply", &report).vertices;
  EXPECT_EQ(report.format, "ply binary_big_endian");
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(cloud.positions[0], Eigen::Vector3d(1.25, -2.5, -300));
  EXPECT_EQ(cloud.positions[1], Eigen::Vector3d(1e6, static_cast<double>(0.1f), 32767));
  EXPECT_THAT(cloud.intensity, ElementsAre(200.f, 0.f));
}

TEST(PlyRead, EveryScalarTypeAsciiAndBinary) {
  const std::string header =
      "element vertex 1\nproperty char x\nproperty uint8 y\nproperty int16 z\n"
      "property ushort a\nproperty int b\nproperty uint32 c\nproperty float d\n"
      "property float64 e\nproperty int8 f\nproperty uchar g\nproperty short h\n"
      "property uint16 i\nproperty int32 j\nproperty uint k\nproperty float32 l\n"
      "property double m\nend_header\n";
  const std::string ascii = "ply\nformat ascii 1.0\n" + header +
                            "-128 255 -32768 65535 -2147483648 4294967295 1.5 2.5 1 2 3 4 5 6 "
                            "7 8\n";
  const std::string binary = Bytes()
                                 .Text("ply\nformat binary_little_endian 1.0\n" + header)
                                 .Le(std::int8_t{-128}, std::uint8_t{255}, std::int16_t{-32768})
                                 .Le(std::uint16_t{65535}, std::int32_t{-2147483647 - 1})
                                 .Le(std::uint32_t{4294967295u}, 1.5f, 2.5, std::int8_t{1})
                                 .Le(std::uint8_t{2}, std::int16_t{3}, std::uint16_t{4})
                                 .Le(std::int32_t{5}, std::uint32_t{6}, 7.f, 8.0)
                                 .str();
  for (const std::string& ply : {ascii, binary}) {
    ReadReport report;
    const PointCloud cloud = ParsePly(ply, "types.ply", &report).vertices;
    ASSERT_EQ(cloud.size(), 1u);
    EXPECT_EQ(cloud.positions[0], Eigen::Vector3d(-128, 255, -32768));
    EXPECT_EQ(report.ignored_fields.size(), 13u);
  }
}

TEST(PlyRead, PermutedPropertyOrderAndAliases) {
  const std::string ply =
      "ply\nformat ascii 1.0\ncomment made by hand\nobj_info scanner xyz\n"
      "element vertex 2\nproperty float nz\nproperty float z\nproperty uchar red\n"
      "property float normal_x\nproperty float y\nproperty float scalar_Intensity\n"
      "property float x\nproperty float ny\nend_header\n"
      "1 3 255 0 2 0.5 1 0\n0 6 0 1 5 0.25 4 0\n";
  ReadReport report;
  const PointCloud cloud = ParsePly(ply, "perm.ply", &report).vertices;
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(cloud.positions[0], Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(cloud.positions[1], Eigen::Vector3d(4, 5, 6));
  EXPECT_EQ(cloud.normals[0], Eigen::Vector3d(0, 0, 1));
  EXPECT_EQ(cloud.normals[1], Eigen::Vector3d(1, 0, 0));
  EXPECT_THAT(cloud.intensity, ElementsAre(0.5f, 0.25f));
  EXPECT_THAT(report.ignored_fields, ElementsAre("red"));
  EXPECT_EQ(report.lasercell_format_version, 0);
}

TEST(PlyRead, PartialNormalsAreIgnoredNotHalfRead) {
  const std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
      "property float z\nproperty float nx\nproperty float ny\nend_header\n1 2 3 0 1\n";
  ReadReport report;
  const PointCloud cloud = ParsePly(ply, "nxny.ply", &report).vertices;
  EXPECT_FALSE(cloud.HasNormals());
  EXPECT_THAT(report.ignored_fields, ElementsAre("nx", "ny"));
}

TEST(PlyRead, UnknownElementsAreSkippedAsciiAndBinary) {
  const std::string head =
      "element material 2\nproperty float shine\nproperty list uchar float rgb\n"
      "element vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
      "element edge 1\nproperty int a\nproperty int b\nelement face 1\n"
      "property list uchar int vertex_indices\nelement trailer 1\nproperty double t\n"
      "end_header\n";
  const std::string ascii =
      "ply\nformat ascii 1.0\n" + head + "0.5 3 1 2 3\n0.25 0\n1 2 3\n4 5 6\n0 1\n3 0 1 1\n9\n";
  const std::string binary =
      Bytes()
          .Text("ply\nformat binary_little_endian 1.0\n" + head)
          .Le(0.5f, std::uint8_t{3}, 1.f, 2.f, 3.f)  // material
          .Le(0.25f, std::uint8_t{0})
          .Le(1.f, 2.f, 3.f, 4.f, 5.f, 6.f)      // vertices
          .Le(std::int32_t{0}, std::int32_t{1})  // edge
          .Le(std::uint8_t{3}, std::int32_t{0}, std::int32_t{1}, std::int32_t{1})
          .Le(9.0)  // trailer
          .str();
  for (const std::string& ply : {ascii, binary}) {
    ReadReport report;
    const TriangleMesh mesh = ParsePly(ply, "extra.ply", &report);
    ASSERT_EQ(mesh.vertices.size(), 2u);
    EXPECT_EQ(mesh.vertices.positions[1], Eigen::Vector3d(4, 5, 6));
    EXPECT_THAT(mesh.faces, ElementsAre(Eigen::Vector3i(0, 1, 1)));
    EXPECT_THAT(report.notes, ElementsAre("skipped element 'material' (2 instances)",
                                          "skipped element 'edge' (1 instances)",
                                          "skipped element 'trailer' (1 instances)"));
  }
}

// An element without properties holds no data, so even the largest count is skipped at once (a
// fuzzer's finding: the reader looped over 14 billion empty instances).
TEST(PlyRead, AnElementWithoutPropertiesIsSkippedWhateverItsCount) {
  for (const char* format : {"ascii", "binary_little_endian"}) {
    std::string ply = std::string("ply\nformat ") + format +
                      " 1.0\nelement nothing 18446744073709551615\nelement vertex 1\n"
                      "property float x\nproperty float y\nproperty float z\nend_header\n";
    ply += std::string(format) == "ascii" ? "1 2 3\n" : Bytes().Le(1.f, 2.f, 3.f).str();
    ReadReport report;
    const TriangleMesh mesh = ParsePly(ply, "empty_element.ply", &report);
    ASSERT_EQ(mesh.vertices.size(), 1u) << format;
    EXPECT_EQ(mesh.vertices.positions[0], Eigen::Vector3d(1, 2, 3)) << format;
    EXPECT_THAT(report.notes, ElementsAre(HasSubstr("skipped element 'nothing'"))) << format;
  }
}

TEST(PlyRead, CrLfHeaderAndGridComment) {
  const std::string ply =
      "ply\r\nformat ascii 1.0\r\ncomment lasercell_format 1\r\ncomment lasercell_grid 2 3\r\n"
      "element vertex 2\r\nproperty float x\r\nproperty float y\r\nproperty float z\r\n"
      "property int profile\r\nproperty int column\r\nend_header\r\n1 2 3 0 2\r\n4 5 6 1 0\r\n";
  ReadReport report;
  const PointCloud cloud = ParsePly(ply, "crlf.ply", &report).vertices;
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(cloud.grid_rows, 2);
  EXPECT_EQ(cloud.grid_cols, 3);
  EXPECT_TRUE(cloud.IsOrganized());
  EXPECT_THAT(cloud.column, ElementsAre(2, 0));
  EXPECT_EQ(report.lasercell_format_version, 1);
}

TEST(PlyRead, UnitHintForMetresOnly) {
  const ::lasercell::test::TestDir dir("io");
  PointCloud metres;
  metres.positions = {{0, 0, 0}, {0.3, 0.1, 0.05}};
  WritePointCloud(dir.File("m.ply"), metres);
  ReadReport report;
  ReadPointCloud(dir.File("m.ply"), &report);
  EXPECT_THAT(report.unit_hint, HasSubstr("looks like metres"));
  EXPECT_THAT(report.unit_hint, HasSubstr("scale by 1000"));
  PointCloud mm;
  mm.positions = {{0, 0, 0}, {300, 100, 50}};
  WritePointCloud(dir.File("mm.ply"), mm);
  ReadPointCloud(dir.File("mm.ply"), &report);
  EXPECT_TRUE(report.unit_hint.empty()) << report.unit_hint;
}

TEST(PlyRead, CorruptedFilesFailCleanly) {
  TriangleMesh mesh{test::MakeFullCloud(20, 5), {{0, 1, 2}, {2, 3, 4}, {5, 6, 7}}};
  for (PlyEncoding encoding :
       {PlyEncoding::kAscii, PlyEncoding::kBinaryLittleEndian, PlyEncoding::kBinaryBigEndian}) {
    WriteOptions options;
    options.ply_encoding = encoding;
    test::ExpectCorruptionsRejectedCleanly(EncodePly(mesh, options), [](const std::string& bytes) {
      const TriangleMesh read = ParsePly(bytes, "corrupt.ply");
      read.vertices.Validate();  // whatever is accepted must be a valid cloud
    });
  }
}

// ---- rejected input: each message names the file and the problem ----

TEST(PlyReject, MissingFileAndUnknownExtension) {
  EXPECT_THAT(FileErrorMessage([] { ReadPointCloud("/nonexistent/scan.ply"); }),
              HasSubstr("/nonexistent/scan.ply"));
  const std::string message = FileErrorMessage([] { ReadPointCloud("scan.xyz"); });
  EXPECT_THAT(message, HasSubstr("scan.xyz"));
  EXPECT_THAT(message, HasSubstr("unsupported extension '.xyz'"));
}

TEST(PlyReject, WrongMagic) {
  const std::string message =
      FileErrorMessage([] { ParsePly("PLY\nformat ascii 1.0\n", "a.ply"); });
  EXPECT_THAT(message, HasSubstr("a.ply"));
  EXPECT_THAT(message, HasSubstr("not a PLY file: first line must be 'ply'"));
}

TEST(PlyReject, MissingEndHeader) {
  const std::string message = FileErrorMessage(
      [] { ParsePly("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n", "cut.ply"); });
  EXPECT_THAT(message, HasSubstr("cut.ply"));
  EXPECT_THAT(message, HasSubstr("missing 'end_header'"));
}

TEST(PlyReject, UnknownPropertyTypeNamesPropertyAndType) {
  const std::string message = FileErrorMessage([] {
    ParsePly("ply\nformat ascii 1.0\nelement vertex 1\nproperty half x\nend_header\n1\n", "t.ply");
  });
  EXPECT_THAT(message, HasSubstr("t.ply: header line 4"));
  EXPECT_THAT(message, HasSubstr("property 'x' has unknown type 'half'"));
}

TEST(PlyReject, UnknownFormatAndKeyword) {
  EXPECT_THAT(FileErrorMessage([] { ParsePly("ply\nformat binary 1.0\nend_header\n", "f.ply"); }),
              HasSubstr("f.ply: header line 2: unknown format 'binary'"));
  EXPECT_THAT(FileErrorMessage([] {
                ParsePly("ply\nformat ascii 1.0\nelemnt vertex 1\nend_header\n", "k.ply");
              }),
              HasSubstr("unknown keyword 'elemnt'"));
}

TEST(PlyReject, VertexWithoutZ) {
  const std::string message = FileErrorMessage([] {
    ParsePly(
        "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
        "end_header\n1 2\n",
        "xy.ply");
  });
  EXPECT_THAT(message, HasSubstr("xy.ply"));
  EXPECT_THAT(message, HasSubstr("no scalar property 'z'"));
}

TEST(PlyReject, FaceIndexOutOfRange) {
  const std::string message = FileErrorMessage([] {
    ParsePly(
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nelement face 2\nproperty list uchar int vertex_indices\n"
        "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 3\n",
        "idx.ply");
  });
  EXPECT_THAT(message, HasSubstr("idx.ply: element 'face' 1 (line 14)"));
  EXPECT_THAT(message, HasSubstr("vertex index 3 is out of range; the file has 3 vertices"));
}

TEST(PlyReject, FaceBeforeVerticesOutOfRange) {
  const std::string message = FileErrorMessage([] {
    ParsePly(
        "ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int vertex_indices\n"
        "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
        "end_header\n3 0 1 5\n0 0 0\n1 0 0\n0 1 0\n",
        "early.ply");
  });
  EXPECT_THAT(message, HasSubstr("early.ply: triangle 0 references vertex 5"));
}

TEST(PlyReject, MalformedAsciiNumberNamesLine) {
  const std::string message = FileErrorMessage([] {
    ParsePly(
        "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
        "property float z\nend_header\n1 2 3\n4 5.5.1 6\n",
        "num.ply");
  });
  EXPECT_THAT(message, HasSubstr("num.ply: element 'vertex' 1 (line 9)"));
  EXPECT_THAT(message, HasSubstr("malformed number '5.5.1' for property 'y'"));
}

TEST(PlyReject, IntegerOutOfTypeRange) {
  const std::string message = FileErrorMessage([] {
    ParsePly(
        "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
        "property uchar z\nend_header\n1 2 300\n",
        "uchar.ply");
  });
  EXPECT_THAT(message, HasSubstr("malformed number '300' for property 'z' of type uchar"));
}

TEST(PlyReject, TruncatedAscii) {
  const std::string message = FileErrorMessage([] {
    ParsePly(
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nend_header\n1.5 2.5 3.5\n4.5 5.5 6.5\n7.5 8.5\n",
        "short.ply");
  });
  EXPECT_THAT(message, HasSubstr("short.ply: element 'vertex' 2"));
  EXPECT_THAT(message, HasSubstr("data ends before property 'z'"));
}

TEST(PlyReject, TruncatedBinary) {
  const std::string full = EncodePly({test::MakeFullCloud(10), {}}, {});
  const std::string message =
      FileErrorMessage([&] { ParsePly(full.substr(0, full.size() - 5), "cut.ply"); });
  EXPECT_THAT(message, HasSubstr("cut.ply: element 'vertex' declares 10 instances of at least"));
  EXPECT_THAT(message, HasSubstr("the file is truncated or the count is wrong"));
}

TEST(PlyReject, TruncatedBinaryFaceList) {
  const std::string ply =
      Bytes()
          .Text(
              "ply\nformat binary_little_endian 1.0\nelement vertex 3\n"
              "property float x\nproperty float y\nproperty float z\n"
              "element face 1\nproperty list uint int vertex_indices\n"
              "end_header\n")
          .Le(0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f)
          .Le(std::uint32_t{1000000}, std::int32_t{0}, std::int32_t{1}, std::int32_t{2})
          .str();
  EXPECT_THAT(FileErrorMessage([&] { ParsePly(ply, "list.ply"); }),
              HasSubstr("list.ply: element 'face' 0: data ends inside property 'vertex_indices'"));
}

// A 4e9-vertex header in a tiny file must be rejected from the sizes alone: reserving
// 4e9 * 24 bytes first would throw std::bad_alloc (or abort under ASan), failing these tests.
TEST(PlyReject, HugeVertexCountRejectedBeforeAllocation) {
  const std::string tail =
      "element vertex 4000000000\nproperty double x\nproperty double y\nproperty double z\n"
      "property float nx\nproperty float ny\nproperty float nz\nend_header\n1 2 3 0 0 1\n";
  for (const char* format : {"ascii", "binary_little_endian", "binary_big_endian"}) {
    const std::string ply = std::string("ply\nformat ") + format + " 1.0\n" + tail;
    const std::string message = FileErrorMessage([&] { ParsePly(ply, "huge.ply"); });
    EXPECT_THAT(message, HasSubstr("huge.ply: element 'vertex' declares 4000000000 instances"));
    EXPECT_THAT(message, HasSubstr("the file is truncated or the count is wrong"));
  }
}

TEST(PlyReject, CountThatOverflowsTimesStride) {
  const std::string ply =
      "ply\nformat binary_little_endian 1.0\nelement vertex 1537228672809129302\n"
      "property float x\nproperty float y\nproperty float z\nend_header\n0123456789ab";
  // 1537228672809129302 * 12 wraps around to 8 bytes in 64-bit arithmetic.
  EXPECT_THAT(FileErrorMessage([&] { ParsePly(ply, "wrap.ply"); }),
              HasSubstr("declares 1537228672809129302 instances"));
  EXPECT_THAT(FileErrorMessage([&] {
                ParsePly(
                    "ply\nformat ascii 1.0\nelement vertex 99999999999999999999\n"
                    "end_header\n",
                    "big.ply");
              }),
              HasSubstr("count '99999999999999999999'; expected a non-negative integer"));
}

TEST(PlyReject, FaceWithTwoIndices) {
  const std::string message = FileErrorMessage([] {
    ParsePly(
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
        "end_header\n0 0 0\n1 0 0\n0 1 0\n2 0 1 \n",
        "edge.ply");
  });
  EXPECT_THAT(message, HasSubstr("face has 2 vertex indices; a face needs at least 3"));
}

TEST(PlyReject, NoVertexElement) {
  EXPECT_THAT(FileErrorMessage([] {
                ParsePly("ply\nformat ascii 1.0\nelement face 0\nend_header\n", "nov.ply");
              }),
              HasSubstr("nov.ply: the header declares no 'element vertex'"));
}

}  // namespace
}  // namespace lasercell::io
