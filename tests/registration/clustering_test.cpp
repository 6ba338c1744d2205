#include "registration/clustering.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <numbers>
#include <random>

#include "core/error.hpp"
#include "core/random.hpp"
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
    const double angle = angle_rad * u(rng);
    const double shift = trans_mm * u(rng);
    h.scene_from_centered = centre * test::RandomPerturbation(rng, angle, shift);
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
  options = {};
  options.refinement_inlier_mm = 0.0;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("refinement_inlier_mm")));
  options = {};
  options.refinement_rounds = 0;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("refinement_rounds")));
  options = {};
  options.refinement_tangent_weight = 0.0;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("refinement_tangent_weight")));
  options = {};
  options.refinement_min_members = 2;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("refinement_min_members")));
}

// Hypotheses as the matcher makes them: scene reference s_i paired with the model sample m_i of
// the same surface patch (on two voxel grids: off by up to half a step per tangent axis, uniform,
// and by 1 mm along the normal), each with its own rotation error (the reference normals' and
// alpha's), translation s_i - R_i m_i. The part is a 300 x 200 mm saddle z = (x^2 - y^2) / 400.
struct Correspondences {
  std::vector<Eigen::Vector3d> model, scene, scene_normals;
  std::vector<PoseHypothesis> hypotheses;
};

Correspondences MakeCorrespondences(const Eigen::Isometry3d& truth, int count, double outliers,
                                    std::mt19937_64& rng) {
  Correspondences c;
  std::uniform_real_distribution<double> box(-1.0, 1.0), unit(0.0, 1.0);
  std::normal_distribution<double> turn(0.0, 0.14), along(0.0, 1.0);  // ~8 deg per axis
  const double half_step_mm = 10.0;
  for (int i = 0; i < count; ++i) {
    const double x = 150.0 * box(rng), y = 100.0 * box(rng);
    const Eigen::Vector3d m(x, y, (x * x - y * y) / 400.0);
    const Eigen::Vector3d n = Eigen::Vector3d(-x / 200.0, y / 200.0, 1.0).normalized();
    const Eigen::Vector3d u = n.unitOrthogonal(), v = n.cross(u);
    const Eigen::Vector3d jitter{box(rng), box(rng), along(rng)};
    Eigen::Vector3d s =
        truth * (m + half_step_mm * (jitter.x() * u + jitter.y() * v) + jitter.z() * n);
    if (unit(rng) < outliers) s = truth * Eigen::Vector3d{150 * box(rng), 100 * box(rng), 0};
    const Eigen::Matrix3d r =
        truth.linear() * QuaternionFromRotationVector(Draws<3>(turn, rng)).toRotationMatrix();
    PoseHypothesis h;
    h.scene_reference = h.model_reference = static_cast<std::uint32_t>(i);
    h.votes = 10.0 + 10.0 * unit(rng);
    h.scene_from_centered.linear() = r;
    h.scene_from_centered.translation() = s - r * m;
    c.model.push_back(m);
    c.scene.push_back(s);
    c.scene_normals.push_back(truth.linear() * n);
    c.hypotheses.push_back(h);
  }
  return c;
}

PoseClusteringOptions FitOptions(double tangent_weight) {
  PoseClusteringOptions options;
  options.translation_radius_mm = 200.0;
  options.rotation_threshold_rad = 1.0;
  options.refinement_inlier_mm = 15.0;
  options.refinement_tangent_weight = tangent_weight;
  return options;
}

