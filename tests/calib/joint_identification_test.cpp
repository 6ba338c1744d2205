// Joint-offset identification: the cost functor's derivatives, the observability
// analysis naming the unidentifiable parameters, recovery of the true offsets from 50 poses,
// held-out positioning error, Monte-Carlo coverage of the reported 1 sigma, bad input.

#include "calib/joint_identification.hpp"

#include <ceres/gradient_checker.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "calib/camera_model.hpp"
#include "calib/cost_functions/kinematic_sphere_cost.hpp"
#include "calib/robot_observability.hpp"
#include "calib/robot_positioning.hpp"
#include "calib/sweep_bias.hpp"
#include "core/error.hpp"
#include "datasets/robots.hpp"
#include "tests/calib/joint_test_util.hpp"
#include "tests/sanitizer_scale.hpp"
#include "triangulation/profile_io.hpp"

namespace lasercell::calib {
namespace {

using ::testing::HasSubstr;
using testing::kDeg;

// Simulation profile: ideal (SimConfig{}: the true robot has joint offsets only, exact DH
// lengths); the sweep points are synthetic (tests/calib/joint_test_util.hpp).
datasets::SimConfig JointConfig(std::uint64_t seed = 21) {
  datasets::SimConfig config;
  config.seed = seed;
  return config;
}

// Sanitizer time: the accuracy tests sweep each pose with 4 profiles instead of 10 and position
// 5 held-out poses instead of 30 (the same solve and observability analysis run); their
// accuracy bounds hold at full size and are asserted in the normal build.
constexpr int kAccuracyProfiles = lasercell::test::kSanitizerBuild ? 4 : 10;
constexpr int kHeldOutPoses = lasercell::test::kSanitizerBuild ? 5 : 30;

/// The 50-pose set of the default simulator, planned once for the whole test binary.
const testing::PlannedPoses& FiftyPoses() {
  static const testing::PlannedPoses poses = [] {
    datasets::SimConfig config = JointConfig();
    return testing::PlanPoses(config, config.joint_poses, 4242);
  }();
  return poses;
}

TEST(KinematicSphereCost, TemplatedChainMatchesDhChain) {
  DhChain chain = NominalUr5();
  chain.mutable_joints()[2].joint_offset_rad = 0.01;
  chain.set_base_from_chain(Eigen::Isometry3d(Eigen::Translation3d(1, 2, 3) *
                                              Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ())));
  const KinematicChainReference ref = KinematicChainReference::From(chain);
  const std::array<double, 24> zero{};
  const double q[6] = {0.1, -1.2, 1.3, -0.4, 1.5, 0.6};
  Eigen::Matrix3d r;
  Eigen::Vector3d t;
  ref.BaseFromFlange(q, zero.data(), &r, &t);
  const Eigen::Isometry3d expected = chain.BaseFromFlange(std::vector<double>(q, q + 6));
  EXPECT_LT((r - expected.linear()).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_LT((t - expected.translation()).cwiseAbs().maxCoeff(), 1e-11);
}

TEST(KinematicSphereCost, AutodiffDerivativesMatchNumericDifferences) {
  const DhChain chain = NominalUr5();
  const KinematicChainReference ref = KinematicChainReference::From(chain);
  const Eigen::Isometry3d x0(Eigen::Translation3d(12, -95, 160) *
                             Eigen::AngleAxisd(0.04, Eigen::Vector3d(1, 2, 3).normalized()));
  std::vector<Eigen::Vector3d> points = {{10, 5, 690}, {-20, 3, 700}, {0, -4, 710}};
  std::unique_ptr<ceres::CostFunction> cost(
      KinematicSphereCost::Create(&ref, &x0, {0.1, -1.2, 1.3, -0.4, 1.5, 0.6}, points, 0.05));
  std::array<double, 24> robot{};
  for (int k = 0; k < 24; ++k) robot[k] = 1e-3 * (k % 5 - 2);
  std::array<double, 6> he = {1e-3, -2e-3, 3e-3, 0.1, -0.2, 0.3};
  std::array<double, 3> centre = {300, -100, -400};
  double radius = 25;
  std::vector<const double*> params = {robot.data(), he.data(), centre.data(), &radius};
  ceres::NumericDiffOptions nd;
  const std::vector<const ceres::Manifold*>* no_manifolds = nullptr;
  ceres::GradientChecker checker(cost.get(), no_manifolds, nd);
  ceres::GradientChecker::ProbeResults results;
  EXPECT_TRUE(checker.Probe(params.data(), 1e-7, &results)) << results.error_log;
}

TEST(RobotObservability, NamesJointOneAgainstFreeSphereCentres) {
  // Sphere-centre observations of 3 spheres from poses; derivative columns: offset_1 and the
  // centres. A base rotation about z moves every centre: the combination is unidentifiable.
  const testing::PlannedPoses& poses = FiftyPoses();
  const std::vector<SphereSweep> sweeps = testing::SyntheticSweeps(poses, 6, 0.05, 9);
  JointIdentificationOptions options;
  options.point_sigma_mm = 0.05;
  options.max_points_per_sweep = 60;
  const JointIdentificationResult r = IdentifyRobot(
      poses.truth.nominal_vision_robot, poses.truth.vision_flange_from_sensor, sweeps, options);
  ASSERT_EQ(r.observability.directions.size(), 1u) << r.observability.Summary();
  EXPECT_EQ(r.observability.directions[0].fixed_parameter, "joint_offset_1");
  EXPECT_THAT(r.observability.directions[0].parameters, ::testing::Contains("centre_0_x"));
  EXPECT_FALSE(r.parameter_estimated[0]);
  EXPECT_EQ(r.parameter_corrections[0], 0.0);
  EXPECT_LT(r.observability.condition_number, 1e4);
}

TEST(RobotObservability, WithHandEyeJointSixIsAbsorbedInTheMount) {
  const testing::PlannedPoses& poses = FiftyPoses();
  const std::vector<SphereSweep> sweeps = testing::SyntheticSweeps(poses, 6, 0.05, 9);
  JointIdentificationOptions options;
  options.point_sigma_mm = 0.05;
  options.max_points_per_sweep = 60;
  options.estimate_hand_eye = true;
  const JointIdentificationResult r = IdentifyRobot(
      poses.truth.nominal_vision_robot, poses.truth.vision_flange_from_sensor, sweeps, options);
  const std::vector<std::string> fixed = r.observability.Fixed();
  EXPECT_THAT(fixed, ::testing::UnorderedElementsAre("joint_offset_1", "joint_offset_6"));
  EXPECT_TRUE(r.flange_from_sensor_covariance.has_value());
}

TEST(RobotObservability, ZeroAndDuplicateColumnsAreNamed) {
  Eigen::MatrixXd j = Eigen::MatrixXd::Random(20, 4);
  j.col(3) = 2 * j.col(1);
  const ObservabilityReport r =
      AnalyzeObservability(j, {"a", "b", "c", "d"}, {true, false, true, true});
  ASSERT_EQ(r.directions.size(), 1u);
  EXPECT_EQ(r.directions[0].fixed_parameter, "d");
  EXPECT_THAT(r.directions[0].parameters, ::testing::UnorderedElementsAre("b", "d"));
  EXPECT_EQ(r.singular_values.size(), 3);
  Eigen::MatrixXd k = Eigen::MatrixXd::Random(20, 3);
  k.col(2).setZero();
  const ObservabilityReport s = AnalyzeObservability(k, {"a", "b", "c"}, {false, false, false});
  EXPECT_TRUE(s.degenerate);
  EXPECT_THAT(s.directions.back().parameters, ::testing::ElementsAre("c"));
}

// 50 poses, sigma 0.05 mm, sphere centres known to 0.02 mm (e.g. from the half-sphere
// calibration): every offset within 0.005 deg of the truth; a held-out set of 30 poses is
// positioned within 0.1 mm, where the nominal model misses by >= 2 mm.
TEST(JointIdentification, RecoversOffsetsAndPositionsHeldOutPoses) {
  const testing::PlannedPoses& poses = FiftyPoses();
  const std::vector<SphereSweep> sweeps =
      testing::SyntheticSweeps(poses, kAccuracyProfiles, 0.05, 31);
  JointIdentificationOptions options;
  options.point_sigma_mm = 0.05;
  options.known_centres_in_base = poses.centres_in_base;
  options.known_centre_sigma_mm = 0.02;
  const JointIdentificationResult r = IdentifyRobot(
      poses.truth.nominal_vision_robot, poses.truth.vision_flange_from_sensor, sweeps, options);
  ASSERT_TRUE(r.converged) << r.Summary();
  std::printf("%s\n  %s\n", r.Summary().c_str(), r.observability.Summary().c_str());
  EXPECT_TRUE(r.observability.directions.empty()) << r.observability.Summary();
  for (int j = 0; j < 6; ++j) {
    const double err_deg =
        (r.robot.joints()[j].joint_offset_rad - poses.truth.joint_offsets_rad[j]) / kDeg;
    std::printf("  joint %d: error %.5f deg (1 sigma %.5f)\n", j + 1, err_deg,
                r.parameter_sigmas[j] / kDeg);
    EXPECT_LT(std::abs(err_deg), 0.005) << "joint " << j + 1;
  }
  // Held-out poses: another plan of 30 poses.
  datasets::PoseSweepOptions held = poses.config.joint_poses;
  held.poses = kHeldOutPoses;
  const std::vector<datasets::PoseSweep> other =
      datasets::PlanPoseSweeps(poses.config, poses.truth, held, 999, "held-out");
  double worst_calibrated = 0, worst_nominal = 0;
  for (const datasets::PoseSweep& p : other) {
    const std::vector<double>& q = p.trajectory.joints_rad[1];
    const Eigen::Vector3d truth = testing::MeasuredPointInBase(
        poses.truth.true_vision_robot, poses.truth.vision_flange_from_sensor, q);
    worst_calibrated =
        std::max(worst_calibrated,
                 (testing::MeasuredPointInBase(r.robot, r.flange_from_sensor, q) - truth).norm());
    worst_nominal = std::max(
        worst_nominal, (testing::MeasuredPointInBase(poses.truth.nominal_vision_robot,
                                                     poses.truth.vision_flange_from_sensor, q) -
                        truth)
                           .norm());
  }
  std::printf("  held-out positioning: worst %.4f mm calibrated, %.3f mm nominal\n",
              worst_calibrated, worst_nominal);
  EXPECT_LT(worst_calibrated, 0.1);
  // The worst of 5 held-out poses (sanitizer) need not reach the 30 poses' 2 mm.
  EXPECT_GT(worst_nominal, lasercell::test::kSanitizerBuild ? 1.0 : 2.0);
}

// Monte Carlo: 100 noise draws of a small problem (15 poses, 6 profiles, 12 points each, known
// centres): each of the 6 offsets' truth lies inside the reported 1 sigma 60-76 % of the time,
// and the predicted positioning covariance (calib/robot_positioning.hpp) of the working point at
// 34 poses no solve saw fits the positioning errors: mean squared Mahalanobis distance 3 (chi-
// square, 3 dof) within its Monte-Carlo spread.
TEST(JointIdentification, ReportedSigmaCoversTheTruth) {
  const testing::PlannedPoses& all = FiftyPoses();
  testing::PlannedPoses poses = all;
  poses.plans.resize(16);
  int inside = 0, total = 0;
  double mahalanobis2 = 0;
  int positioned = 0;
  for (int draw = 0; draw < lasercell::test::Draws(100); ++draw) {
    const std::vector<SphereSweep> sweeps =
        testing::SyntheticSweeps(poses, 4, 0.1, 1000 + static_cast<std::uint64_t>(draw), 5, 0);
    JointIdentificationOptions options;
    options.point_sigma_mm = 0.1;
    options.known_centres_in_base = poses.centres_in_base;
    options.known_centre_sigma_mm = 1e-4;  // centres known (truth): only point noise
    options.seed_gate_mm = 3;
    options.max_iterations = 30;
    const JointIdentificationResult r = IdentifyRobot(
        poses.truth.nominal_vision_robot, poses.truth.vision_flange_from_sensor, sweeps, options);
    for (int j = 0; j < 6; ++j) {
      const double err = r.robot.joints()[j].joint_offset_rad - poses.truth.joint_offsets_rad[j];
      inside += std::abs(err) <= r.parameter_sigmas[j];
      ++total;
    }
    // One held-out pose per draw (the plans the solve did not get), in turn.
    const std::vector<double>& q =
        all.plans[16 + static_cast<std::size_t>(draw) % (all.plans.size() - 16)]
            .trajectory.joints_rad[1];
    const Eigen::Vector3d err =
        testing::MeasuredPointInBase(r.robot, r.flange_from_sensor, q) -
        testing::MeasuredPointInBase(poses.truth.true_vision_robot,
                                     poses.truth.vision_flange_from_sensor, q);
    const Eigen::Matrix3d cov = PointCovarianceInBase(r, q, Eigen::Vector3d(0, 0, 700));
    // Offsets only: rank <= 6 but a 3x3 of a 6-joint robot is full rank at a general pose.
    mahalanobis2 += err.dot(cov.ldlt().solve(err));
    ++positioned;
  }
  const double fraction = static_cast<double>(inside) / total;
  const double mean_m2 = mahalanobis2 / positioned;
  std::printf(
      "joint offsets inside 1 sigma: %.3f of %d; positioning: mean squared Mahalanobis "
      "%.2f over %d held-out poses (3 expected)\n",
      fraction, total, mean_m2, positioned);
  if (lasercell::test::StatisticsAsserted()) {
    EXPECT_GE(fraction, 0.60);
    EXPECT_LE(fraction, 0.76);
    // Mean of 100 chi-square(3) draws: sd sqrt(6/100) = 0.245; 3.3 sd either way.
    EXPECT_GT(mean_m2, 2.2);
    EXPECT_LT(mean_m2, 3.8);
  }
}

// The true UR5 also has DH length errors (N(0, 0.3 mm) on every a and d): joint offsets alone
// leave a positioning error; with --dh-deltas the parameters the poses cannot separate (e.g. the
// d of the parallel joints 2-4, only their sum acts) are named and fixed, and the held-out
// positioning error drops back under 0.1 mm.
// Simulation profile: ideal, plus DH length errors N(0, 0.3 mm).
TEST(JointIdentification, DhDeltasNameTheUnidentifiableAndFixThePositioning) {
  datasets::SimConfig config = JointConfig();
  config.dh_length_sigma_mm = 0.3;
  const testing::PlannedPoses poses = testing::PlanPoses(config, config.joint_poses, 4242);
  const std::vector<SphereSweep> sweeps =
      testing::SyntheticSweeps(poses, kAccuracyProfiles, 0.05, 31);
  JointIdentificationOptions options;
  options.point_sigma_mm = 0.05;
  options.known_centres_in_base = poses.centres_in_base;
  options.known_centre_sigma_mm = 0.02;
  const auto held_out_worst = [&](const JointIdentificationResult& r) {
    datasets::PoseSweepOptions held = config.joint_poses;
    held.poses = kHeldOutPoses;
    double worst = 0;
    for (const datasets::PoseSweep& p :
         datasets::PlanPoseSweeps(config, poses.truth, held, 999, "held-out")) {
      const std::vector<double>& q = p.trajectory.joints_rad[1];
      worst =
          std::max(worst, (testing::MeasuredPointInBase(r.robot, r.flange_from_sensor, q) -
                           testing::MeasuredPointInBase(poses.truth.true_vision_robot,
                                                        poses.truth.vision_flange_from_sensor, q))
                              .norm());
    }
    return worst;
  };
  const JointIdentificationResult offsets_only = IdentifyRobot(
      poses.truth.nominal_vision_robot, poses.truth.vision_flange_from_sensor, sweeps, options);
  options.estimate_dh_deltas = true;
  const JointIdentificationResult full = IdentifyRobot(
      poses.truth.nominal_vision_robot, poses.truth.vision_flange_from_sensor, sweeps, options);
  ASSERT_TRUE(full.converged) << full.Summary();
  const double worst_offsets = held_out_worst(offsets_only), worst_full = held_out_worst(full);
  std::printf("DH deltas: %s\n  %s\n  held-out worst: offsets only %.4f mm, full %.4f mm\n",
              full.Summary().c_str(), full.observability.Summary().c_str(), worst_offsets,
              worst_full);
  EXPECT_FALSE(full.observability.directions.empty());
  EXPECT_LT(full.observability.condition_number, 1e6);
  EXPECT_GT(worst_offsets, 0.1);
  EXPECT_LT(worst_full, 0.1);
  // The offsets alone cannot absorb 0.3 mm link-length errors: whole sweeps stay biased and the
  // result says so; with the lengths free the per-sweep means are noise (F ~ 1).
  EXPECT_GT(offsets_only.sweep_bias_ratio, kSweepBiasWarningRatio);
  EXPECT_THAT(::testing::PrintToString(offsets_only.warnings), HasSubstr("estimate DH deltas"));
  EXPECT_LT(full.sweep_bias_ratio, 2.0);
  EXPECT_THAT(::testing::PrintToString(full.warnings),
              ::testing::Not(HasSubstr("model misses something")));
}

TEST(JointIdentification, RejectsFewerPosesThanParameters) {
  const testing::PlannedPoses& poses = FiftyPoses();
  std::vector<SphereSweep> sweeps = testing::SyntheticSweeps(poses, 4, 0.05, 3);
  sweeps.resize(8);
  JointIdentificationOptions options;
  options.estimate_dh_deltas = true;
  try {
    IdentifyRobot(poses.truth.nominal_vision_robot, poses.truth.vision_flange_from_sensor, sweeps,
                  options);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("record more poses"));
  }
}

TEST(JointIdentification, RejectsProfilesWithoutJoints) {
  const testing::PlannedPoses& poses = FiftyPoses();
  std::vector<SphereSweep> sweeps = testing::SyntheticSweeps(poses, 4, 0.05, 3);
  sweeps[3].profiles[2].joints_rad.clear();
  try {
    IdentifyRobot(poses.truth.nominal_vision_robot, poses.truth.vision_flange_from_sensor, sweeps,
                  {});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("pose_3' profile 2: no joint values recorded"));
  }
}

