#include "core/io/mesh_io.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <string>

#include "core/error.hpp"
#include "core/io/file_util.hpp"
#include "tests/cli_util.hpp"

namespace lasercell::io {
namespace {

// A closed box [0,a] x [0,b] x [0,c] with outward counter-clockwise faces; coordinates that are
// not float-representable so float32 storage is visible.
TriangleMesh Box(double a = 10.1, double b = 20.3, double c = 5.7) {
  TriangleMesh m;
  for (int i = 0; i < 8; ++i) {
    m.vertices.positions.emplace_back(i & 1 ? a : 0.0, i & 2 ? b : 0.0, i & 4 ? c : 0.0);
  }
  m.faces = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
             {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

double WorstVertexError(const TriangleMesh& a, const TriangleMesh& b) {
  double worst = 0;
  for (std::size_t f = 0; f < a.faces.size(); ++f) {
    for (int c = 0; c < 3; ++c) {
      worst = std::max(
          worst,
          (a.vertices.positions[a.faces[f][c]] - b.vertices.positions[b.faces[f][c]]).norm());
    }
  }
  return worst;
}

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const FileError& e) {
    return e.what();
  }
  return "no FileError";
}

TEST(MeshIo, BinaryStlRoundTripsWithSharedVerticesAndOutwardNormals) {
  const TriangleMesh mesh = Box();
  const test::TestDir dir("stl");
  const std::string path = dir.File("box.stl");
  WriteStlMesh(path, mesh);
  const std::string bytes = ReadFileBytes(path);
  EXPECT_EQ(bytes.size(), 84 + 50 * mesh.faces.size());
  EXPECT_NE(bytes.rfind("solid", 0), 0u);  // not mistaken for ASCII STL
  const TriangleMesh back = ReadStlMesh(path);
  ASSERT_EQ(back.faces.size(), mesh.faces.size());
  EXPECT_EQ(back.vertices.size(), mesh.vertices.size());  // merged again
  EXPECT_LT(WorstVertexError(back, mesh), 1e-5);          // float32 at ~20 mm
  EXPECT_GT(WorstVertexError(back, mesh), 0.0);           // ... and it was float32
  const auto& v = mesh.vertices.positions;
  const Eigen::Vector3i& f0 = mesh.faces[0];
  const Eigen::Vector3d n = (v[f0[1]] - v[f0[0]]).cross(v[f0[2]] - v[f0[0]]).normalized();
  float stored[3];
  std::memcpy(stored, bytes.data() + 84, sizeof(stored));
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(stored[k], n[k], 1e-6);
  EXPECT_EQ(n, Eigen::Vector3d(0, 0, -1));  // the bottom face points down: outward
}

TEST(MeshIo, AsciiStlRoundTripsExactly) {
  const TriangleMesh mesh = Box();
  const std::string text = EncodeAsciiStl(mesh, "box");
  EXPECT_EQ(text.rfind("solid box\n", 0), 0u);
  const TriangleMesh back = DecodeStl(text, "box.stl");
  ASSERT_EQ(back.faces.size(), mesh.faces.size());
  EXPECT_EQ(back.vertices.size(), 8u);
  EXPECT_EQ(WorstVertexError(back, mesh), 0.0);
}

TEST(MeshIo, BinaryStlWhoseHeaderStartsWithSolidIsReadAsBinary) {
  std::string bytes = EncodeBinaryStl(Box());
  std::memcpy(bytes.data(), "solid exported", 14);  // as some CAD exporters write it
  EXPECT_EQ(DecodeStl(bytes, "x.stl").faces.size(), 12u);
}

TEST(MeshIo, TruncatedOrMalformedStlNamesTheFileAndTheLine) {
  const std::string bytes = EncodeBinaryStl(Box());
  EXPECT_NE(ErrorOf([&] {
              DecodeStl(bytes.substr(0, bytes.size() - 1), "cut.stl");
            }).find("cut.stl: binary STL declares 12 triangles"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { DecodeStl("short", "short.stl"); }).find("short.stl: not an STL"),
            std::string::npos);
  const std::string text = EncodeAsciiStl(Box());
  EXPECT_NE(ErrorOf([&] {
              DecodeStl(text.substr(0, text.find("endloop")), "half.stl");
            }).find("unexpected end of file"),
            std::string::npos);
  const std::string bad = "solid x\n facet normal 0 0 1\n outer loop\n vertex 0 0 nan\n";
  EXPECT_NE(ErrorOf([&] { DecodeStl(bad, "nan.stl"); }).find("nan.stl: ASCII STL line 4"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] {
              DecodeStl("solid x\n facet normal 0 0 1\n inner loop\n", "w.stl");
            }).find("line 3: expected 'outer', found 'inner'"),
            std::string::npos);
  TriangleMesh tri = Box();
  tri.faces = {{0, 1, 9}};
  EXPECT_THROW(EncodeBinaryStl(tri), InputError);
  EXPECT_THROW(EncodeBinaryStl(Box(), "solid name"), InputError);
}

TEST(MeshIo, ObjPolygonsAreFannedAndEveryIndexFormIsRead) {
  const std::string text =
      "# a unit square and a triangle\n"
      "mtllib x.mtl\no square\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n"
      "usemtl m\ns off\nf 1/1/1 2/1/1 3//1 4\n"
      "v 0 0 2 2\nf -1 1 2\n";
  const TriangleMesh mesh = DecodeObj(text, "sq.obj");
  ASSERT_EQ(mesh.vertices.size(), 5u);
  EXPECT_EQ(mesh.vertices.positions[4], Eigen::Vector3d(0, 0, 1));  // w = 2 divides
  ASSERT_EQ(mesh.faces.size(), 3u);
  EXPECT_EQ(mesh.faces[0], Eigen::Vector3i(0, 1, 2));
  EXPECT_EQ(mesh.faces[1], Eigen::Vector3i(0, 2, 3));
  EXPECT_EQ(mesh.faces[2], Eigen::Vector3i(4, 0, 1));
}

TEST(MeshIo, MalformedObjNamesTheFileAndTheLine) {
  EXPECT_NE(ErrorOf([] {
              DecodeObj("v 0 0 0\nv 1 0 0\nf 1 2 3\n", "a.obj");
            }).find("a.obj: OBJ line 3: face vertex index 3 is out of range"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { DecodeObj("v 0 0\n", "b.obj"); }).find("line 1: 'v' needs x y z"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { DecodeObj("v 0 0 inf\n", "c.obj"); }).find("not a finite number"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { DecodeObj("hello world\n", "d.obj"); }).find("unknown statement"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { DecodeObj("# nothing\n", "e.obj"); }).find("no vertices"),
            std::string::npos);
}

TEST(MeshIo, ReadMeshDispatchesOnTheExtension) {
  const test::TestDir dir("mesh");
  const TriangleMesh mesh = Box();
  WriteStlMesh(dir.File("a.STL"), mesh);
  WritePlyMesh(dir.File("a.ply"), mesh);
  WriteFileAtomically(dir.File("a.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  ReadReport report;
  EXPECT_EQ(ReadMesh(dir.File("a.STL"), &report).faces.size(), 12u);
  EXPECT_EQ(report.format, "stl");
  EXPECT_EQ(report.faces, 12u);
  EXPECT_EQ(ReadMesh(dir.File("a.ply")).faces.size(), 12u);
  EXPECT_EQ(ReadMesh(dir.File("a.obj")).faces.size(), 1u);
  EXPECT_NE(ErrorOf([&] { ReadMesh(dir.File("a.off")); }).find("unknown mesh extension '.off'"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { ReadMesh(dir.File("missing.stl")); }).find("missing.stl"),
            std::string::npos);
}

// WriteMesh picks the format by extension as ReadMesh reads it: STL stores float32 corners,
// PLY the vertices as written; other extensions are refused, naming the file, and not written.
TEST(MeshIo, WriteMeshDispatchesOnTheExtension) {
  const test::TestDir dir("mesh_write");
  const TriangleMesh mesh = Box();
  WriteMesh(dir.File("b.Stl"), mesh);
  WriteMesh(dir.File("b.ply"), mesh);
  const TriangleMesh stl = ReadMesh(dir.File("b.Stl"));
  const TriangleMesh ply = ReadMesh(dir.File("b.ply"));
  ASSERT_EQ(stl.faces.size(), 12u);
  ASSERT_EQ(ply.faces.size(), 12u);
  EXPECT_LT(WorstVertexError(mesh, stl), 1e-5);
  EXPECT_GT(WorstVertexError(mesh, stl), 0.0);  // float32: 10.1 is not representable
  EXPECT_LT(WorstVertexError(mesh, ply), 1e-5);
  const std::string error = ErrorOf([&] { WriteMesh(dir.File("b.obj"), mesh); });
  EXPECT_NE(error.find("b.obj"), std::string::npos) << error;
  EXPECT_NE(error.find(".stl or .ply"), std::string::npos) << error;
  EXPECT_FALSE(std::filesystem::exists(dir.File("b.obj")));
}

}  // namespace
}  // namespace lasercell::io
