#include "registration/filters.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <random>
#include <vector>

#include "core/error.hpp"
#include "core/se3.hpp"

namespace lasercell::registration {
namespace {

using ::testing::HasSubstr;

TEST(CropBoxTest, KeepsPointsInsideTheBoxInAGivenFrame) {
  PointCloud cloud;
  cloud.positions = {{0, 0, 0}, {5, 0, 0}, {10, 0, 0}, {0, 20, 0}};
  cloud.intensity = {1, 2, 3, 4};
  BoundingBox box;
  box.Extend({-1, -1, -1});
  box.Extend({6, 1, 1});
  EXPECT_EQ(CropBoxIndices(cloud, box), (std::vector<std::size_t>{0, 1}));
  // The same box in a frame shifted by -5 mm along x: frame_from_cloud maps x -> x - 5.
  const Eigen::Isometry3d frame_from_cloud =
      PoseFromRotationVector(Eigen::Vector3d::Zero(), {-5, 0, 0});
  EXPECT_EQ(CropBoxIndices(cloud, box, frame_from_cloud), (std::vector<std::size_t>{1, 2}));
  const PointCloud cropped = CropBox(cloud, box, frame_from_cloud);
  ASSERT_EQ(cropped.size(), 2U);
  EXPECT_EQ(cropped.intensity, (std::vector<float>{2, 3}));
  // Rotated frame: 90 deg about z maps (0, 20, 0) to (-20, 0, 0).
  const Eigen::Isometry3d rotated =
      PoseFromRotationVector({0, 0, std::numbers::pi / 2}, Eigen::Vector3d::Zero());
  BoundingBox left;
  left.Extend({-21, -1, -1});
  left.Extend({-19, 1, 1});
  EXPECT_EQ(CropBoxIndices(cloud, left, rotated), (std::vector<std::size_t>{3}));
}

// Two dense blobs and a few isolated points, on a grid so the organized path can run too.
PointCloud TwoBlobsAndSpecks() {
  PointCloud cloud;
  cloud.grid_rows = 40;
  cloud.grid_cols = 40;
  auto add = [&](int r, int c, const Eigen::Vector3d& p) {
    cloud.positions.push_back(p);
    cloud.profile.push_back(r);
    cloud.column.push_back(c);
  };
  for (int r = 0; r < 10; ++r) {
    for (int c = 0; c < 10; ++c) add(r, c, {r * 1.0, c * 1.0, 0.0});  // blob A: 100 points
  }
  for (int r = 20; r < 28; ++r) {
    for (int c = 20; c < 28; ++c) add(r, c, {r * 1.0, c * 1.0, 5.0});  // blob B: 64 points
  }
  add(35, 5, {35, 5, 0});   // isolated
  add(35, 6, {35, 6, 0});   // its neighbour: a 2-point cluster
  add(5, 35, {5, 35, 50});  // isolated
  return cloud;
}

TEST(ClusterFilterTest, RemovesSmallComponentsByRadiusAndByGrid) {
  const PointCloud cloud = TwoBlobsAndSpecks();
  ClusterFilterOptions options;
  options.radius_mm = 1.5;
  options.min_cluster_size = 10;
  for (bool grid : {false, true}) {
    options.use_grid_when_organized = grid;
    const ClusterFilterResult result = RemoveSmallClusters(cloud, options);
    EXPECT_EQ(result.used_grid, grid);
    EXPECT_EQ(result.components, 4U);
    EXPECT_EQ(result.removed_components, 2U);
    EXPECT_EQ(result.kept.size(), 164U);
    EXPECT_EQ(result.labels[0], 0);  // labels in order of first point
    EXPECT_EQ(result.labels[100], 1);
    EXPECT_EQ(result.labels[164], result.labels[165]);
    EXPECT_NE(result.labels[164], result.labels[166]);
  }
}

TEST(ClusterFilterTest, GridPathRespectsTheDistance) {
  // Grid neighbours that are far apart in space (a depth jump) are not connected.
  PointCloud cloud;
  cloud.grid_rows = 1;
  cloud.grid_cols = 4;
  cloud.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 30}, {3, 0, 30}};
  cloud.profile = {0, 0, 0, 0};
  cloud.column = {0, 1, 2, 3};
  ClusterFilterOptions options;
  options.radius_mm = 1.5;
  options.min_cluster_size = 1;
  EXPECT_EQ(RemoveSmallClusters(cloud, options).components, 2U);
}

TEST(ClusterFilterTest, RejectsBadOptions) {
  ClusterFilterOptions options;
  options.radius_mm = -1.0;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("radius_mm")));
  options = {};
  options.grid_window = 0;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("grid_window")));
}

