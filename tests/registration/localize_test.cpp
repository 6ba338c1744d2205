#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <limits>
#include <random>

#include "core/error.hpp"
#include "core/se3.hpp"
#include "registration/internal/rank_candidates.hpp"
#include "registration/localize_in_cloud.hpp"
#include "registration_test_util.hpp"

namespace lasercell::registration {
namespace {

using ::testing::HasSubstr;

const PpfModel& UwaPpfModel() {
  static const PpfModel model = PpfModel::Build(*test::UwaModel());
  return model;
}

double ModelRmsMm(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return test::PoseRmsMm(test::UwaModel()->positions, a, b);
}

// Real data: the parasaurolophus in rs1 at the committed reference pose (see the data file for
// how the reference was established). 1 mm RMS over the model's points; we measure ~0.05 mm.
TEST(LocalizeRealTest, FindsTheParasaurolophusInRs1) {
  LASERCELL_REQUIRE_UWA();
  const PpfModel& model = UwaPpfModel();
  const auto start = std::chrono::steady_clock::now();
  const LocalizationResult result = LocalizeInCloud(*test::UwaScene(), model);
  const double wall_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  ASSERT_TRUE(result.found) << result.Summary();
  const LocalizationCandidate& best = result.candidates.front();
  EXPECT_EQ(best.rank, 1);
  EXPECT_LT(ModelRmsMm(best.scene_from_model, test::Rs1ReferencePose()), 1.0) << result.Summary();
  EXPECT_TRUE(best.icp_run);
  EXPECT_TRUE(best.icp.converged) << best.icp.Summary();
  EXPECT_LT(best.icp.rmse_mm, 0.6);  // the scanner's noise
  EXPECT_GT(best.verification.support, 0.6);
  // The vote itself ranks the true pose first: its cluster is the best-scored one.
  EXPECT_EQ(best.cluster, 0u) << "score " << best.score;
  EXPECT_FALSE(result.ambiguous) << result.ambiguity_reason;
  EXPECT_EQ(result.scene_points, test::UwaScene()->size());
  // The timings are milliseconds of this call: their stages add up to at most the total, and
  // the total to at most the wall time measured around the call.
  const LocalizationTimings& t = result.timings;
  EXPECT_GE(t.total_ms, t.preprocess_ms + t.normals_ms + t.subsample_ms + t.kdtree_ms +
                            t.matching_ms + t.clustering_ms + t.verification_ms + t.icp_ms - 1e-6);
  EXPECT_LE(t.total_ms, wall_ms);
  EXPECT_GT(t.matching_ms, 0.0);
  EXPECT_THAT(result.Summary(), HasSubstr("found 1 instance"));
}

// Several clusters can converge to one pose under ICP; their refined supports then differ only by
// ICP's tolerance. The answer keeps the stronger cluster's evidence (score, coarse pose) and rank;
// the weaker one is its duplicate. A second orientation at the same place stays a duplicate of
// the better-supported one whatever its cluster score.
TEST(RankCandidatesTest, OneAnswerFoundTwiceKeepsTheStrongerClusterEvidence) {
  LASERCELL_REQUIRE_UWA();
  const PpfModel& model = UwaPpfModel();
  LocalizeOptions options;
  options.clustering.duplicate_radius_mm = 0.1 * model.diameter_mm();
  const Eigen::Isometry3d pose = test::Rs1ReferencePose();
  std::mt19937_64 rng(1);
  const auto candidate = [&](const Eigen::Isometry3d& at, double support, double score) {
    LocalizationCandidate c;
    c.scene_from_model = at;
    c.coarse_scene_from_model = at * test::RandomPerturbation(rng, 0.1, 5.0);
    c.verification.accepted = true;
    c.verification.support = support;
    c.score = score;
    c.icp_run = true;
    return c;
  };
  // Same pose within 0.01 mm: the weaker cluster has the (insignificantly) higher support.
  Eigen::Isometry3d nudged = pose;
  nudged.translation() += Eigen::Vector3d(0.01, 0, 0);
  LocalizationResult same;
  internal::RankCandidates({candidate(pose, 0.9938, 80.0), candidate(nudged, 0.9930, 200.0)}, model,
                           options, &same);
  ASSERT_EQ(same.candidates.size(), 1u);
  EXPECT_EQ(same.candidates[0].score, 200.0);
  EXPECT_EQ(same.candidates[0].rank, 1);
  ASSERT_EQ(same.rejected.size(), 1u);
  EXPECT_EQ(same.rejected[0].score, 80.0);
  EXPECT_THAT(same.rejected[0].rejection_reason, HasSubstr("duplicate of rank 1"));
  // A different orientation at the same place (30 deg about z): the better support wins.
  const Eigen::Isometry3d turned =
      pose * model.model_from_centered() *
      Eigen::Isometry3d(Eigen::AngleAxisd(0.52, Eigen::Vector3d::UnitZ())) *
      model.model_from_centered().inverse();
  LocalizationResult other;
  internal::RankCandidates({candidate(pose, 0.99, 80.0), candidate(turned, 0.5, 200.0)}, model,
                           options, &other);
  ASSERT_EQ(other.candidates.size(), 1u);
  EXPECT_EQ(other.candidates[0].score, 80.0);
  EXPECT_EQ(other.rejected[0].score, 200.0);
  EXPECT_FALSE(other.ambiguous);
}

// The reference is a fixed point of careful ICP: starts 2 deg / 4 mm away come back to it.
TEST(LocalizeRealTest, ReferencePoseIsAStableIcpOptimum) {
  LASERCELL_REQUIRE_UWA();
  const PpfModel& model = UwaPpfModel();
  const Eigen::Isometry3d reference = test::Rs1ReferencePose();
  VerificationOptions grid;
  grid.overlap_band_mm = 5.0;
  IcpOptions icp;
  icp.max_correspondence_distance_mm = 10.0;
  icp.translation_tolerance_mm = 1e-5;
  icp.rotation_tolerance_rad = 1e-7;
  icp.max_iterations = 100;
  icp.threads = 0;
  std::mt19937_64 rng(81);
  for (int start = 0; start < 3; ++start) {
    Eigen::Isometry3d pose = reference * model.model_from_centered() *
                             test::RandomPerturbation(rng, 0.035, 4.0) *
                             model.model_from_centered().inverse();
    for (int round = 0; round < 3; ++round) {
      std::vector<std::uint32_t> overlap;
      VerifyPose(test::UwaScene()->positions, model, pose, Viewpoint{}, grid, &overlap);
      std::vector<Eigen::Vector3d> source;
      for (std::size_t k = 0; k < overlap.size(); k += 3)
        source.push_back(test::UwaScene()->positions[overlap[k]]);
      const IcpResult result = AlignIcp(source, model.refinement_tree(), model.refinement_normals(),
                                        (pose * model.model_from_centered()).inverse(), icp);
      pose = result.target_from_source.inverse() * model.model_from_centered().inverse();
    }
    EXPECT_LT(ModelRmsMm(pose, reference), 0.05) << "start " << start;
  }
}

TEST(LocalizeRealTest, IdenticalForAnyThreadCount) {
  LASERCELL_REQUIRE_UWA();
  LocalizeOptions options;
  options.threads = 1;
  const LocalizationResult one = LocalizeInCloud(*test::UwaScene(), UwaPpfModel(), options);
  for (int threads : {2, 0}) {
    options.threads = threads;
    const LocalizationResult other = LocalizeInCloud(*test::UwaScene(), UwaPpfModel(), options);
    ASSERT_EQ(one.candidates.size(), other.candidates.size());
    ASSERT_EQ(one.rejected.size(), other.rejected.size());
    EXPECT_EQ(one.hypotheses, other.hypotheses);
    EXPECT_EQ(one.votes_cast, other.votes_cast);
    for (std::size_t i = 0; i < one.candidates.size(); ++i) {
      EXPECT_EQ(one.candidates[i].scene_from_model.matrix(),
                other.candidates[i].scene_from_model.matrix());
      EXPECT_EQ(one.candidates[i].score, other.candidates[i].score);
      EXPECT_EQ(one.candidates[i].verification.support, other.candidates[i].verification.support);
      EXPECT_EQ(one.candidates[i].icp.rmse_mm, other.candidates[i].icp.rmse_mm);
    }
  }
}

// The model at seeded random poses in rs1's real clutter (the real parasaurolophus cut out),
// rendered at rs1's density with 0.3 mm noise and a z-buffer, normals re-estimated. After ICP
// the error is a few tenths of a mm (1500 source points, sigma 0.3 mm); 1 mm leaves room for
// occluded placements. Every placement with at least 60 % of its visible surface unoccluded by
// the clutter must be found; on this seed one placement is 54 % hidden and may be missed.
// (The 200-placement success curve over noise is a benchmark, not a unit test.)
TEST(LocalizeSyntheticTest, FindsRandomPlacementsInRealClutter) {
  LASERCELL_REQUIRE_UWA();
  std::mt19937_64 rng(91);
  const Eigen::Vector3d centroid = test::UwaModel()->Centroid();
  int found = 0;
  for (int trial = 0; trial < 10; ++trial) {
    const Eigen::Isometry3d truth = test::RandomPlacementInRs1(centroid, rng);
    std::size_t visible = 0;
    const PointCloud scan = test::SyntheticRs1Scan({truth}, 0.3, rng, &visible);
    const double unoccluded =
        static_cast<double>(visible) /
        test::VisibleFromOrigin(test::UwaModelDenseSurface().Transformed(truth), 0.8, 2.0).size();
    const LocalizationResult result = LocalizeInCloud(scan, UwaPpfModel());
    const double error =
        result.found ? ModelRmsMm(result.candidates.front().scene_from_model, truth) : -1.0;
    const bool ok = result.found && error < 1.0;
    found += ok ? 1 : 0;
    if (unoccluded >= 0.6) {
      EXPECT_TRUE(ok) << "trial " << trial << " (" << unoccluded << " unoccluded): error " << error
                      << " mm; " << result.Summary();
    }
  }
  EXPECT_GE(found, 9);
}

TEST(LocalizeSyntheticTest, FindsTwoInstances) {
  LASERCELL_REQUIRE_UWA();
  std::mt19937_64 rng(92);
  const Eigen::Vector3d centroid = test::UwaModel()->Centroid();
  // Two random orientations, centroids 170 mm apart.
  Eigen::Isometry3d a = test::RandomPose(rng, 0.0), b = test::RandomPose(rng, 0.0);
  a.translation() = Eigen::Vector3d(-80, 40, -620) - a.linear() * centroid;
  b.translation() = Eigen::Vector3d(60, -60, -620) - b.linear() * centroid;
  const PointCloud scan = test::SyntheticRs1Scan({a, b}, 0.3, rng);
  LocalizeOptions options;
  options.max_instances = 2;
  const LocalizationResult result = LocalizeInCloud(scan, UwaPpfModel(), options);
  ASSERT_EQ(result.candidates.size(), 2U) << result.Summary();
  const Eigen::Isometry3d first = result.candidates[0].scene_from_model,
                          second = result.candidates[1].scene_from_model;
  const bool in_order = ModelRmsMm(first, a) < ModelRmsMm(first, b);
  EXPECT_LT(ModelRmsMm(in_order ? first : second, a), 1.0);
  EXPECT_LT(ModelRmsMm(in_order ? second : first, b), 1.0);
  EXPECT_EQ(result.candidates[1].rank, 2);
}

TEST(LocalizeBadInputTest, SceneWithoutThePartIsNotFound) {
  LASERCELL_REQUIRE_UWA();
  const LocalizationResult result =
      LocalizeInCloud(test::Rs1WithoutParasaurolophus(), UwaPpfModel());
  EXPECT_FALSE(result.found) << result.Summary();
  EXPECT_TRUE(result.candidates.empty());
  EXPECT_FALSE(result.rejected.empty());
  for (const auto& c : result.rejected) EXPECT_FALSE(c.rejection_reason.empty());
  EXPECT_THAT(result.message, HasSubstr("no candidate passed verification"));
}

TEST(LocalizeBadInputTest, NanPointsAreDroppedAndReported) {
  LASERCELL_REQUIRE_UWA();
  PointCloud scene = *test::UwaScene();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t i = 0; i < scene.size(); i += 200) scene.positions[i].x() = nan;
  for (std::size_t i = 100; i < scene.size(); i += 1000) scene.normals[i].z() = nan;
  const std::size_t expected = (scene.size() + 199) / 200 + (scene.size() - 100 + 999) / 1000;
  const LocalizationResult result = LocalizeInCloud(scene, UwaPpfModel());
  EXPECT_EQ(result.dropped_points, expected);
  ASSERT_TRUE(result.found) << result.Summary();
  EXPECT_LT(ModelRmsMm(result.candidates.front().scene_from_model, test::Rs1ReferencePose()), 1.0);
}

// A scene without normals gets them estimated, by default once per voxel-grid point (the only
// normals the voting reads), else at every point of the verification thinning, averaged and split
// per voxel: both find the part within 1 mm; the first never has more voxel points than the
// second, whose split can only add some.
TEST(LocalizeBadInputTest, SceneWithoutNormalsGetsThemEstimated) {
  LASERCELL_REQUIRE_UWA();
  std::mt19937_64 rng(93);
  const Eigen::Isometry3d truth = test::RandomPlacementInRs1(test::UwaModel()->Centroid(), rng);
  PointCloud scan = test::SyntheticRs1Scan({truth}, 0.3, rng);
  scan.normals.clear();
  LocalizeOptions options;
  ASSERT_TRUE(options.scene_normals_at_samples);
  const LocalizationResult at_samples = LocalizeInCloud(scan, UwaPpfModel(), options);
  options.scene_normals_at_samples = false;
  const LocalizationResult everywhere = LocalizeInCloud(scan, UwaPpfModel(), options);
  for (const LocalizationResult* result : {&at_samples, &everywhere}) {
    ASSERT_TRUE(result->found) << result->Summary();
    EXPECT_LT(ModelRmsMm(result->candidates.front().scene_from_model, truth), 1.0);
  }
  EXPECT_EQ(at_samples.used_points, everywhere.used_points);
  EXPECT_GT(at_samples.sampled_points, at_samples.used_points / 100);
  EXPECT_LE(at_samples.sampled_points, everywhere.sampled_points);
}

TEST(LocalizeBadInputTest, ModelLargerThanTheSceneIsNotFound) {
  LASERCELL_REQUIRE_UWA();
  // A 40 mm patch of rs1 (the model is 310 mm across).
  const PointCloud& rs1 = *test::UwaScene();
  std::vector<std::size_t> patch;
  for (std::size_t i = 0; i < rs1.size(); ++i) {
    if ((rs1.positions[i] - rs1.positions[0]).norm() < 40.0) patch.push_back(i);
  }
  const LocalizationResult result = LocalizeInCloud(rs1.Subset(patch), UwaPpfModel());
  EXPECT_FALSE(result.found);
  EXPECT_FALSE(result.message.empty());
}

TEST(LocalizeBadInputTest, EmptyAndMalformedScenes) {
  const PpfModel model = PpfModel::Build(test::BoxPoints({30, 20, 10}, 2.0));
  EXPECT_THAT([&] { LocalizeInCloud(PointCloud{}, model); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("scene cloud is empty")));
  PointCloud mismatched;
  mismatched.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mismatched.normals = {{0, 0, 1}};
  EXPECT_THAT([&] { LocalizeInCloud(mismatched, model); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("'normals' has 1 values for 3")));
  PointCloud all_nan;
  all_nan.positions.assign(10, Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN()));
  const LocalizationResult result = LocalizeInCloud(all_nan, model);
  EXPECT_FALSE(result.found);
  EXPECT_EQ(result.dropped_points, 10U);
  EXPECT_THAT(result.message, HasSubstr("fewer than 3 scene points"));
  // The region of interest can leave nothing, too: reported, not thrown.
  LocalizeOptions options;
  options.use_roi = true;
  options.roi.Extend({1000, 1000, 1000});
  options.roi.Extend({1001, 1001, 1001});
  EXPECT_FALSE(LocalizeInCloud(test::BoxPoints({30, 20, 10}, 2.0), model, options).found);
}

