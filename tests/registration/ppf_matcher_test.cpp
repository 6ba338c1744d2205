#include "registration/ppf_matcher.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <vector>

#include "core/error.hpp"
#include "core/se3.hpp"
#include "registration/clustering.hpp"
#include "registration/filters.hpp"
#include "registration_test_util.hpp"

namespace lasercell::registration {
namespace {

using ::testing::HasSubstr;

// The sampled scene (voxel grid at the model's step) as MatchPpf expects it.
struct SampledScene {
  KdTree tree;
  std::vector<Eigen::Vector3d> normals;
};

SampledScene Sample(const PointCloud& scene, double step_mm) {
  VoxelGridOptions voxel;
  voxel.voxel_size_mm = step_mm;
  PointCloud sampled = VoxelGridDownsample(scene, voxel);
  return {KdTree(std::move(sampled.positions)), std::move(sampled.normals)};
}

class PpfMatcherTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (test::UwaModel() == nullptr || test::UwaScene() == nullptr)
      GTEST_FAIL() << "bundled UWA data missing from datasets/real/uwa";
    model_ = PpfModel::Build(*test::UwaModel());
    std::mt19937_64 rng(71);
    truth_ = test::RandomPlacementInRs1(test::UwaModel()->Centroid(), rng);
    scene_ = Sample(test::SyntheticRs1Scan({truth_}, 0.3, rng), model_.sampling_step_mm());
  }

  // The best cluster of the hypotheses is the part: within the clustering radius (0.1 x the
  // diameter) and two angle steps of the truth. (ICP refines it later; only the voting is tested.)
  void ExpectBestClusterIsThePart(const std::vector<PoseHypothesis>& hypotheses) const {
    PoseClusteringOptions clustering;
    clustering.translation_radius_mm = clustering.duplicate_radius_mm = 0.1 * model_.diameter_mm();
    const ClusteringResult clusters = ClusterPoses(hypotheses, clustering);
    ASSERT_FALSE(clusters.clusters.empty());
    EXPECT_THAT(clusters.clusters[0].scene_from_centered,
                test::PoseNear(truth_ * model_.model_from_centered(), 2 * model_.angle_step_rad(),
                               0.1 * model_.diameter_mm()));
  }

  PpfModel model_;
  Eigen::Isometry3d truth_;
  SampledScene scene_;
};

// A scene with more than max_reference_points sampled points gets a larger stride: the count is
// capped, the references stay evenly spread (every ceil(n / cap)-th point), and the cap (not the
// stride) decides only when it is the tighter limit.
TEST_F(PpfMatcherTest, ReferencePointsAreCapped) {
  const std::size_t n = scene_.tree.size();
  ASSERT_GT(n, 100U);
  PpfMatchOptions options;
  options.threads = 1;
  options.max_reference_points = n / 10;
  const std::size_t stride = (n + options.max_reference_points - 1) / options.max_reference_points;
  const PpfMatchResult capped = MatchPpf(scene_.tree, scene_.normals, model_, options);
  EXPECT_EQ(capped.reference_points, (n + stride - 1) / stride);
  EXPECT_LE(capped.reference_points, options.max_reference_points);
  options.max_reference_points = 0;  // no cap: Drost's 1/5
  EXPECT_EQ(MatchPpf(scene_.tree, scene_.normals, model_, options).reference_points, (n + 4) / 5);
  options.max_reference_points = n;  // looser than the stride: no effect
  EXPECT_EQ(MatchPpf(scene_.tree, scene_.normals, model_, options).reference_points, (n + 4) / 5);
}

// A key holding more than max_entries_per_key model pairs votes with that many of them at most,
// so every looked-up pair casts at most `cap` votes; uncapped, the same scene casts more (the
// cap was active); capped, the best cluster is still the part.
TEST_F(PpfMatcherTest, FloodedKeysVoteWithAtMostTheCapsEntries) {
  PpfMatchOptions options;
  options.threads = 1;
  options.max_entries_per_key = 0;
  const PpfMatchResult full = MatchPpf(scene_.tree, scene_.normals, model_, options);
  constexpr std::size_t kCap = 4;
  ASSERT_GT(full.votes_cast, kCap * full.scene_pairs) << "no key is flooded: the test is void";
  options.max_entries_per_key = kCap;
  const PpfMatchResult capped = MatchPpf(scene_.tree, scene_.normals, model_, options);
  EXPECT_EQ(capped.scene_pairs, full.scene_pairs);
  EXPECT_LE(capped.votes_cast, kCap * capped.scene_pairs);
  options.max_entries_per_key = 16;  // a cap measured on rs1 (bench speed) still finds the part
  const PpfMatchResult sixteen = MatchPpf(scene_.tree, scene_.normals, model_, options);
  EXPECT_LT(sixteen.votes_cast, full.votes_cast);
  ExpectBestClusterIsThePart(sixteen.hypotheses);
}

