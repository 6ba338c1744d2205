#include "registration/normals.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <numbers>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/io/point_cloud_io.hpp"
#include "registration/filters.hpp"
#include "registration_test_util.hpp"

namespace lasercell::registration {
namespace {

using ::testing::HasSubstr;

double AngleTo(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::clamp(std::abs(a.normalized().dot(b.normalized())), 0.0, 1.0));
}

// z = 0.3 x + 0.2 y on a 1 mm grid with Gaussian noise along z, as an organized cloud.
PointCloud NoisyPlaneGrid(int rows, int cols, double noise_mm, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, noise_mm);
  PointCloud cloud;
  cloud.grid_rows = rows;
  cloud.grid_cols = cols;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const double x = c, y = r;
      cloud.positions.push_back({x, y, -200.0 + 0.3 * x + 0.2 * y + g(rng)});
      cloud.profile.push_back(r);
      cloud.column.push_back(c);
    }
  }
  return cloud;
}

const Eigen::Vector3d kPlaneNormal = Eigen::Vector3d(-0.3, -0.2, 1.0).normalized();

TEST(NormalsTest, SphereNormalsAreRadialAndFaceTheViewpoint) {
  std::mt19937_64 rng(21);
  const Eigen::Vector3d centre(0, 0, -300);
  const PointCloud sphere = test::SpherePoints(6000, 50.0, centre, rng);
  PointCloud cloud;
  cloud.positions = sphere.positions;
  NormalOptions options;
  options.viewpoint = Viewpoint::AtPoint(Eigen::Vector3d::Zero());
  const NormalEstimationResult result = EstimateNormals(cloud, options);
  EXPECT_EQ(result.invalid_count, 0U);
  double sum = 0.0, worst = 0.0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const double error = AngleTo(result.normals[i], cloud.positions[i] - centre);
    sum += error;
    worst = std::max(worst, error);
    EXPECT_GE(result.normals[i].dot(-cloud.positions[i]), 0.0)
        << "point " << i << " faces away from the sensor";
    EXPECT_NEAR(result.normals[i].norm(), 1.0, 1e-12);
  }
  // 12 neighbours span ~5 mm on a 50 mm sphere: the fit is nearly unbiased; sampling
  // asymmetry bounds the worst case at a few degrees.
  EXPECT_LT(sum / cloud.size(), 0.02);
  EXPECT_LT(worst, 0.12);
}

TEST(NormalsTest, NoisyPlaneByKdTreeRadiusAndGrid) {
  const PointCloud plane = NoisyPlaneGrid(60, 60, 0.05, 22);
  NormalOptions options;
  options.viewpoint = Viewpoint::AlongDirection(-Eigen::Vector3d::UnitZ());
  options.k = 20;
  for (int mode = 0; mode < 3; ++mode) {
    NormalOptions o = options;
    PointCloud cloud = plane;
    if (mode == 0) cloud.grid_rows = cloud.grid_cols = 0;  // unorganized: k nearest
    if (mode == 1) {
      cloud.grid_rows = cloud.grid_cols = 0;
      o.radius_mm = 2.6;
    }
    const NormalEstimationResult result = EstimateNormals(cloud, o);
    EXPECT_EQ(result.used_grid, mode == 2);
    double sum = 0.0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      sum += AngleTo(result.normals[i], kPlaneNormal);
      ASSERT_GT(result.normals[i].z(), 0.0);  // toward the sensor above
    }
    // sigma / (extent * sqrt(k)) ~ 0.05 / (2 * 4.5) ~ 0.006 rad; allow 3x.
    EXPECT_LT(sum / cloud.size(), 0.02) << "mode " << mode;
  }
}

TEST(NormalsTest, GridDistanceLimitSeparatesDepthJumps) {
  // Two parallel planes 30 mm apart interleaved by column halves: with the limit the normals at
  // the seam stay exact; without it the fit mixes both planes.
  PointCloud cloud = NoisyPlaneGrid(20, 20, 0.0, 23);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (cloud.column[i] >= 10) cloud.positions[i].z() += 30.0;
  }
  NormalOptions options;
  options.viewpoint = Viewpoint::AlongDirection(-Eigen::Vector3d::UnitZ());
  options.grid_max_distance_mm = 5.0;
  const auto limited = EstimateNormals(cloud, options);
  options.grid_max_distance_mm = 0.0;
  const auto mixed = EstimateNormals(cloud, options);
  const std::size_t seam = 5 * 20 + 9;  // row 5, column 9
  EXPECT_LT(AngleTo(limited.normals[seam], kPlaneNormal), 1e-6);
  EXPECT_GT(AngleTo(mixed.normals[seam], kPlaneNormal), 0.1);
}

