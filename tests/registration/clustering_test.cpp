#include "registration/clustering.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <random>

#include "core/error.hpp"
#include "core/se3.hpp"
#include "registration_test_util.hpp"

namespace lasercell::registration {
namespace {

using ::testing::HasSubstr;

// `count` hypotheses scattered around `centre` by `trans_mm` and `angle_rad`.
void AddGroup(const Eigen::Isometry3d& centre, int count, double votes, double trans_mm,
              double angle_rad, std::mt19937_64& rng, std::vector<PoseHypothesis>* out) {
  std::uniform_real_distribution<double> u(0.2, 1.0);
  for (int i = 0; i < count; ++i) {
    PoseHypothesis h;
    h.scene_from_centered =
        centre * test::RandomPerturbation(rng, angle_rad * u(rng), trans_mm * u(rng));
    h.votes = votes;
    out->push_back(h);
  }
}

TEST(ClusteringTest, QuaternionDistanceIsTheSeedFormula) {
  std::mt19937_64 rng(41);
  for (int i = 0; i < 100; ++i) {
    const Eigen::Quaterniond a(test::RandomPose(rng, 1.0).linear()),
        b(test::RandomPose(rng, 1.0).linear());
    EXPECT_NEAR(QuaternionDistance(a, b), RotationDistance(a, b), 1e-7);
    Eigen::Quaterniond minus_b(-b.w(), -b.x(), -b.y(), -b.z());
    EXPECT_NEAR(QuaternionDistance(a, minus_b), QuaternionDistance(a, b), 1e-12);
  }
}

TEST(ClusteringTest, GroupsByTranslationAndRotationAndSuppressesOrientationsAtOnePlace) {
  std::mt19937_64 rng(42);
  const Eigen::Isometry3d a = PoseFromRotationVector({0.1, 0.2, 0.3}, {0, 0, -500});
  const Eigen::Isometry3d b = PoseFromRotationVector({-0.5, 0.1, 1.0}, {150, 0, -500});
  const Eigen::Isometry3d a_turned =
      a * PoseFromRotationVector({0, 0, std::numbers::pi / 2}, Eigen::Vector3d::Zero());
  std::vector<PoseHypothesis> hypotheses;
  AddGroup(a, 20, 10.0, 3.0, 0.05, rng, &hypotheses);
  AddGroup(b, 10, 10.0, 3.0, 0.05, rng, &hypotheses);
  AddGroup(a_turned, 15, 10.0, 3.0, 0.05, rng, &hypotheses);
  PoseClusteringOptions options;
  options.translation_radius_mm = 10.0;
  options.duplicate_radius_mm = 10.0;
  options.rotation_threshold_rad = 0.4;
  const ClusteringResult result = ClusterPoses(hypotheses, options);
  ASSERT_EQ(result.clusters.size(), 3U);
  EXPECT_EQ(result.kept, 2U);
  const PoseCluster& best = result.clusters[0];
  EXPECT_DOUBLE_EQ(best.score, 200.0);
  EXPECT_EQ(best.members, 20U);
  EXPECT_THAT(best.scene_from_centered, test::PoseNear(a, 0.03, 2.0));
  // The vote-weighted average of the members (here equal votes) is the cluster pose.
  std::vector<Eigen::Isometry3d> members;
  for (int i = 0; i < 20; ++i)
    members.push_back(hypotheses[static_cast<std::size_t>(i)].scene_from_centered);
  EXPECT_THAT(best.scene_from_centered, test::PoseNear(AveragePoses(members), 1e-9, 1e-9));
  // Same place, other orientation: formed but suppressed by the better cluster, not dropped.
  EXPECT_DOUBLE_EQ(result.clusters[1].score, 150.0);
  EXPECT_EQ(result.clusters[1].suppressed_by, 0);
  EXPECT_THAT(result.clusters[1].scene_from_centered, test::PoseNear(a_turned, 0.03, 2.0));
  EXPECT_EQ(result.clusters[2].suppressed_by, -1);
  EXPECT_THAT(result.clusters[2].scene_from_centered, test::PoseNear(b, 0.03, 2.0));

  options.duplicate_radius_mm = 0.0;
  EXPECT_EQ(ClusterPoses(hypotheses, options).kept, 3U);
  options.max_clusters = 1;
  EXPECT_EQ(ClusterPoses(hypotheses, options).clusters.size(), 1U);
}

TEST(ClusteringTest, VotesWeighTheAverageAndSeedTheGreedyOrder) {
  const Eigen::Isometry3d p0 = PoseFromRotationVector(Eigen::Vector3d::Zero(), {0, 0, 0});
  const Eigen::Isometry3d p1 = PoseFromRotationVector(Eigen::Vector3d::Zero(), {4, 0, 0});
  const Eigen::Isometry3d p2 = PoseFromRotationVector(Eigen::Vector3d::Zero(), {8, 0, 0});
  std::vector<PoseHypothesis> hypotheses(3);
  hypotheses[0].scene_from_centered = p0;
  hypotheses[0].votes = 1.0;
  hypotheses[1].scene_from_centered = p1;
  hypotheses[1].votes = 3.0;  // seed
  hypotheses[2].scene_from_centered = p2;
  hypotheses[2].votes = 1.0;
  PoseClusteringOptions options;
  options.translation_radius_mm =
      5.0;  // the seed reaches both others; they do not reach each other
  const ClusteringResult result = ClusterPoses(hypotheses, options);
  ASSERT_EQ(result.clusters.size(), 1U);
  EXPECT_EQ(result.clusters[0].seed, 1U);
  EXPECT_DOUBLE_EQ(result.clusters[0].seed_votes, 3.0);
  EXPECT_NEAR(result.clusters[0].scene_from_centered.translation().x(),
              (0 * 1 + 4 * 3 + 8 * 1) / 5.0, 1e-12);
  EXPECT_TRUE(ClusterPoses({}, options).clusters.empty());
}

TEST(ClusteringTest, RejectsBadOptions) {
  PoseClusteringOptions options;
  options.translation_radius_mm = 0.0;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("translation_radius_mm")));
  options = {};
  options.rotation_threshold_rad = 4.0;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("rotation_threshold_rad")));
  options = {};
  options.max_clusters = 0;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("max_clusters")));
  options = {};
  options.duplicate_radius_mm = -1.0;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("duplicate_radius_mm")));
}

}  // namespace
}  // namespace lasercell::registration