// unique_votes casts each (key, scene alpha bin) of a reference once: the same pairs are looked
// up, fewer votes are cast, and the best cluster is still the part.
TEST_F(PpfMatcherTest, UniqueVotesSkipRepeatedKeysAndStillFindThePart) {
  PpfMatchOptions options;
  options.threads = 1;
  const PpfMatchResult plain = MatchPpf(scene_.tree, scene_.normals, model_, options);
  options.unique_votes = true;
  const PpfMatchResult unique = MatchPpf(scene_.tree, scene_.normals, model_, options);
  EXPECT_EQ(unique.scene_pairs, plain.scene_pairs);
  EXPECT_LT(unique.votes_cast, plain.votes_cast);
  EXPECT_GT(unique.votes_cast, plain.votes_cast / 4);  // repeats, not most of the evidence
  ExpectBestClusterIsThePart(unique.hypotheses);
  // Identical for any thread count, like the plain voting.
  options.threads = 2;
  const PpfMatchResult two = MatchPpf(scene_.tree, scene_.normals, model_, options);
  ASSERT_EQ(two.hypotheses.size(), unique.hypotheses.size());
  EXPECT_EQ(two.votes_cast, unique.votes_cast);
  for (std::size_t i = 0; i < two.hypotheses.size(); ++i)
    ASSERT_EQ(two.hypotheses[i].votes, unique.hypotheses[i].votes);
}

// With more than 64 alpha bins (one bit each does not fit) unique_votes votes every pair, as
// its documentation says: the same votes as the plain voting, and no bit shifted past 63 (the
// sanitizer build aborts on that shift).
TEST_F(PpfMatcherTest, UniqueVotesWithMoreThan64AlphaBinsVoteEveryPair) {
  PpfModelOptions fine;
  fine.angle_step_rad = std::numbers::pi / 40.0;  // 80 alpha bins
  fine.sampling_step_relative = 0.08;             // a small model keeps the test quick
  const PpfModel model = PpfModel::Build(*test::UwaModel(), fine);
  ASSERT_GT(model.alpha_bins(), 64);
  std::mt19937_64 rng(72);
  const SampledScene scene =
      Sample(test::SyntheticRs1Scan({truth_}, 0.3, rng), model.sampling_step_mm());
  PpfMatchOptions options;
  options.threads = 1;
  const PpfMatchResult plain = MatchPpf(scene.tree, scene.normals, model, options);
  options.unique_votes = true;
  const PpfMatchResult unique = MatchPpf(scene.tree, scene.normals, model, options);
  EXPECT_GT(plain.votes_cast, 0U);
  EXPECT_EQ(unique.votes_cast, plain.votes_cast);
}

TEST_F(PpfMatcherTest, VotesAndClustersFindASyntheticPoseInRealClutter) {
  const PpfMatchResult match = MatchPpf(scene_.tree, scene_.normals, model_);
  EXPECT_EQ(match.reference_points, (scene_.tree.size() + 4) / 5);
  EXPECT_GT(match.hypotheses.size(), match.reference_points / 2);
  EXPECT_GT(match.votes_cast, match.scene_pairs);
  PoseClusteringOptions clustering;
  clustering.translation_radius_mm = clustering.duplicate_radius_mm = 0.1 * model_.diameter_mm();
  const ClusteringResult clusters = ClusterPoses(match.hypotheses, clustering);
  ASSERT_FALSE(clusters.clusters.empty());
  // The best cluster is the part: within the clustering radius and two angle steps. (The
  // coarse pose is refined by ICP later; here only the voting is tested.)
  const Eigen::Isometry3d scene_from_centered = truth_ * model_.model_from_centered();
  EXPECT_THAT(
      clusters.clusters[0].scene_from_centered,
      test::PoseNear(scene_from_centered, 2 * model_.angle_step_rad(), 0.1 * model_.diameter_mm()));
  EXPECT_GT(clusters.clusters[0].score, 2.0 * clusters.clusters[1].score);
}

TEST_F(PpfMatcherTest, SpreadingStillFindsThePose) {
  PpfMatchOptions options;
  options.spread_features = true;
  options.spread_alpha = true;
  options.reference_stride = 10;
  const PpfMatchResult spread = MatchPpf(scene_.tree, scene_.normals, model_, options);
  options.spread_features = options.spread_alpha = false;
  const PpfMatchResult plain = MatchPpf(scene_.tree, scene_.normals, model_, options);
  EXPECT_GT(spread.votes_cast, 8 * plain.votes_cast);  // 2^4 feature cells x 2 alpha bins
  PoseClusteringOptions clustering;
  clustering.translation_radius_mm = clustering.duplicate_radius_mm = 0.1 * model_.diameter_mm();
  const ClusteringResult clusters = ClusterPoses(spread.hypotheses, clustering);
  ASSERT_FALSE(clusters.clusters.empty());
  EXPECT_THAT(clusters.clusters[0].scene_from_centered,
              test::PoseNear(truth_ * model_.model_from_centered(), 2 * model_.angle_step_rad(),
                             0.1 * model_.diameter_mm()));
}