TEST(NormalsTest, PerPointLineOfSightOrientsEachNormal) {
  PointCloud cloud = NoisyPlaneGrid(10, 10, 0.0, 24);
  std::vector<Eigen::Vector3d> line_of_sight(cloud.size(), Eigen::Vector3d::UnitZ());
  for (std::size_t i = 0; i < cloud.size(); i += 2) line_of_sight[i] = -Eigen::Vector3d::UnitZ();
  const auto result = EstimateNormals(cloud, NormalOptions{}, line_of_sight);
  for (std::size_t i = 0; i < cloud.size(); ++i)
    EXPECT_GT(result.normals[i].dot(line_of_sight[i]), 0.9);
  const std::vector<Eigen::Vector3d> wrong(3, Eigen::Vector3d::UnitZ());
  EXPECT_THAT([&] { EstimateNormals(cloud, NormalOptions{}, wrong); },
              ::testing::ThrowsMessage<InputError>(
                  HasSubstr("line_of_sight has 3 vectors for 100 points")));
}

// Normals at a subset are the full estimate's at those points, from the same neighbourhoods in
// the whole cloud: on the grid of an organized sweep and by kd-tree on a plain cloud, with
// per-point lines of sight; an index out of range is refused.
TEST(NormalsTest, NormalsAtASubsetEqualTheFullEstimateThere) {
  PointCloud grid = NoisyPlaneGrid(40, 50, 0.05, 26);
  std::vector<Eigen::Vector3d> sight(grid.size(), Eigen::Vector3d::UnitZ());
  for (std::size_t i = 0; i < grid.size(); i += 3) sight[i] = -Eigen::Vector3d::UnitZ();
  std::mt19937_64 rng(27);
  PointCloud plain;
  plain.positions = test::SpherePoints(5000, 40.0, {0, 0, -250}, rng).positions;
  for (const PointCloud* cloud : {&grid, &plain}) {
    const bool organized = cloud == &grid;
    SCOPED_TRACE(organized ? "grid" : "kd-tree");
    const std::span<const Eigen::Vector3d> los =
        organized ? std::span<const Eigen::Vector3d>(sight) : std::span<const Eigen::Vector3d>();
    const NormalEstimationResult full = EstimateNormals(*cloud, NormalOptions{}, los);
    std::vector<std::size_t> at;
    for (std::size_t i = 7; i < cloud->size(); i += 11) at.push_back(i);
    const NormalEstimationResult some = EstimateNormalsAt(*cloud, at, NormalOptions{}, los);
    ASSERT_EQ(some.normals.size(), at.size());
    EXPECT_EQ(some.used_grid, organized);
    for (std::size_t k = 0; k < at.size(); ++k) {
      ASSERT_EQ(some.valid[k], full.valid[at[k]]) << k;
      ASSERT_EQ(some.normals[k], full.normals[at[k]]) << k;
      ASSERT_EQ(some.curvature[k], full.curvature[at[k]]) << k;
    }
  }
  const std::vector<std::size_t> bad = {0, grid.size()};
  EXPECT_THAT([&] { EstimateNormalsAt(grid, bad, NormalOptions{}); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("index 2000 for a cloud of 2000")));
}

// WithNormalsAtCells keeps one point per cell, the one nearest its centre, with the normal
// EstimateNormalsAt fits there (points without a valid fit are skipped and counted); cell 0
// fits every point, as WithEstimatedNormals does.
TEST(NormalsTest, NormalsAtCellsAreTheFitsAtTheCellPoints) {
  PointCloud grid = NoisyPlaneGrid(40, 50, 0.05, 28);
  std::vector<Eigen::Vector3d> sight(grid.size(), Eigen::Vector3d::UnitZ());
  const double cell = 3.0;
  const CloudWithNormals thinned = WithNormalsAtCells(grid, cell, NormalOptions{}, sight);
  const std::vector<std::size_t> at =
      OnePerCellIndices(grid.positions, cell, CellPoint::kNearestCentre);
  const NormalEstimationResult fit = EstimateNormalsAt(grid, at, NormalOptions{}, sight);
  ASSERT_LT(at.size(), grid.size() / 2);
  ASSERT_EQ(thinned.kept.size() + thinned.dropped, at.size());
  ASSERT_EQ(thinned.cloud.size(), thinned.kept.size());
  std::size_t k = 0;
  for (std::size_t j = 0; j < at.size(); ++j) {
    if (!fit.valid[j]) continue;
    ASSERT_EQ(thinned.kept[k], at[j]);
    EXPECT_EQ(thinned.cloud.positions[k], grid.positions[at[j]]);
    EXPECT_EQ(thinned.cloud.normals[k], fit.normals[j]);
    ++k;
  }
  const CloudWithNormals every = WithNormalsAtCells(grid, 0.0, NormalOptions{});
  std::size_t dropped = 0;
  const PointCloud same = WithEstimatedNormals(grid, NormalOptions{}, &dropped);
  EXPECT_EQ(every.cloud.positions, same.positions);
  EXPECT_EQ(every.cloud.normals, same.normals);
  EXPECT_EQ(every.dropped, dropped);
  EXPECT_EQ(every.kept.size() + every.dropped, grid.size());
}

