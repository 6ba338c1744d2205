// Fuzz targets for core's file formats: PLY, PCD, STL, OBJ and the cell file (cell.yaml).
// Each reader's result is written by lasercell's writer and read again: what lasercell wrote
// must read back, and writing that again must give the same bytes (parse -> write -> parse is
// the identity on lasercell's own files).

#include <cmath>
#include <string>
#include <vector>

#include "core/frame_graph.hpp"
#include "core/io/mesh_io.hpp"
#include "core/io/point_cloud_io.hpp"
#include "tests/fuzz/harness/fuzz_target.hpp"

namespace lasercell::fuzz {
namespace {

// A small mesh with every attribute the formats carry, on a 3 x 4 grid (organized).
TriangleMesh SeedMesh(bool with_faces) {
  TriangleMesh mesh;
  PointCloud& c = mesh.vertices;
  c.grid_rows = 3;
  c.grid_cols = 4;
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 4; ++k) {
      c.positions.emplace_back(10.0 * k + 0.125, -5.0 * r, 100.0 + 0.5 * r * k);
      c.normals.push_back(Eigen::Vector3d(0.1 * k, 0.2, 1.0).normalized());
      c.intensity.push_back(0.25f * static_cast<float>(k));
      c.profile.push_back(r);
      c.column.push_back(k);
    }
  }
  if (with_faces) {
    mesh.faces = {{0, 1, 5}, {0, 5, 4}, {5, 6, 10}, {6, 11, 10}};
  }
  return mesh;
}

std::vector<std::string> PlySeeds() {
  std::vector<std::string> seeds;
  for (const bool faces : {false, true}) {
    for (const io::PlyEncoding e : {io::PlyEncoding::kBinaryLittleEndian,
                                    io::PlyEncoding::kBinaryBigEndian, io::PlyEncoding::kAscii}) {
      io::WriteOptions options;
      options.ply_encoding = e;
      options.positions_as_double = faces;
      seeds.push_back(io::EncodePly(SeedMesh(faces), options));
    }
  }
  // A foreign header: other property types, an extra element, a comment and a colour.
  seeds.push_back(
      "ply\nformat ascii 1.0\ncomment made by hand\nelement vertex 3\nproperty double x\n"
      "property double y\nproperty double z\nproperty uchar red\nproperty uchar green\n"
      "property uchar blue\nelement face 1\nproperty list uchar int vertex_indices\n"
      "element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n"
      "0 0 0 255 0 0\n1 0 0 0 255 0\n0 1 0 0 0 255\n3 0 1 2\n0 1\n");
  return seeds;
}

}  // namespace

LASERCELL_FUZZ_TARGET(ply, PlySeeds) {
  const TriangleMesh mesh = io::ParsePly(bytes, "fuzz.ply");
  io::WriteOptions options;
  options.positions_as_double = true;  // lossless for whatever precision the file had
  const std::string written = io::EncodePly(mesh, options);
  TriangleMesh again;
  LASERCELL_FUZZ_MUST_ACCEPT(again = io::ParsePly(written, "written.ply"));
  LASERCELL_FUZZ_ASSERT(io::EncodePly(again, options) == written,
                        "PLY: write(read(write(read(x)))) differs from write(read(x))");
}

static std::vector<std::string> PcdSeeds() {
  std::vector<std::string> seeds;
  for (const bool binary : {true, false}) {
    io::WriteOptions options;
    options.pcd_binary = binary;
    seeds.push_back(io::EncodePcd(SeedMesh(false).vertices, options));
  }
  // Real scans (binary and binary_compressed PCL files, bundled with provenance).
  seeds.push_back(RepositoryFile("datasets/real/pcl/bun4.pcd"));
  seeds.push_back(RepositoryFile("datasets/real/pcl/bun0.pcd"));
  seeds.push_back(
      "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z rgb\n"
      "SIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\nWIDTH 2\nHEIGHT 2\n"
      "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 4\nDATA ascii\n1 2 3 0\nnan nan nan 0\n4 5 6 7\n"
      "7 8 9 1\n");
  return seeds;
}

LASERCELL_FUZZ_TARGET(pcd, PcdSeeds) {
  const PointCloud cloud = io::ParsePcd(bytes, "fuzz.pcd");
  io::WriteOptions options;
  options.positions_as_double = true;
  const std::string written = io::EncodePcd(cloud, options);
  PointCloud again;
  LASERCELL_FUZZ_MUST_ACCEPT(again = io::ParsePcd(written, "written.pcd"));
  LASERCELL_FUZZ_ASSERT(io::EncodePcd(again, options) == written,
                        "PCD: write(read(write(read(x)))) differs from write(read(x))");
}

// Every face of a mesh a reader returns indexes its vertices.
static void CheckFaces(const TriangleMesh& mesh, const char* format) {
  const auto n = static_cast<int>(mesh.vertices.size());
  for (const Eigen::Vector3i& f : mesh.faces) {
    LASERCELL_FUZZ_ASSERT((f.array() >= 0).all() && (f.array() < n).all(),
                          std::string(format) + ": a face indexes a vertex that does not exist");
  }
  for (const Eigen::Vector3d& p : mesh.vertices.positions) {
    LASERCELL_FUZZ_ASSERT(p.allFinite(), std::string(format) + ": a non-finite vertex");
  }
}

static std::vector<std::string> StlSeeds() {
  const TriangleMesh mesh = SeedMesh(true);
  return {io::EncodeBinaryStl(mesh), io::EncodeAsciiStl(mesh, "seed")};
}

LASERCELL_FUZZ_TARGET(stl, StlSeeds) {
  const TriangleMesh mesh = io::DecodeStl(bytes, "fuzz.stl");
  CheckFaces(mesh, "STL");
  const std::string written = io::EncodeAsciiStl(mesh, "again");  // prints doubles exactly
  TriangleMesh again;
  LASERCELL_FUZZ_MUST_ACCEPT(again = io::DecodeStl(written, "written.stl"));
  LASERCELL_FUZZ_ASSERT(io::EncodeAsciiStl(again, "again") == written,
                        "STL: write(read(write(read(x)))) differs from write(read(x))");
}

static std::vector<std::string> ObjSeeds() {
  return {
      "# seed\no part\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nvt 0 0\n"
      "f 1/1/1 2/1/1 3/1/1\nf 1//1 3//1 4//1\n",
      "v 0 0 0 1\nv 10 0 0\nv 0 10 0\nv 0 0 10\nf -4 -3 -2\nf 1 2 3 4\ng side\nusemtl x\n"
      "s off\nf 2 3 4\n",
  };
}

LASERCELL_FUZZ_TARGET(obj, ObjSeeds) {
  const TriangleMesh mesh = io::DecodeObj(bytes, "fuzz.obj");
  CheckFaces(mesh, "OBJ");
}

static std::vector<std::string> CellSeeds() { return {RepositoryFile("datasets/demo/cell.yaml")}; }

LASERCELL_FUZZ_TARGET(cell_yaml, CellSeeds) {
  const FrameGraph graph = FrameGraphFromYaml(std::string(bytes), "fuzz_cell.yaml");
  const std::string written = FrameGraphToYaml(graph);
  FrameGraph again;
  LASERCELL_FUZZ_MUST_ACCEPT(again = FrameGraphFromYaml(written, "written_cell.yaml"));
  LASERCELL_FUZZ_ASSERT(FrameGraphToYaml(again) == written,
                        "cell.yaml: write(read(write(read(x)))) differs from write(read(x))");
}

}  // namespace lasercell::fuzz