// The alpha of a peak placed at the vertex of the parabola through its cell and the two alpha
// neighbours, instead of at the bin centre: over the hypotheses that found the part (within two
// angle steps and 0.1 x diameter of the truth) the median rotation error is smaller, and every
// alpha stays inside its own bin.
TEST_F(PpfMatcherTest, InterpolatedAlphaBringsTheHypothesesCloserToTheTruth) {
  const Eigen::Isometry3d truth = truth_ * model_.model_from_centered();
  const auto median_rotation_error = [&](const PpfMatchResult& match) {
    std::vector<double> errors;
    for (const PoseHypothesis& h : match.hypotheses) {
      const double rotation = RotationDistance(h.scene_from_centered, truth);
      if (rotation < 2 * model_.angle_step_rad() &&
          TranslationDistance(h.scene_from_centered, truth) < 0.1 * model_.diameter_mm())
        errors.push_back(rotation);
    }
    EXPECT_GT(errors.size(), 20U);
    std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
    return errors[errors.size() / 2];
  };
  PpfMatchOptions options;
  options.interpolate_alpha = false;
  const PpfMatchResult centre = MatchPpf(scene_.tree, scene_.normals, model_, options);
  options.interpolate_alpha = true;
  const PpfMatchResult vertex = MatchPpf(scene_.tree, scene_.normals, model_, options);
  ASSERT_EQ(centre.hypotheses.size(), vertex.hypotheses.size());
  const double step = model_.alpha_step_rad();
  for (const PoseHypothesis& h : vertex.hypotheses) {
    ASSERT_GE(h.alpha_rad, h.alpha_bin * step - 1e-12);
    ASSERT_LE(h.alpha_rad, (h.alpha_bin + 1) * step + 1e-12);
  }
  const double at_centre = median_rotation_error(centre), at_vertex = median_rotation_error(vertex);
  std::printf(
      "median rotation error of the part's hypotheses: %.2f deg at the bin centre, %.2f "
      "deg interpolated\n",
      at_centre * 180 / M_PI, at_vertex * 180 / M_PI);
  EXPECT_LT(at_vertex, at_centre);
}

TEST_F(PpfMatcherTest, IdenticalForAnyThreadCount) {
  PpfMatchOptions options;
  options.threads = 1;
  const PpfMatchResult one = MatchPpf(scene_.tree, scene_.normals, model_, options);
  for (int threads : {2, 0}) {
    options.threads = threads;
    const PpfMatchResult other = MatchPpf(scene_.tree, scene_.normals, model_, options);
    ASSERT_EQ(one.hypotheses.size(), other.hypotheses.size());
    EXPECT_EQ(one.votes_cast, other.votes_cast);
    for (std::size_t i = 0; i < one.hypotheses.size(); ++i) {
      EXPECT_EQ(one.hypotheses[i].scene_from_centered.matrix(),
                other.hypotheses[i].scene_from_centered.matrix());
      EXPECT_EQ(one.hypotheses[i].votes, other.hypotheses[i].votes);
    }
  }
}

TEST_F(PpfMatcherTest, PeaksPerReferenceAreBestFirst) {
  PpfMatchOptions options;
  options.peaks_per_reference = 4;
  options.peak_min_relative = 0.0;
  const PpfMatchResult match = MatchPpf(scene_.tree, scene_.normals, model_, options);
  std::size_t with_several = 0;
  for (std::size_t i = 1; i < match.hypotheses.size(); ++i) {
    const auto& a = match.hypotheses[i - 1];
    const auto& b = match.hypotheses[i];
    if (a.scene_reference != b.scene_reference) continue;
    ++with_several;
    EXPECT_GE(a.votes, b.votes);
  }
  EXPECT_GT(with_several, match.reference_points);
}

TEST(PpfMatcherOptionsTest, RejectsBadOptionsAndInput) {
  PpfMatchOptions options;
  options.reference_stride = 0;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("reference_stride")));
  options = {};
  options.peaks_per_reference = 0;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("peaks_per_reference")));
  options = {};
  options.peak_min_relative = -0.5;
  EXPECT_THAT([&] { options.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("peak_min_relative")));
  const PpfModel model = PpfModel::Build(test::BoxPoints({30, 20, 10}, 2.0));
  const KdTree tree(std::vector<Eigen::Vector3d>{{0, 0, 0}, {1, 0, 0}});
  const std::vector<Eigen::Vector3d> one_normal = {{0, 0, 1}};
  EXPECT_THAT([&] { MatchPpf(tree, one_normal, model); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("1 scene normals for 2")));
  EXPECT_TRUE(MatchPpf(KdTree(), {}, model).hypotheses.empty());
}

}  // namespace
}  // namespace lasercell::registration