TEST(NormalsTest, IdenticalForAnyThreadCount) {
  std::mt19937_64 rng(25);
  PointCloud cloud;
  cloud.positions = test::SpherePoints(20000, 40.0, {0, 0, -250}, rng).positions;
  NormalOptions options;
  options.threads = 1;
  const auto one = EstimateNormals(cloud, options);
  options.threads = 2;
  const auto two = EstimateNormals(cloud, options);
  options.threads = 0;
  const auto all = EstimateNormals(cloud, options);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    ASSERT_EQ(one.normals[i], two.normals[i]);
    ASSERT_EQ(one.normals[i], all.normals[i]);
  }
}

TEST(NormalsTest, DegenerateNeighbourhoodsAreReportedAndDropped) {
  PointCloud cloud;
  for (int i = 0; i < 20; ++i) cloud.positions.push_back({i * 1.0, 0, 0});  // a line: no plane
  cloud.positions.push_back({100, 100, 100});  // its neighbourhood (itself + the line) is a plane
  const auto result = EstimateNormals(cloud, NormalOptions{});
  EXPECT_EQ(result.invalid_count, 20U);
  EXPECT_EQ(result.valid[20], 1);
  std::size_t dropped = 0;
  const PointCloud kept = WithEstimatedNormals(cloud, NormalOptions{}, &dropped);
  EXPECT_EQ(dropped, 20U);
  ASSERT_EQ(kept.size(), 1U);
  EXPECT_EQ(kept.positions[0], Eigen::Vector3d(100, 100, 100));
}

TEST(NormalsTest, RejectsBadOptionsAndInput) {
  NormalOptions options;
  options.k = 2;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("NormalOptions.k")));
  options = {};
  options.radius_mm = -1.0;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("radius_mm")));
  options = {};
  options.viewpoint = Viewpoint::AlongDirection(Eigen::Vector3d::Zero());
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("direction")));
  PointCloud nan_cloud;
  nan_cloud.positions = {{0, 0, 0}, {std::nan(""), 0, 0}, {1, 1, 0}};
  EXPECT_THROW(EstimateNormals(nan_cloud, NormalOptions{}), InputError);
}

// Two 100 x 100 mm sheets 4 mm apart on a 2 mm grid, the top wound counter-clockwise seen from
// +z, the bottom seen from -z: the two sides of a thin shell, as in a CAD part (the simulated
// chair seat is 8 mm thick).
TriangleMesh ThinSlab(int cells, double step_mm, double thickness_mm) {
  TriangleMesh mesh;
  const int n = cells + 1;
  for (int side = 0; side < 2; ++side) {
    const double z = side == 0 ? thickness_mm / 2 : -thickness_mm / 2;
    const int base = side * n * n;
    for (int r = 0; r < n; ++r) {
      for (int c = 0; c < n; ++c) mesh.vertices.positions.push_back({c * step_mm, r * step_mm, z});
    }
    for (int r = 0; r < cells; ++r) {
      for (int c = 0; c < cells; ++c) {
        const int a = base + r * n + c, b = a + 1, d = a + n, e = d + 1;
        if (side == 0) {
          mesh.faces.push_back({a, b, e});
          mesh.faces.push_back({a, e, d});
        } else {
          mesh.faces.push_back({a, e, b});
          mesh.faces.push_back({a, d, e});
        }
      }
    }
  }
  return mesh;
}

