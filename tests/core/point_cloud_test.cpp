#include "core/point_cloud.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "core/error.hpp"
#include "core/random.hpp"
#include "core/se3.hpp"

namespace lasercell {
namespace {

using ::testing::HasSubstr;

PointCloud RandomCloud(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-100.0, 100.0);
  PointCloud cloud;
  for (std::size_t i = 0; i < n; ++i) {
    cloud.positions.push_back(Eigen::Vector3d{u(rng), u(rng), u(rng)});
    cloud.normals.push_back(Draws<3>(u, rng).normalized());
    cloud.intensity.push_back(static_cast<float>(i));
  }
  return cloud;
}

TEST(PointCloudTest, BoundsAndCentroid) {
  PointCloud cloud;
  EXPECT_TRUE(cloud.Bounds().Empty());
  EXPECT_EQ(cloud.Centroid(), Eigen::Vector3d::Zero());
  cloud.positions = {{0, 0, 0}, {2, 4, 6}, {-2, 0, 3}};
  const BoundingBox box = cloud.Bounds();
  EXPECT_FALSE(box.Empty());
  EXPECT_EQ(box.min, Eigen::Vector3d(-2, 0, 0));
  EXPECT_EQ(box.max, Eigen::Vector3d(2, 4, 6));
  EXPECT_DOUBLE_EQ(box.Diagonal(), std::sqrt(16.0 + 16.0 + 36.0));
  EXPECT_TRUE(box.Contains({0, 2, 3}));
  EXPECT_FALSE(box.Contains({0, 5, 3}));
  EXPECT_TRUE(cloud.Centroid().isApprox(Eigen::Vector3d(0, 4.0 / 3.0, 3)));
}

TEST(PointCloudTest, TransformMovesPositionsAndRotatesNormals) {
  const PointCloud cloud = RandomCloud(50, 1);
  const Eigen::Isometry3d t = PoseFromRotationVector({0.3, -0.2, 1.1}, {10, 20, -30});
  const PointCloud moved = cloud.Transformed(t);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    EXPECT_TRUE(moved.positions[i].isApprox(t * cloud.positions[i], 1e-12));
    EXPECT_TRUE(moved.normals[i].isApprox(t.linear() * cloud.normals[i], 1e-12));
    EXPECT_NEAR(moved.normals[i].norm(), 1.0, 1e-12);
  }
  const PointCloud back = moved.Transformed(t.inverse());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    EXPECT_LT((back.positions[i] - cloud.positions[i]).norm(), 1e-9);
  }
}

TEST(PointCloudTest, SubsetKeepsAttributesAndGrid) {
  PointCloud cloud = RandomCloud(10, 2);
  cloud.grid_rows = 2;
  cloud.grid_cols = 5;
  for (int i = 0; i < 10; ++i) {
    cloud.profile.push_back(i / 5);
    cloud.column.push_back(i % 5);
  }
  const std::vector<std::size_t> idx = {7, 2};
  const PointCloud sub = cloud.Subset(idx);
  ASSERT_EQ(sub.size(), 2u);
  EXPECT_EQ(sub.positions[0], cloud.positions[7]);
  EXPECT_EQ(sub.intensity[1], 2.0f);
  EXPECT_EQ(sub.profile[0], 1);
  EXPECT_EQ(sub.column[0], 2);
  EXPECT_TRUE(sub.IsOrganized());
  EXPECT_FALSE(sub.HasTimestamps());
  EXPECT_EQ(sub.FieldNames(), "x y z nx ny nz intensity profile column");
}

TEST(PointCloudTest, AppendRequiresSameAttributes) {
  PointCloud a = RandomCloud(3, 3), b = RandomCloud(4, 4);
  a.Append(b);
  EXPECT_EQ(a.size(), 7u);
  EXPECT_EQ(a.normals.size(), 7u);
  PointCloud plain;
  plain.positions = {{1, 2, 3}};
  try {
    a.Append(plain);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("different attributes"));
  }
  PointCloud empty;
  empty.Append(b);
  EXPECT_EQ(empty.size(), 4u);
}

TEST(PointCloudTest, ValidateRejectsMismatchedSizesAndNonFinite) {
  PointCloud cloud = RandomCloud(5, 5);
  EXPECT_NO_THROW(cloud.Validate());
  cloud.intensity.pop_back();
  try {
    cloud.Validate("scene.ply");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("scene.ply"));
    EXPECT_THAT(e.what(), HasSubstr("intensity"));
  }
  cloud = RandomCloud(5, 5);
  cloud.positions[3].y() = std::numeric_limits<double>::quiet_NaN();
  try {
    cloud.Validate("scene.ply");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("point 3"));
    EXPECT_THAT(e.what(), HasSubstr("non-finite"));
  }
  cloud = RandomCloud(5, 5);
  cloud.normals[1].x() = std::numeric_limits<double>::infinity();
  EXPECT_THROW(cloud.Validate(), InputError);
}

TEST(PointCloudTest, ValidateRejectsGridIndicesOutsideGrid) {
  PointCloud cloud;
  cloud.positions = {{0, 0, 0}};
  cloud.profile = {3};
  cloud.column = {0};
  cloud.grid_rows = 3;
  cloud.grid_cols = 1;
  try {
    cloud.Validate();
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("profile 3 outside the grid"));
  }
}

TEST(ErrorTest, CheckThrowsInternalErrorWithLocation) {
  try {
    LASERCELL_CHECK(1 + 1 == 3, "arithmetic");
    FAIL();
  } catch (const InternalError& e) {
    EXPECT_THAT(e.what(), HasSubstr("1 + 1 == 3"));
    EXPECT_THAT(e.what(), HasSubstr("point_cloud_test.cpp"));
    EXPECT_THAT(e.what(), HasSubstr("arithmetic"));
  }
  EXPECT_NO_THROW(LASERCELL_CHECK(true, ""));
}

TEST(ErrorTest, FileErrorNamesThePath) {
  const FileError e("/tmp/x.ply", "truncated");
  EXPECT_EQ(std::string(e.what()), "/tmp/x.ply: truncated");
  EXPECT_EQ(e.path(), "/tmp/x.ply");
  const InputError& base = e;  // FileError is an input error (exit 2)
  EXPECT_THAT(base.what(), HasSubstr("truncated"));
}

}  // namespace
}  // namespace lasercell