TEST(JointIdentification, RejectsMismatchedCentreCount) {
  const testing::PlannedPoses& poses = FiftyPoses();
  const std::vector<SphereSweep> sweeps = testing::SyntheticSweeps(poses, 4, 0.05, 3);
  JointIdentificationOptions options;
  options.known_centres_in_base = {poses.centres_in_base[0], poses.centres_in_base[1]};
  try {
    IdentifyRobot(poses.truth.nominal_vision_robot, poses.truth.vision_flange_from_sensor, sweeps,
                  options);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("2 given but the sweeps aim at 4 spheres"));
  }
}

TEST(JointIdentification, RejectsPosesRotatingAboutOneAxisWithHandEye) {
  const testing::PlannedPoses& poses = FiftyPoses();
  std::vector<SphereSweep> sweeps = testing::SyntheticSweeps(poses, 4, 0.05, 3);
  const std::vector<double> q0 = sweeps[0].profiles[0].joints_rad;
  for (std::size_t i = 0; i < sweeps.size(); ++i) {
    for (SweptProfile& p : sweeps[i].profiles) {
      p.joints_rad = q0;
      p.joints_rad[0] += 0.05 * static_cast<double>(i);
    }
  }
  JointIdentificationOptions options;
  options.estimate_hand_eye = true;
  try {
    IdentifyRobot(poses.truth.nominal_vision_robot, poses.truth.vision_flange_from_sensor, sweeps,
                  options);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("about one axis"));
  }
}