// The average carries each hypothesis's rotation error times its lever arm |m_i| into the
// translation; the fit of the correspondences does not, and trusting them along the normal more
// than across it removes most of the voxel offsets. Over 20 clusters of 150 members (20 % of
// them wrong correspondences): point-to-point fit well below the average, normal-weighted fit
// below that.
TEST(ClusteringTest, CorrespondenceFitBeatsTheAveragePose) {
  std::mt19937_64 rng(5);
  double average_mm = 0, horn_mm = 0, fit_mm = 0, average_deg = 0, horn_deg = 0, fit_deg = 0;
  const auto deg = [](const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
    return RotationDistance(a, b) * 180 / std::numbers::pi;
  };
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Isometry3d truth = test::RandomPose(rng, 500.0);
    const Correspondences c = MakeCorrespondences(truth, 150, 0.2, rng);
    const ClusteringResult r = ClusterPoses(c.hypotheses, FitOptions(1.0));
    ASSERT_FALSE(r.clusters.empty());
    ASSERT_GT(r.clusters.front().members, 100u);
    average_mm += TranslationDistance(r.clusters.front().scene_from_centered, truth);
    average_deg += deg(r.clusters.front().scene_from_centered, truth);
    PoseCluster horn = r.clusters.front(), fit = r.clusters.front();
    ASSERT_TRUE(RefineClusterPose(c.hypotheses, c.scene, {}, c.model, FitOptions(1.0), &horn));
    ASSERT_TRUE(
        RefineClusterPose(c.hypotheses, c.scene, c.scene_normals, c.model, FitOptions(0.1), &fit));
    EXPECT_GT(fit.fitted_members, 80u);
    horn_mm += TranslationDistance(horn.scene_from_centered, truth);
    horn_deg += deg(horn.scene_from_centered, truth);
    fit_mm += TranslationDistance(fit.scene_from_centered, truth);
    fit_deg += deg(fit.scene_from_centered, truth);
  }
  std::printf(
      "[ measured ] mean over 20 clusters: average %.2f mm %.2f deg, point fit %.2f mm %.2f deg, "
      "normal-weighted fit %.2f mm %.2f deg\n",
      average_mm / 20, average_deg / 20, horn_mm / 20, horn_deg / 20, fit_mm / 20, fit_deg / 20);
  EXPECT_LT(horn_mm, 0.5 * average_mm);
  EXPECT_LT(fit_mm, horn_mm);
  EXPECT_LT(fit_deg, average_deg);
}

TEST(ClusteringTest, CorrespondenceFitKeepsThePoseWhenItCannotImproveIt) {
  std::mt19937_64 rng(6);
  const Eigen::Isometry3d truth = test::RandomPose(rng, 500.0);
  Correspondences c = MakeCorrespondences(truth, 40, 0.0, rng);
  PoseClusteringOptions options;
  options.translation_radius_mm = 200.0;
  options.rotation_threshold_rad = 1.0;
  // Collinear model points: the rotation about their line is free.
  Correspondences line = c;
  for (std::size_t i = 0; i < line.model.size(); ++i) {
    line.model[i] = Eigen::Vector3d(line.model[i].x(), 0, 0);
    line.scene[i] = truth * line.model[i];
    Eigen::Isometry3d& pose = line.hypotheses[i].scene_from_centered;
    pose.translation() = line.scene[i] - pose.linear() * line.model[i];
  }
  ClusteringResult r = ClusterPoses(line.hypotheses, options);
  const Eigen::Isometry3d before = r.clusters.front().scene_from_centered;
  EXPECT_FALSE(RefineClusterPose(line.hypotheses, line.scene, line.scene_normals, line.model,
                                 FitOptions(0.1), &r.clusters.front()));
  EXPECT_TRUE(r.clusters.front().scene_from_centered.isApprox(before));
  // Too few members within the inlier distance.
  r = ClusterPoses(c.hypotheses, options);
  PoseClusteringOptions tight = FitOptions(0.1);
  tight.refinement_inlier_mm = 0.01;
  EXPECT_FALSE(RefineClusterPose(c.hypotheses, c.scene, c.scene_normals, c.model, tight,
                                 &r.clusters.front()));
  EXPECT_EQ(r.clusters.front().fitted_members, 0u);
  tight.refinement_inlier_mm = 0.0;
  EXPECT_THROW(RefineClusterPose(c.hypotheses, c.scene, c.scene_normals, c.model, tight,
                                 &r.clusters.front()),
               OptionError);
  EXPECT_THROW(
      RefineClusterPose(c.hypotheses, {}, {}, c.model, FitOptions(1.0), &r.clusters.front()),
      InputError);
  // Without normals only the point-to-point fit can run.
  EXPECT_THROW(
      RefineClusterPose(c.hypotheses, c.scene, {}, c.model, FitOptions(0.1), &r.clusters.front()),
      InputError);
}

}  // namespace
}  // namespace lasercell::registration