TEST(VoxelGridTest, CentroidsAndAveragedNormals) {
  PointCloud cloud;
  // Voxel [0,10)^3: two points; voxel [10,20) x ...: one point. Bounds start at the min point.
  cloud.positions = {{0, 0, 0}, {4, 2, 0}, {15, 0, 0}};
  cloud.normals = {{0, 0, 1}, {0, 1, 0}, {1, 0, 0}};
  VoxelGridOptions options;
  options.voxel_size_mm = 10.0;
  std::vector<std::int32_t> voxel_of_point;
  const PointCloud out = VoxelGridDownsample(cloud, options, &voxel_of_point);
  ASSERT_EQ(out.size(), 2U);
  EXPECT_TRUE(out.positions[0].isApprox(Eigen::Vector3d(2, 1, 0)));
  EXPECT_TRUE(out.normals[0].isApprox(Eigen::Vector3d(0, 1, 1).normalized()));
  EXPECT_TRUE(out.positions[1].isApprox(Eigen::Vector3d(15, 0, 0)));
  EXPECT_EQ(voxel_of_point, (std::vector<std::int32_t>{0, 0, 1}));

  // Carried normal: the dense point nearest the centroid (7/3, 0, 0) is (1, 0, 0).
  PointCloud three;
  three.positions = {{0, 0, 0}, {6, 0, 0}, {1, 0, 0}};
  three.normals = {{0, 0, 1}, {0, 1, 0}, {1, 0, 0}};
  options.normal_mode = VoxelNormalMode::kNearestPoint;
  const PointCloud carried = VoxelGridDownsample(three, options);
  ASSERT_EQ(carried.size(), 1U);
  EXPECT_TRUE(carried.normals[0].isApprox(Eigen::Vector3d(1, 0, 0)));

  // Normal coherence: two orthogonal normals average to length 0.707.
  options.normal_mode = VoxelNormalMode::kAverage;
  options.min_normal_coherence = 0.6;
  EXPECT_EQ(VoxelGridDownsample(cloud, options).size(), 2U);
  options.min_normal_coherence = 0.8;
  EXPECT_EQ(VoxelGridDownsample(cloud, options).size(), 1U);

  options = {};
  options.voxel_size_mm = 10.0;
  options.normal_mode = VoxelNormalMode::kNone;
  EXPECT_FALSE(VoxelGridDownsample(cloud, options).HasNormals());
}

TEST(VoxelGridTest, OneCentroidPerOccupiedVoxelOnRandomData) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0.0, 100.0);
  PointCloud cloud;
  for (int i = 0; i < 20000; ++i) cloud.positions.push_back({u(rng), u(rng), u(rng)});
  VoxelGridOptions options;
  options.voxel_size_mm = 7.0;
  std::vector<std::int32_t> voxel_of_point;
  const PointCloud out = VoxelGridDownsample(cloud, options, &voxel_of_point);
  // Every output point is the mean of the input points mapped to it, and lies in their voxel.
  std::vector<Eigen::Vector3d> sum(out.size(), Eigen::Vector3d::Zero());
  std::vector<int> count(out.size(), 0);
  const Eigen::Vector3d origin = cloud.Bounds().min;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    sum[static_cast<std::size_t>(voxel_of_point[i])] += cloud.positions[i];
    ++count[static_cast<std::size_t>(voxel_of_point[i])];
    const Eigen::Vector3d a = ((cloud.positions[i] - origin) / 7.0).array().floor();
    const Eigen::Vector3d b =
        ((out.positions[static_cast<std::size_t>(voxel_of_point[i])] - origin) / 7.0)
            .array()
            .floor();
    ASSERT_EQ(a, b);
  }
  for (std::size_t v = 0; v < out.size(); ++v)
    EXPECT_TRUE(out.positions[v].isApprox(sum[v] / count[v], 1e-12));
  EXPECT_LE(out.size(), 15U * 15U * 15U);
  EXPECT_GT(out.size(), 14U * 14U * 14U);
}

// A 4 mm wall in 10 mm voxels: without the split each voxel averages both faces into a point
// inside the wall whose normal is meaningless (here the two normals cancel); with it, each face
// keeps its own sample on the face with its own normal.
TEST(VoxelGridTest, NormalSplitKeepsTheTwoFacesOfAThinWallApart) {
  PointCloud wall;
  for (int x = 0; x < 10; ++x) {
    for (int y = 0; y < 10; ++y) {
      wall.positions.push_back({x + 0.5, y + 0.5, 2.0});
      wall.normals.push_back({0, 0, 1});
      wall.positions.push_back({x + 0.5, y + 0.5, -2.0});
      wall.normals.push_back({0, 0, -1});
    }
  }
  VoxelGridOptions options;
  options.voxel_size_mm = 10.0;
  options.min_normal_coherence = 0.5;
  EXPECT_EQ(VoxelGridDownsample(wall, options).size(), 0U);  // every voxel incoherent
  options.normal_split_angle_rad = std::numbers::pi / 2;
  std::vector<std::int32_t> voxel_of_point;
  const PointCloud split = VoxelGridDownsample(wall, options, &voxel_of_point);
  ASSERT_EQ(split.size(), 2U);
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_NEAR(std::abs(split.positions[k].z()), 2.0, 1e-12);
    EXPECT_NEAR(split.normals[k].z(), split.positions[k].z() > 0 ? 1.0 : -1.0, 1e-12);
  }
  for (std::size_t i = 0; i < wall.size(); ++i) {
    EXPECT_EQ(split.positions[static_cast<std::size_t>(voxel_of_point[i])].z(),
              wall.positions[i].z());
  }
  // Normals within the angle share a sample.
  wall.normals[1] = Eigen::Vector3d(0, 1, 1).normalized();
  for (std::size_t i = 1; i < wall.size(); i += 2) wall.normals[i] = wall.normals[1];
  EXPECT_EQ(VoxelGridDownsample(wall, options).size(), 1U);
}

