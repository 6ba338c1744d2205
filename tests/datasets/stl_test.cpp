#include "datasets/stl.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <string>

#include "core/error.hpp"
#include "core/io/file_util.hpp"
#include "datasets/chair_seat.hpp"
#include "tests/cli_util.hpp"

namespace lasercell::datasets {
namespace {

TEST(Stl, SeatMeshRoundTripsThroughABinaryStlFile) {
  const ChairSeat seat = MakeChairSeat({});
  const TriangleMesh& mesh = seat.part.mesh;
  const test::TestDir dir("stl");
  const std::string path = dir.File("seat.stl");
  WriteStlMesh(path, mesh);
  const std::string bytes = io::ReadFileBytes(path);
  EXPECT_EQ(bytes.size(), 84 + 50 * mesh.faces.size());
  EXPECT_NE(bytes.rfind("solid", 0), 0u);  // not mistaken for ASCII STL
  const TriangleMesh back = ReadStlMesh(path);
  ASSERT_EQ(back.faces.size(), mesh.faces.size());
  // Same triangles, same winding, to float32 precision; shared vertices are merged again.
  double worst = 0;
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    for (int c = 0; c < 3; ++c) {
      worst = std::max(worst, (back.vertices.positions[back.faces[f][c]] -
                               mesh.vertices.positions[mesh.faces[f][c]])
                                  .norm());
    }
  }
  EXPECT_LT(worst, 1e-4);  // float32 at <= 300 mm: ~2e-5 mm
  EXPECT_EQ(back.vertices.size(), mesh.vertices.size());
  // The stored normal is the face's outward unit normal.
  const Eigen::Vector3i& f0 = mesh.faces[0];
  const auto& v = mesh.vertices.positions;
  const Eigen::Vector3d n = (v[f0[1]] - v[f0[0]]).cross(v[f0[2]] - v[f0[0]]).normalized();
  float stored[3];
  std::memcpy(stored, bytes.data() + 84, sizeof(stored));
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(stored[k], n[k], 1e-6);
}

TEST(Stl, TruncatedOrMalformedInputIsAnError) {
  TriangleMesh tri;
  tri.vertices.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  tri.faces = {{0, 1, 2}};
  const std::string bytes = EncodeBinaryStl(tri);
  EXPECT_NO_THROW(DecodeBinaryStl(bytes, "ok.stl"));
  try {
    DecodeBinaryStl(bytes.substr(0, bytes.size() - 1), "cut.stl");
    ADD_FAILURE() << "no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cut.stl"), std::string::npos) << e.what();
  }
  EXPECT_THROW(DecodeBinaryStl("short", "short.stl"), InputError);
  tri.faces = {{0, 1, 7}};
  EXPECT_THROW(EncodeBinaryStl(tri), InputError);
  tri.faces = {{0, 1, 2}};
  EXPECT_THROW(EncodeBinaryStl(tri, "solid name"), InputError);
}

}  // namespace
}  // namespace lasercell::datasets