TEST(MeshNormalsTest, TheTwoSidesOfAThinShellPointAwayFromEachOther) {
  const TriangleMesh slab = ThinSlab(50, 2.0, 4.0);
  const std::vector<Eigen::Vector3d> normals = MeshVertexNormals(slab);
  ASSERT_EQ(normals.size(), slab.vertices.size());
  for (std::size_t i = 0; i < normals.size(); ++i) {
    const double side = slab.vertices.positions[i].z() > 0 ? 1.0 : -1.0;
    EXPECT_NEAR(normals[i].z(), side, 1e-12) << "vertex " << i;
  }
  // A PCA fit over 12 neighbours of this 2 mm grid reaches across the 4 mm gap and loses the
  // side: with the normal flipped toward a viewpoint above, half the vertices face the wrong way.
  NormalOptions pca;
  pca.viewpoint = Viewpoint::AtPoint({50, 50, 1000});
  const NormalEstimationResult estimated = EstimateNormals(slab.vertices, pca);
  int wrong_side = 0;
  for (std::size_t i = 0; i < estimated.normals.size(); ++i) {
    const double side = slab.vertices.positions[i].z() > 0 ? 1.0 : -1.0;
    if (estimated.valid[i] && estimated.normals[i].z() * side < 0) ++wrong_side;
  }
  EXPECT_GT(wrong_side, static_cast<int>(slab.vertices.size()) / 3);
}

TEST(MeshNormalsTest, UnusedVerticesAreDroppedAndCounted) {
  TriangleMesh mesh = ThinSlab(4, 1.0, 1.0);
  mesh.vertices.positions.push_back({100, 100, 100});  // no face uses it
  std::size_t dropped = 0;
  const PointCloud cloud = WithMeshNormals(mesh, &dropped);
  EXPECT_EQ(dropped, 1u);
  EXPECT_EQ(cloud.size(), mesh.vertices.size() - 1);
  ASSERT_TRUE(cloud.HasNormals());
  for (const Eigen::Vector3d& n : cloud.normals) EXPECT_NEAR(n.norm(), 1.0, 1e-12);
}

// Real data: the UWA parasaurolophus mesh ships with vertex normals written by VCGLIB
// (unnormalized, from a processing history we do not know). Ours from its faces must agree
// with them in side and, for almost every vertex, in direction. Measured: median 2.10 deg, 99th
// percentile 41 deg (vertices on the thin crest and the feet, where one face more or less
// turns the normal), 15 of 6700 on the opposite side.
TEST(MeshNormalsTest, AgreeWithTheNormalsShippedWithTheRealUwaMesh) {
  const std::string path = test::RealDataFile("uwa", "parasaurolophus_6700.ply");
  ASSERT_FALSE(path.empty()) << "datasets/real/uwa/parasaurolophus_6700.ply missing";
  const TriangleMesh mesh = io::ReadPlyMesh(path);
  ASSERT_FALSE(mesh.faces.empty());
  const std::vector<Eigen::Vector3d> ours = MeshVertexNormals(mesh);
  std::vector<double> angles_deg;
  int opposite = 0;
  for (std::size_t i = 0; i < ours.size(); ++i) {
    if (ours[i].isZero()) continue;
    const double c = std::clamp(ours[i].dot(mesh.vertices.normals[i].normalized()), -1.0, 1.0);
    if (c < 0) ++opposite;
    angles_deg.push_back(std::acos(c) * 180.0 / std::numbers::pi);
  }
  ASSERT_GT(angles_deg.size(), mesh.vertices.size() * 99 / 100);
  std::sort(angles_deg.begin(), angles_deg.end());
  const double median = angles_deg[angles_deg.size() / 2];
  const double p99 = angles_deg[angles_deg.size() * 99 / 100];
  std::printf(
      "UWA mesh: %zu vertex normals, median %.4f deg, 99th percentile %.4f deg, %d "
      "opposite\n",
      angles_deg.size(), median, p99, opposite);
  EXPECT_LT(median, 5.0);
  EXPECT_LT(p99, 60.0);
  EXPECT_LT(opposite, static_cast<int>(angles_deg.size()) / 200);  // < 0.5 %
}

TEST(MeshNormalsTest, RejectsAMeshWithoutFacesOrWithABadIndex) {
  TriangleMesh mesh = ThinSlab(2, 1.0, 1.0);
  TriangleMesh no_faces = mesh;
  no_faces.faces.clear();
  EXPECT_THAT([&] { MeshVertexNormals(no_faces); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("has no faces")));
  mesh.faces[3] = {0, 1, 999};
  EXPECT_THAT([&] { MeshVertexNormals(mesh); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("face 3 uses vertex 999")));
}

}  // namespace
}  // namespace lasercell::registration