TEST(VoxelGridTest, RejectsBadOptions) {
  VoxelGridOptions options;
  options.voxel_size_mm = 0.0;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("voxel_size_mm")));
  options.voxel_size_mm = 1.0;
  options.min_normal_coherence = 2.0;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("min_normal_coherence")));
  options.min_normal_coherence = 0.0;
  options.normal_split_angle_rad = 4.0;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("normal_split_angle_rad")));
  // Voxels far too small for the extent.
  PointCloud cloud;
  cloud.positions = {{0, 0, 0}, {1e6, 0, 0}};
  options = {};
  options.voxel_size_mm = 1e-3;
  EXPECT_THAT([&] { VoxelGridDownsample(cloud, options); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("too small")));
}

// One point per occupied cell, the first in input order: kept points lie in distinct cells, every
// input point has one in its own cell (so within sqrt(3) x the cell), indices ascend; a cell that
// is not positive is refused naming it.
TEST(OnePerCellTest, KeepsTheFirstPointOfEveryOccupiedCell) {
  std::mt19937_64 rng(31);
  std::uniform_real_distribution<double> u(-20.0, 20.0);
  std::vector<Eigen::Vector3d> points(5000);
  for (Eigen::Vector3d& p : points) p = {u(rng), u(rng), 0.1 * u(rng)};
  constexpr double kCell = 3.0;
  const auto cell_of = [](const Eigen::Vector3d& p) {
    return std::array<long, 3>{static_cast<long>(std::floor(p.x() / kCell)),
                               static_cast<long>(std::floor(p.y() / kCell)),
                               static_cast<long>(std::floor(p.z() / kCell))};
  };
  const std::vector<std::size_t> kept = OnePerCellIndices(points, kCell);
  ASSERT_FALSE(kept.empty());
  EXPECT_LT(kept.size(), points.size());
  EXPECT_TRUE(std::is_sorted(kept.begin(), kept.end()));
  std::map<std::array<long, 3>, std::size_t> first;
  for (std::size_t i = 0; i < points.size(); ++i) first.emplace(cell_of(points[i]), i);
  ASSERT_EQ(kept.size(), first.size());
  for (std::size_t i : kept) EXPECT_EQ(first.at(cell_of(points[i])), i);
  // The point nearest each cell's centre instead: one per cell too, ascending, and no other
  // point of its cell is nearer the centre.
  const std::vector<std::size_t> central =
      OnePerCellIndices(points, kCell, CellPoint::kNearestCentre);
  ASSERT_EQ(central.size(), kept.size());
  EXPECT_TRUE(std::is_sorted(central.begin(), central.end()));
  const auto centre_distance = [&](const Eigen::Vector3d& p) {
    const std::array<long, 3> c = cell_of(p);
    return (Eigen::Vector3d(c[0] + 0.5, c[1] + 0.5, c[2] + 0.5) * kCell - p).norm();
  };
  std::map<std::array<long, 3>, double> nearest;
  for (const Eigen::Vector3d& p : points) {
    const auto [it, added] = nearest.emplace(cell_of(p), centre_distance(p));
    if (!added) it->second = std::min(it->second, centre_distance(p));
  }
  std::size_t moved = 0;
  for (std::size_t k = 0; k < central.size(); ++k) {
    const Eigen::Vector3d& p = points[central[k]];
    EXPECT_EQ(centre_distance(p), nearest.at(cell_of(p)));
    moved += central[k] != kept[k] ? 1 : 0;
  }
  EXPECT_GT(moved, 0U);
  // Far from the origin (beyond the packed keys' +-2^20 cells) the same cells are found.
  std::vector<Eigen::Vector3d> far = points;
  for (Eigen::Vector3d& p : far) p.x() += 1e7 * kCell;
  EXPECT_EQ(OnePerCellIndices(far, kCell).size(), kept.size());
  EXPECT_EQ(OnePerCellIndices(far, kCell, CellPoint::kNearestCentre).size(), kept.size());
  EXPECT_THROW(OnePerCellIndices(points, 0.0), OptionError);
  EXPECT_TRUE(OnePerCellIndices({}, 1.0).empty());
  std::vector<Eigen::Vector3d> with_nan = points;
  with_nan[3].y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THAT([&] { OnePerCellIndices(with_nan, kCell); },
              ::testing::ThrowsMessage<InputError>(::testing::HasSubstr("point 3 is not finite")));
}

TEST(VoxelGridTest, EmptyCloudGivesEmptyOutput) {
  VoxelGridOptions options;
  std::vector<std::int32_t> voxel_of_point{1, 2};
  EXPECT_TRUE(VoxelGridDownsample(PointCloud{}, options, &voxel_of_point).empty());
  EXPECT_TRUE(voxel_of_point.empty());
}

}  // namespace
}  // namespace lasercell::registration
