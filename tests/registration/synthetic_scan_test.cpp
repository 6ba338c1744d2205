// datasets/synthetic_scan.hpp, the generator behind the synthetic registration tests and
// `lasercell bench robustness`, on small synthetic inputs with known answers.
#include "datasets/synthetic_scan.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/error.hpp"
#include "registration_test_util.hpp"

namespace lasercell::datasets {
namespace {

using ::testing::HasSubstr;

// A square patch in the x/y plane (normal +z), `half_mm` wide, spacing `step_mm`.
PointCloud Patch(double half_mm, double step_mm) {
  PointCloud cloud;
  for (double x = -half_mm; x <= half_mm + 1e-9; x += step_mm) {
    for (double y = -half_mm; y <= half_mm + 1e-9; y += step_mm) {
      cloud.positions.emplace_back(x, y, 0.0);
      cloud.normals.emplace_back(0.0, 0.0, 1.0);
    }
  }
  return cloud;
}

Eigen::Isometry3d At(const Eigen::Vector3d& t) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = t;
  return pose;
}

TEST(SyntheticScanTest, OptionsAreChecked) {
  SyntheticScanOptions options;
  EXPECT_NO_THROW(options.Check());
  options.noise_sigma_mm = -1.0;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("noise_sigma_mm")));
  options = {};
  options.zbuffer_cell_mm = 0.0;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("zbuffer_cell_mm")));
  options = {};
  options.part_normal_neighbors = 2;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("part_normal_neighbors")));
}

// The clutter: a wall 700 mm away. The part: a patch 600 mm away, 100 mm wide, in front of it.
class SyntheticScanFixture : public ::testing::Test {
 protected:
  PointCloud wall_ = Patch(150.0, 1.0).Transformed(At({0, 0, -700}));
  PointCloud part_ = Patch(50.0, 0.5);
  Eigen::Isometry3d pose_ = At({0, 0, -600});
};

TEST_F(SyntheticScanFixture, NoPoseGivesTheVisibleClutterOnly) {
  const SyntheticScan scan = RenderSyntheticScan(wall_, part_, {}, SyntheticScanOptions{});
  EXPECT_EQ(scan.part_points, 0U);
  EXPECT_EQ(scan.clutter_points, scan.cloud.size());
  EXPECT_EQ(scan.cloud.size(), VisibleFromOrigin(wall_, 0.8, 2.0).size());
  EXPECT_EQ(scan.cloud.size(), wall_.size());  // a plane facing the sensor hides nothing of itself
}

TEST_F(SyntheticScanFixture, PartOccludesTheClutterBehindIt) {
  SyntheticScanOptions options;
  options.noise_sigma_mm = 0.0;
  const SyntheticScan scan = RenderSyntheticScan(wall_, part_, {pose_}, options);
  EXPECT_EQ(scan.part_points, part_.size());
  // The part hides the wall inside its shadow: a cone from the origin, 100 x 700/600 mm wide.
  std::size_t shadowed = 0;
  for (const auto& p : wall_.positions)
    shadowed += (std::abs(p.x()) < 50.0 * 700.0 / 600.0 - 1.0 &&
                 std::abs(p.y()) < 50.0 * 700.0 / 600.0 - 1.0)
                    ? 1
                    : 0;
  EXPECT_LE(scan.clutter_points, wall_.size() - shadowed);
  EXPECT_GT(scan.clutter_points, wall_.size() / 2);
  // Re-estimated part normals face the sensor (+z here).
  for (std::size_t i = scan.clutter_points; i < scan.cloud.size(); ++i)
    EXPECT_GT(scan.cloud.normals[i].z(), 0.99);
}

TEST_F(SyntheticScanFixture, SameSeedSameScanOtherSeedOtherScan) {
  SyntheticScanOptions options;
  options.seed = 5;
  const SyntheticScan a = RenderSyntheticScan(wall_, part_, {pose_}, options);
  const SyntheticScan b = RenderSyntheticScan(wall_, part_, {pose_}, options);
  options.seed = 6;
  const SyntheticScan c = RenderSyntheticScan(wall_, part_, {pose_}, options);
  EXPECT_EQ(a.cloud.positions, b.cloud.positions);
  EXPECT_EQ(a.cloud.normals, b.cloud.normals);
  EXPECT_NE(a.cloud.positions, c.cloud.positions);
}