TEST(LocalizeBadInputTest, AbsurdOptionsNameTheField) {
  const PpfModel model = PpfModel::Build(test::BoxPoints({30, 20, 10}, 2.0));
  const PointCloud scene = test::BoxPoints({30, 20, 10}, 2.0);
  auto expect_error = [&](const LocalizeOptions& options, const char* field) {
    EXPECT_THAT([&] { LocalizeInCloud(scene, model, options); },
                ::testing::ThrowsMessage<OptionError>(HasSubstr(field)));
  };
  LocalizeOptions o;
  o.scene_sampling_step_mm = -2.0;
  expect_error(o, "scene_sampling_step_mm");
  o = {};
  o.verification.grid_cols = 0;
  expect_error(o, "grid_rows/grid_cols");
  o = {};
  o.max_instances = 0;
  expect_error(o, "max_instances");
  o = {};
  o.matching.reference_stride = 0;
  expect_error(o, "reference_stride");
  o = {};
  o.icp.max_iterations = 0;
  expect_error(o, "max_iterations");
  o = {};
  o.refined_support_distance_relative = 0.0;
  expect_error(o, "refined_support_distance_relative");
  o = {};
  o.use_roi = true;  // with an empty box
  expect_error(o, "roi");
  o = {};
  o.viewpoint = Viewpoint::AlongDirection(Eigen::Vector3d::Zero());
  expect_error(o, "viewpoint");
}

