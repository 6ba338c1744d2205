#include "registration/verification.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <random>

#include "core/error.hpp"
#include "core/se3.hpp"
#include "registration_test_util.hpp"

namespace lasercell::registration {
namespace {

using ::testing::HasSubstr;

class VerificationTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const PointCloud box = test::BoxPoints({40, 30, 20}, 1.0);
    PpfModelOptions options;
    options.sampling_step_relative = 0.1;
    model_ = PpfModel::Build(box, options);
    // Scene: the box resting on a floor z = -450, seen from the origin (sensor above, looking -z).
    truth_ = PoseFromRotationVector({0, 0, 0.4}, {10, -20, -430});
    PointCloud world = box.Transformed(truth_);
    for (double x = -150; x <= 150; x += 1.0) {
      for (double y = -150; y <= 150; y += 1.0) {
        world.positions.push_back({x, y, -450});
        world.normals.push_back(Eigen::Vector3d::UnitZ());
      }
    }
    std::mt19937_64 rng(51);
    scene_ = test::SimulateView(world, viewpoint_, 1.0, 0.5, 0.1, rng).positions;
  }

  VerificationResult Verify(const Eigen::Isometry3d& pose, const VerificationOptions& options,
                            std::vector<std::uint32_t>* overlap = nullptr) const {
    return VerifyPose(scene_, model_, pose, viewpoint_, options, overlap);
  }

  PpfModel model_;
  Eigen::Isometry3d truth_;
  Viewpoint viewpoint_ = Viewpoint::AtPoint(Eigen::Vector3d::Zero());
  std::vector<Eigen::Vector3d> scene_;
};

TEST_F(VerificationTest, TruePoseIsSupportedAndSelectsTheOverlap) {
  VerificationOptions options;
  options.support_distance_mm = 2.0;
  options.overlap_band_mm = 3.0;
  std::vector<std::uint32_t> overlap;
  const VerificationResult result = Verify(truth_, options, &overlap);
  EXPECT_TRUE(result.accepted) << result.Summary();
  EXPECT_GT(result.support, 0.9) << result.Summary();
  EXPECT_GT(result.visible_cells, 500U);
  // The overlap is the box's visible surface (top face: 80 x 60 mm at 1 mm); floor points enter
  // only along the bottom edges, where the box's side faces meet the floor.
  EXPECT_GT(overlap.size(), 4000U);
  EXPECT_EQ(result.overlapping_scene_points, overlap.size());
  const auto on_floor = std::count_if(overlap.begin(), overlap.end(),
                                      [&](std::uint32_t i) { return scene_[i].z() < -449.0; });
  EXPECT_LT(static_cast<double>(on_floor), 0.05 * overlap.size());
  EXPECT_TRUE(std::is_sorted(overlap.begin(), overlap.end()));
}

TEST_F(VerificationTest, WrongPosesAreRejectedWithReasons) {
  VerificationOptions options;
  options.support_distance_mm = 2.0;
  // Floating 15 mm toward the sensor: the scene is seen behind the model (free-space conflict).
  const Eigen::Isometry3d floating =
      PoseFromRotationVector(Eigen::Vector3d::Zero(), {0, 0, 15}) * truth_;
  const VerificationResult in_front = Verify(floating, options);
  EXPECT_FALSE(in_front.accepted);
  EXPECT_LT(in_front.support, 0.3);
  EXPECT_GT(in_front.conflicting_cells, in_front.occluded_cells);
  EXPECT_THAT(in_front.rejection_reason, HasSubstr("support"));
  // Sunk 15 mm into the floor: the scene lies in front of the model (occlusion).
  const Eigen::Isometry3d sunk =
      PoseFromRotationVector(Eigen::Vector3d::Zero(), {0, 0, -15}) * truth_;
  const VerificationResult behind = Verify(sunk, options);
  EXPECT_FALSE(behind.accepted);
  EXPECT_GT(behind.occluded_cells, behind.conflicting_cells);
  // Outside the scanned area: no scene at all in its cells.
  const Eigen::Isometry3d away =
      PoseFromRotationVector(Eigen::Vector3d::Zero(), {500, 0, 0}) * truth_;
  const VerificationResult empty = Verify(away, options);
  EXPECT_FALSE(empty.accepted);
  EXPECT_EQ(empty.empty_cells, empty.visible_cells);
  EXPECT_THAT(empty.Summary(), HasSubstr("rejected"));
}

TEST_F(VerificationTest, SupportingPlaneAndStablePoses) {
  VerificationOptions options;
  options.support_distance_mm = 2.0;
  options.constraints.enabled = true;
  options.constraints.plane_normal = Eigen::Vector3d::UnitZ();
  options.constraints.plane_offset_mm = -450.0;
  options.constraints.up_in_model = {Eigen::Vector3d::UnitZ()};
  options.constraints.max_tilt_rad = 0.2;
  options.constraints.max_penetration_mm = 2.0;
  const VerificationResult upright = Verify(truth_, options);
  EXPECT_TRUE(upright.accepted) << upright.Summary();
  EXPECT_NEAR(upright.tilt_rad, 0.0, 1e-9);
  EXPECT_LT(upright.penetration_mm, 2.0);

  const Eigen::Isometry3d tilted =
      truth_ * PoseFromRotationVector({0.7, 0, 0}, Eigen::Vector3d::Zero());
  const VerificationResult tilt = Verify(tilted, options);
  EXPECT_FALSE(tilt.accepted);
  EXPECT_NEAR(tilt.tilt_rad, 0.7, 1e-9);
  EXPECT_THAT(tilt.rejection_reason, HasSubstr("tilt"));
  // A second stable pose (lying on another face) makes the tilted orientation legal.
  VerificationResult result;
  PoseConstraints stable = options.constraints;
  stable.up_in_model.push_back(Eigen::AngleAxisd(-0.7, Eigen::Vector3d::UnitX()) *
                               Eigen::Vector3d::UnitZ());
  stable.max_penetration_mm = -1.0;
  EXPECT_TRUE(CheckPoseConstraints(model_, tilted, stable, &result));
  EXPECT_NEAR(result.tilt_rad, 0.0, 1e-9);

  const Eigen::Isometry3d sunk =
      PoseFromRotationVector(Eigen::Vector3d::Zero(), {0, 0, -10}) * truth_;
  const VerificationResult sinks = Verify(sunk, options);
  EXPECT_FALSE(sinks.accepted);
  EXPECT_NEAR(sinks.penetration_mm, 10.0, 1.0);
  EXPECT_THAT(sinks.rejection_reason, HasSubstr("sinks"));
}

TEST(VerificationOptionsTest, RejectsAbsurdValues) {
  VerificationOptions options;
  options.grid_rows = 0;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("grid_rows/grid_cols = 0x48")));
  options = {};
  options.support_distance_mm = -1.0;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("support_distance_mm")));
  options = {};
  options.min_support = 1.5;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("min_support")));
  options = {};
  options.constraints.enabled = true;
  options.constraints.plane_normal = Eigen::Vector3d::Zero();
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("plane_normal")));
}

}  // namespace
}  // namespace lasercell::registration