TEST(JointIdentification, RejectsPureTranslationsWithHandEye) {
  const testing::PlannedPoses& poses = FiftyPoses();
  std::vector<SphereSweep> sweeps = testing::SyntheticSweeps(poses, 4, 0.05, 3);
  const DhChain& robot = poses.truth.nominal_vision_robot;
  const std::vector<double> q0 = sweeps[0].profiles[0].joints_rad;
  const Eigen::Isometry3d f0 = robot.BaseFromFlange(q0);
  for (std::size_t i = 0; i < sweeps.size(); ++i) {
    Eigen::Isometry3d target = f0;
    target.translation() += Eigen::Vector3d(2.0 * i, -1.0 * i, 0.5 * i);
    const auto q = datasets::SolveIk(robot, target, q0);
    ASSERT_TRUE(q.has_value()) << i;
    for (SweptProfile& p : sweeps[i].profiles) p.joints_rad = *q;
  }
  JointIdentificationOptions options;
  options.estimate_hand_eye = true;
  try {
    IdentifyRobot(robot, poses.truth.vision_flange_from_sensor, sweeps, options);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("pure translations"));
  }
}

TEST(JointIdentificationOptions, CheckNamesTheField) {
  JointIdentificationOptions o;
  o.point_sigma_mm = 0;
  EXPECT_THAT([&] { o.Check(); },
              ::testing::ThrowsMessage<OptionError>(HasSubstr("point_sigma_mm")));
}

}  // namespace
}  // namespace lasercell::calib