// A flat plate: every pair has the same normal angles, rotations about the normal are
// unobservable. The result must say so.
TEST(LocalizeAmbiguityTest, PlanarModelIsFlagged) {
  PointCloud plate;
  for (double x = -50; x <= 50; x += 1.0) {
    for (double y = -30; y <= 30; y += 1.0) {
      plate.positions.push_back({x, y, 0});
      plate.normals.push_back(Eigen::Vector3d::UnitZ());
    }
  }
  const PpfModel model = PpfModel::Build(plate);
  const Eigen::Isometry3d truth = PoseFromRotationVector({0.2, 0.1, 0.5}, {0, 0, -500});
  const LocalizationResult result = LocalizeInCloud(plate.Transformed(truth), model);
  EXPECT_TRUE(result.ambiguous);
  EXPECT_THAT(result.ambiguity_reason, HasSubstr("planar model"));
}

// A box seen from above: its 180 deg turn about the vertical axis looks identical. Both
// orientations are refined and end with the same support.
TEST(LocalizeAmbiguityTest, SymmetricViewIsFlagged) {
  const PointCloud box = test::BoxPoints({40, 25, 15}, 1.0);
  const PpfModel model = PpfModel::Build(box);
  const Eigen::Isometry3d truth = PoseFromRotationVector({0.3, -0.2, 0.4}, {0, 0, -500});
  std::mt19937_64 rng(94);
  const PointCloud view =
      test::SimulateView(box.Transformed(truth), Viewpoint{}, 1.0, 0.5, 0.1, rng);
  const LocalizationResult result = LocalizeInCloud(view, model);
  ASSERT_TRUE(result.found) << result.Summary();
  EXPECT_TRUE(result.ambiguous) << result.Summary();
  EXPECT_THAT(result.ambiguity_reason, HasSubstr("two orientations"));
}