// Noise is along the line of sight with the requested sigma: for the patch 600 mm in front of
// the sensor the depth deviations have sample sigma within 5 % of 0.7 mm (n ~ 40000: the
// standard error of a sample sigma is sigma / sqrt(2n), 0.35 %).
TEST_F(SyntheticScanFixture, NoiseHasTheRequestedSigmaAlongTheLineOfSight) {
  SyntheticScanOptions options;
  options.noise_sigma_mm = 0.7;
  options.zbuffer_depth_tolerance_mm = 10.0;  // keep every noisy point of the patch
  const SyntheticScan scan = RenderSyntheticScan(wall_, part_, {pose_}, options);
  ASSERT_EQ(scan.part_points, part_.size());
  double sum_sq = 0.0;
  std::size_t n = 0;
  for (std::size_t i = scan.clutter_points; i < scan.cloud.size(); ++i) {
    const Eigen::Vector3d& p = scan.cloud.positions[i];
    // Distance from the patch plane z = -600 along the ray through p.
    const double along_ray = (p.z() + 600.0) * p.norm() / -p.z();
    sum_sq += along_ray * along_ray;
    ++n;
  }
  ASSERT_GT(n, 30000U);
  EXPECT_NEAR(std::sqrt(sum_sq / static_cast<double>(n)), 0.7, 0.035);
}

TEST(SyntheticScanTest, MeshSamplingHasTheRequestedDensity) {
  TriangleMesh mesh;  // a 100 x 100 mm square from two triangles, normal +z
  mesh.vertices.positions = {{0, 0, 0}, {100, 0, 0}, {100, 100, 0}, {0, 100, 0}};
  mesh.vertices.normals.assign(4, Eigen::Vector3d::UnitZ());
  mesh.faces = {{0, 1, 2}, {0, 2, 3}};
  const PointCloud sampled = SampleMeshSurface(mesh, 0.5, 3);
  EXPECT_NEAR(static_cast<double>(sampled.size()), 20000.0,
              2.0);  // stochastic rounding: +-1 per face
  for (std::size_t i = 0; i < sampled.size(); ++i) {
    EXPECT_NEAR(sampled.positions[i].z(), 0.0, 1e-12);
    EXPECT_GE(sampled.positions[i].x(), -1e-9);
    EXPECT_LE(sampled.positions[i].x(), 100.0 + 1e-9);
    EXPECT_NEAR(sampled.normals[i].z(), 1.0, 1e-12);
  }
}

TEST(SyntheticScanTest, CutOutRemovesOnlyThePartsSurroundings) {
  const PointCloud scene = Patch(100.0, 1.0);
  const PointCloud part = Patch(10.0, 1.0).Transformed(At({50, 50, 0}));
  const PointCloud cut = CutOutModel(scene, part, 2.0);
  // Removed: the 21 x 21 part footprint grown by 2 mm on each side (25 x 25, corners rounded).
  EXPECT_LT(cut.size(), scene.size() - 21 * 21);
  EXPECT_GT(cut.size(), scene.size() - 25 * 25);
  for (const auto& p : cut.positions)
    EXPECT_FALSE(std::abs(p.x() - 50) <= 10 && std::abs(p.y() - 50) <= 10);
}

TEST(SyntheticScanTest, ReadPoseFileReadsTheReferenceAndRejectsMissingFiles) {
  EXPECT_THROW(ReadPoseFile("/nonexistent/pose.txt"), FileError);
  const Eigen::Isometry3d rs1 =
      ReadPoseFile(std::string(LASERCELL_SOURCE_DIR) +
                   "/tests/registration/data/rs1_parasaurolophus_reference.txt");
  EXPECT_NEAR(rs1.linear().determinant(), 1.0, 1e-6);
}

}  // namespace
}  // namespace lasercell::datasets