TEST(LocalizeProgressTest, ReportsEveryStageInOrder) {
  const PointCloud box = test::BoxPoints({40, 25, 15}, 1.0);
  const PpfModel model = PpfModel::Build(box);
  std::vector<std::string> stages;
  LocalizeOptions options;
  options.progress = [&](std::string_view stage, double fraction) {
    EXPECT_EQ(fraction, 1.0);
    stages.emplace_back(stage);
  };
  options.scene_normal_mode = VoxelNormalMode::kNearestPoint;
  const LocalizationResult result = LocalizeInCloud(
      box.Transformed(PoseFromRotationVector({0.3, 0.2, 0.1}, {0, 0, -400})), model, options);
  EXPECT_TRUE(result.found) << result.Summary();
  EXPECT_EQ(stages, (std::vector<std::string>{"preprocess", "normals", "subsample", "matching",
                                              "clustering", "refinement"}));
}

TEST(LocalizeConvenienceTest, BuildsTheModelFromACloud) {
  LASERCELL_REQUIRE_UWA();
  const LocalizationResult result =
      LocalizeInCloud(*test::UwaScene(), *test::UwaModel(), PpfModelOptions{}, LocalizeOptions{});
  ASSERT_TRUE(result.found);
  EXPECT_LT(ModelRmsMm(result.candidates.front().scene_from_model, test::Rs1ReferencePose()), 1.0);
}

}  // namespace
}  // namespace lasercell::registration
