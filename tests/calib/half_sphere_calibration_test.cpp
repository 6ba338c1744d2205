// Half-sphere calibration handling_base_from_sweep: simulated sweep + touches against the truth,
// calibrated covariance (Monte Carlo), correspondence, and bad input.
#include "calib/half_sphere_calibration.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/error.hpp"
#include "core/se3.hpp"
#include "datasets/sim_profile.hpp"
#include "tests/calib/sphere_sweep_sim.hpp"
#include "tests/calib/sphere_test_util.hpp"
#include "tests/sanitizer_scale.hpp"

namespace lasercell::calib {
namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;

std::vector<SphereTouch> Touches(const std::vector<datasets::Touch>& sim) {
  std::vector<SphereTouch> out;
  for (const auto& t : sim) out.push_back({t.sphere, t.measured_in_handling_base, t.joints_rad});
  return out;
}

// Errors of an estimate against the truth: rotation (deg), translation of the transform (the
// sweep origin = the sensor at the sweep start, ~0.7 m from the spheres) and the largest error
// of a mapped point over the spheres' working volume (the four true centres).
struct PoseError {
  double rotation_deg, translation_mm, at_spheres_mm;
};
PoseError Compare(const Eigen::Isometry3d& est, const Eigen::Isometry3d& truth,
                  const std::vector<Eigen::Vector3d>& centers_in_sweep) {
  PoseError e{RotationDistance(est, truth) * kRadToDeg, TranslationDistance(est, truth), 0};
  for (const auto& c : centers_in_sweep)
    e.at_spheres_mm = std::max(e.at_spheres_mm, (est * c - truth * c).norm());
  return e;
}

// A result against the simulated truth: the errors, and the Mahalanobis distance of the error
// under the reported 6x6 covariance; printed as one `[ measured ]` line headed `what`.
struct Scored {
  PoseError error;
  double mahalanobis;
};
Scored Score(const HalfSphereCalibrationResult& r, const testing::SimulatedSphereSweep& sim,
             const char* what) {
  const Scored s{
      Compare(r.handling_base_from_sweep, sim.handling_base_from_sweep, sim.centers_in_sweep),
      std::sqrt([&] {
        const Vector6d xi = RotationVectorTranslation(sim.handling_base_from_sweep *
                                                      r.handling_base_from_sweep.inverse());
        return xi.dot(r.covariance.inverse() * xi);
      }())};
  std::printf(
      "[ measured ] %s: %s; error vs truth: rotation %.5f deg, translation %.4f mm, at the "
      "spheres %.4f mm; Mahalanobis %.2f (6 dof)\n",
      what, r.Summary().c_str(), s.error.rotation_deg, s.error.translation_mm,
      s.error.at_spheres_mm, s.mahalanobis);
  return s;
}

// The full chain on the simulated cell: render + triangulate the sphere sweep, segment, fit,
// match the 4 touches (simulator default: sigma 0.05 mm per axis), rigid fit.
// Simulation profile: ideal (DefaultSphereSweep; a regression check of the algorithms' own error).
TEST(CalibrateHalfSpheres, SimulatedCellAgreesWithTheTruthWithinItsReportedSigma) {
  const testing::SimulatedSphereSweep& sim = testing::DefaultSphereSweep();
  const SphereSegmentationResult& seg = testing::DefaultSphereSegmentation();
  ASSERT_EQ(seg.spheres.size(), 4u) << seg.Summary();
  HalfSphereCalibrationOptions options;
  options.touch_sigma_mm = 0.05;
  const HalfSphereCalibrationResult r =
      CalibrateHalfSpheres(SweptSpheresFrom(seg), Touches(sim.touches), options);
  ASSERT_EQ(r.spheres.size(), 4u);
  for (const auto& s : r.spheres) {
    // The match is right: the swept sphere lies where the truth puts sphere s.sphere.
    EXPECT_LT((s.center_in_sweep - sim.centers_in_sweep[static_cast<std::size_t>(s.sphere)]).norm(),
              0.05);
  }
  const double mahalanobis = Score(r, sim, "touch sigma 0.05").mahalanobis;
  // 6-dof chi2 at p = 0.999: 22.5 -> Mahalanobis 4.7.
  EXPECT_LT(mahalanobis, 4.7);
  EXPECT_TRUE(r.unmatched_swept.empty());
  EXPECT_TRUE(r.unmatched_touches.empty());
}

// The same chain on the realistic profile (datasets/SIMULATOR.md, Profiles: speckle, ghosts and
// dropouts on the sweep, timestamp noise, sphere radii up to 0.05 mm off the 25 mm the touches
// file states), seed 437, the true camera and plane (the chain through calibrated ones is
// `lasercell bench table1`, BENCHMARKS.md). Asserted: the error within the reported covariance
// (Mahalanobis, 6 dof, p = 0.999), at the stated touch noise and at CMM-grade touches with the
// radii fitted. The 0.05 mm / 0.01 deg targets are not met here (BENCHMARKS.md, half-sphere
// section): the stated 0.05 mm touches alone leave 0.012 deg of 1 sigma.
TEST(CalibrateHalfSpheres, RealisticSweepAgreesWithTheTruthWithinItsReportedSigma) {
  if (lasercell::test::kSanitizerBuild) {
    GTEST_SKIP() << "a second rendered sweep; the chain runs under the sanitizer in the test above";
  }
  datasets::SimConfig config = datasets::SimConfigForProfile(datasets::SimProfile::kRealistic);
  config.seed = 437;
  const testing::SimulatedSphereSweep sim =
      testing::SimulateSphereSweep(config, datasets::StreamSeed(437, 0x5F));
  const SphereSegmentationResult seg = SegmentSpheres(sim.cloud);
  ASSERT_EQ(seg.spheres.size(), 4u) << seg.Summary();
  HalfSphereCalibrationOptions options;
  options.touch_sigma_mm = config.touches.sigma_mm;  // what the touches file states
  const HalfSphereCalibrationResult r =
      CalibrateHalfSpheres(SweptSpheresFrom(seg), Touches(sim.touches), options);
  ASSERT_EQ(r.spheres.size(), 4u);
  EXPECT_LT(Score(r, sim, "realistic, touches 0.05 mm, radius fixed").mahalanobis, 4.7);
  // At CMM-grade touches (0.005 mm per axis) the rest shows: the realistic radii are up to
  // 0.05 mm off the stated 25 mm, which a fixed radius turns into centre heights the covariance
  // does not hold (chi2/dof 13.2/6, Mahalanobis 5.3 on this seed); fitted radii take it up.
  datasets::SimConfig fine = config;
  fine.touches.sigma_mm = 0.005;
  const testing::SimulatedSphereSweep sim_fine =
      testing::SimulateSphereSweep(fine, datasets::StreamSeed(437, 0x5F));
  SphereSegmentationOptions free_radius;
  free_radius.fix_radius = false;
  options.touch_sigma_mm = fine.touches.sigma_mm;
  const HalfSphereCalibrationResult f =
      CalibrateHalfSpheres(SweptSpheresFrom(SegmentSpheres(sim_fine.cloud, free_radius)),
                           Touches(sim_fine.touches), options);
  EXPECT_LT(Score(f, sim_fine, "realistic, touches 0.005 mm, free radii").mahalanobis, 4.7);
  // The fixed radius at the same touches: without the radius tolerance the covariance does not
  // hold the error (printed for BENCHMARKS.md); with the tolerance the touches file states
  // (+-0.05 mm, the simulator draws the radii within it) it must.
  const HalfSphereCalibrationResult x = CalibrateHalfSpheres(
      SweptSpheresFrom(SegmentSpheres(sim_fine.cloud)), Touches(sim_fine.touches), options);
  Score(x, sim_fine, "realistic, touches 0.005 mm, radius fixed, no tolerance");
  SphereTouches stated;
  stated.stated_sigma_mm = fine.touches.sigma_mm;
  stated.sphere_radius_mm = fine.spheres.radius_mm;
  stated.sphere_radius_tolerance_mm = fine.sphere_radius_tolerance_mm;
  stated.touches = Touches(sim_fine.touches);
  const HalfSphereSweepResult t = CalibrateHalfSpheresInSweep(sim_fine.cloud, stated, {});
  ASSERT_TRUE(t.calibrated) << t.failure;
  EXPECT_EQ(t.radius_tolerance_mm, 0.05);
  EXPECT_LT(Score(t.calibration, sim_fine, "realistic, touches 0.005 mm, radius fixed, +-0.05 mm")
                .mahalanobis,
            4.7);
}

// Target: <= 0.05 mm / 0.01 deg from the truth with 4 spheres. The transform's translation is the
// sensor's position at the sweep start, ~0.7 m from the spheres, so rotation noise reaches it
// through that lever arm: with the simulator's default touch sigma of 0.05 mm per axis the
// reported 1-sigma of that translation is ~0.11 mm per axis (test above), so 0.05 mm cannot be met
// there. Lower touch sigmas, 20 seeded draws of the touch noise each on the same sweep: 0.01 mm
// reaches ~0.05 mm only just (printed, not asserted); 0.005 mm per axis (a CMM-grade probe;
// stated, not hidden) meets the issue's numbers with margin, and that is what is asserted.
// Simulation profile: ideal (the swept spheres of DefaultSphereSweep; the touches are drawn here).
TEST(CalibrateHalfSpheres, FourSpheresMeetTheIssueNumbersAtTouchSigmaFiveMicrometres) {
  const testing::SimulatedSphereSweep& sim = testing::DefaultSphereSweep();
  const SphereSegmentationResult& seg = testing::DefaultSphereSegmentation();
  ASSERT_EQ(seg.spheres.size(), 4u);
  const auto swept = SweptSpheresFrom(seg);
  for (double sigma : {0.01, 0.005}) {
    datasets::Rng rng(99);
    double worst_rot = 0, worst_trans = 0, worst_at = 0, sigma_trans = 0, sigma_rot = 0;
    for (int draw = 0; draw < 20; ++draw) {
      std::vector<SphereTouch> touches;
      for (std::size_t k = 0; k < 4; ++k) {
        const Eigen::Vector3d top =
            sim.centers_in_handling_base[k] + Eigen::Vector3d(0, 0, sim.radius_mm);
        touches.push_back({static_cast<int>(k),
                           top + sigma * Eigen::Vector3d{rng.Normal(), rng.Normal(), rng.Normal()},
                           std::nullopt});
      }
      HalfSphereCalibrationOptions options;
      options.touch_sigma_mm = sigma;
      const HalfSphereCalibrationResult r = CalibrateHalfSpheres(swept, touches, options);
      const PoseError e =
          Compare(r.handling_base_from_sweep, sim.handling_base_from_sweep, sim.centers_in_sweep);
      worst_rot = std::max(worst_rot, e.rotation_deg);
      worst_trans = std::max(worst_trans, e.translation_mm);
      worst_at = std::max(worst_at, e.at_spheres_mm);
      sigma_trans = r.fit.TranslationSigmaMm().norm();
      sigma_rot = r.fit.RotationSigmaDeg().norm();
    }
    std::printf(
        "[ measured ] touch sigma %.3f mm, 20 draws: worst rotation %.5f deg, translation "
        "%.4f mm, at the spheres %.4f mm (reported 1-sigma |rot| %.5f deg, |trans| %.4f "
        "mm)\n",
        sigma, worst_rot, worst_trans, worst_at, sigma_rot, sigma_trans);
    if (sigma == 0.005) {
      EXPECT_LE(worst_rot, 0.01);
      EXPECT_LE(worst_trans, 0.05);
      EXPECT_LE(worst_at, 0.05);
    }
  }
}

// Calibrated uncertainty of the transform: 100 Monte-Carlo draws of sphere points (sensor-like
// caps, sigma 0.05 mm, centres fitted with the radius given, then free) and touches (sigma
// 0.05 mm); truth inside the reported 1-sigma 60-76 % of the time over the 6 coordinates.
// No simulated points: only DefaultSphereSweep's truth is used; caps and touches are drawn here.
TEST(CalibrateHalfSpheres, TransformCovarianceIsCalibrated) {
  const testing::SimulatedSphereSweep& sim = testing::DefaultSphereSweep();
  const Eigen::Isometry3d& truth = sim.handling_base_from_sweep;
  // Sample each cap about "up" expressed in the sweep frame.
  const Eigen::Vector3d up_in_sweep = truth.linear().transpose() * Eigen::Vector3d::UnitZ();
  const Eigen::Matrix3d local_to_sweep =
      Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), up_in_sweep).toRotationMatrix();
  for (bool free_radius : {false, true}) {
    datasets::Rng rng(free_radius ? 2028 : 2027);
    int inside = 0, total = 0;
    for (int draw = 0; draw < lasercell::test::Draws(100); ++draw) {
      std::vector<SweptSphere> swept;
      std::vector<SphereTouch> touches;
      for (std::size_t k = 0; k < 4; ++k) {
        auto local = testing::SampleCap(Eigen::Vector3d::Zero(), 25.0, 80.0, 0.05, rng, 2.58, 1.5);
        for (auto& p : local) p = sim.centers_in_sweep[k] + local_to_sweep * p;
        SphereFitOptions fo;
        if (!free_radius) fo.radius_mm = 25.0;
        const SphereFitResult f = FitSphere(local, fo);
        ASSERT_TRUE(f.success);
        swept.push_back({f.center, f.CenterCovariance(), f.radius_mm, f.radius_sigma_mm,
                         f.covariance.block<3, 1>(0, 3)});
        const Eigen::Vector3d top = sim.centers_in_handling_base[k] + Eigen::Vector3d(0, 0, 25.0);
        touches.push_back({static_cast<int>(k),
                           top + 0.05 * Eigen::Vector3d{rng.Normal(), rng.Normal(), rng.Normal()},
                           std::nullopt});
      }
      HalfSphereCalibrationOptions options;
      options.touch_sigma_mm = 0.05;
      const HalfSphereCalibrationResult r = CalibrateHalfSpheres(swept, touches, options);
      const Vector6d xi = RotationVectorTranslation(truth * r.handling_base_from_sweep.inverse());
      for (int i = 0; i < 6; ++i) {
        inside += std::abs(xi[i]) <= std::sqrt(r.covariance(i, i));
        ++total;
      }
    }
    const double fraction = static_cast<double>(inside) / total;
    std::printf("[ measured ] half-sphere transform 1-sigma coverage (%s radius): %.3f over %d\n",
                free_radius ? "free" : "given", fraction, total);
    if (!lasercell::test::StatisticsAsserted()) continue;
    EXPECT_GE(fraction, 0.60);
    EXPECT_LE(fraction, 0.76);
  }
}

std::vector<SweptSphere> SweptAt(const std::vector<Eigen::Vector3d>& centers) {
  std::vector<SweptSphere> out;
  for (const auto& c : centers) out.push_back({c, 1e-4 * Eigen::Matrix3d::Identity(), 25.0, 0.0});
  return out;
}

std::vector<SphereTouch> TouchesAt(const std::vector<Eigen::Vector3d>& centers,
                                   const Eigen::Isometry3d& hb_from_sweep) {
  std::vector<SphereTouch> out;
  for (std::size_t k = 0; k < centers.size(); ++k) {
    out.push_back({static_cast<int>(k), hb_from_sweep * centers[k] + Eigen::Vector3d(0, 0, 25.0),
                   std::nullopt});
  }
  return out;
}

Eigen::Isometry3d SomePose() {
  return PoseFromRotationVector(Eigen::Vector3d(3.0, 0.1, -0.2), Eigen::Vector3d(900, -40, 650));
}

TEST(CalibrateHalfSpheres, TouchOrderDoesNotMatterAndExtraSweptSpheresAreReported) {
  const std::vector<Eigen::Vector3d> centers = {
      {-250, -140, 600}, {230, -160, 560}, {260, 150, 520}, {-220, 170, 480}};
  auto touches = TouchesAt(centers, SomePose());
  std::swap(touches[0], touches[3]);
  auto swept = SweptAt(centers);
  swept.push_back({Eigen::Vector3d(0, 0, 300), 1e-4 * Eigen::Matrix3d::Identity(), 25.0, 0.0});
  const auto r = CalibrateHalfSpheres(swept, touches, {});
  EXPECT_LT(RotationDistance(r.handling_base_from_sweep, SomePose()), 1e-9);
  ASSERT_EQ(r.spheres.size(), 4u);
  for (const auto& s : r.spheres) EXPECT_EQ(s.swept, static_cast<std::size_t>(s.sphere));
  ASSERT_EQ(r.unmatched_swept.size(), 1u);
  EXPECT_EQ(r.unmatched_swept[0], 4u);
  EXPECT_FALSE(r.warnings.empty());
}

// Not converging is an outcome on valid data: reported (warning, fit.converged), not thrown.
TEST(CalibrateHalfSpheres, ARigidFitThatDoesNotConvergeIsAWarning) {
  const std::vector<Eigen::Vector3d> centers = {
      {-250, -140, 600}, {230, -160, 560}, {260, 150, 520}, {-220, 170, 480}};
  auto touches = TouchesAt(centers, SomePose());
  const Eigen::Vector3d noise[4] = {
      {0.3, -0.1, 0.2}, {-0.2, 0.25, -0.1}, {0.1, 0.2, -0.3}, {-0.15, -0.3, 0.1}};
  for (std::size_t k = 0; k < 4; ++k) touches[k].point_in_handling_base += noise[k];
  auto swept = SweptAt(centers);
  // Anisotropic centre covariances: the Mahalanobis optimum is not the closed form's.
  for (auto& s : swept) s.covariance = Eigen::Vector3d(1e-4, 4e-4, 9e-2).asDiagonal();
  HalfSphereCalibrationOptions options;
  options.rigid.max_iterations = 1;
  const auto r = CalibrateHalfSpheres(swept, touches, options);
  EXPECT_FALSE(r.fit.converged);
  bool warned = false;
  for (const auto& w : r.warnings)
    warned = warned || w.find("did not converge") != std::string::npos;
  EXPECT_TRUE(warned);
  options.rigid.max_iterations = 20;
  const auto converged = CalibrateHalfSpheres(swept, touches, options);
  EXPECT_TRUE(converged.fit.converged);
  for (const auto& w : converged.warnings) EXPECT_EQ(w.find("did not converge"), std::string::npos);
}

TEST(CalibrateHalfSpheres, FewerThanThreeSpheresIsAnError) {
  const std::vector<Eigen::Vector3d> centers = {{-250, -140, 600}, {230, -160, 560}};
  try {
    CalibrateHalfSpheres(SweptAt(centers), TouchesAt(centers, SomePose()), {});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(),
                 "half-sphere calibration: 2 sphere touches: at least 3 non-collinear "
                 "spheres must be both swept and touched (fewer leave the rotation "
                 "unobservable)");
  }
}

TEST(CalibrateHalfSpheres, CollinearSpheresAreAnError) {
  const std::vector<Eigen::Vector3d> centers = {{-250, 0, 600}, {0, 0, 600}, {300, 0, 600}};
  try {
    CalibrateHalfSpheres(SweptAt(centers), TouchesAt(centers, SomePose()), {});
    FAIL();
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("the 3 spheres are collinear"), std::string::npos) << m;
    EXPECT_NE(m.find("add a sphere off the line"), std::string::npos) << m;
  }
}

TEST(CalibrateHalfSpheres, SymmetricLayoutIsAmbiguous) {
  // A square at one height: rotations by 90 deg map it onto itself.
  const std::vector<Eigen::Vector3d> centers = {
      {-200, -200, 600}, {200, -200, 600}, {200, 200, 600}, {-200, 200, 600}};
  try {
    CalibrateHalfSpheres(SweptAt(centers), TouchesAt(centers, SomePose()), {});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("ambiguous correspondence"), std::string::npos)
        << e.what();
  }
}

TEST(CalibrateHalfSpheres, TouchesThatMatchNoSweptLayoutAreAnError) {
  const std::vector<Eigen::Vector3d> centers = {
      {-250, -140, 600}, {230, -160, 560}, {260, 150, 520}, {-220, 170, 480}};
  auto touches = TouchesAt(centers, SomePose());
  touches[2].point_in_handling_base *= 0.001;  // one touch in metres
  try {
    CalibrateHalfSpheres(SweptAt(centers), touches, {});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("do not match the swept ones"), std::string::npos)
        << e.what();
  }
}

// --- touches file -------------------------------------------------------------------------------

const char* kTouchesYaml = R"(format: lasercell.touches
version: 1
robot: handling_robot
frame: handling_base
handling_flange_from_tool_tip: {translation_mm: [0, 0, 200], rotation_wxyz: [1, 0, 0, 0]}
stated_sigma_mm: 0.05
sphere_radius_mm: 25
touches:
  - sphere: 0
    point_in_handling_base: [1600.1, -140.2, 234.0]
    joints_rad: [0.1, 0.2, 0.3, 0.4, 0.5, 0.6]
  - sphere: 1
    point_in_handling_base: [1120.0, 160.0, 274.0]
    joints_rad: null
)";

TEST(ParseTouchesYaml, ReadsTheSimulatorsFormat) {
  const SphereTouches t = ParseTouchesYaml(kTouchesYaml, "touches.yaml");
  ASSERT_EQ(t.touches.size(), 2u);
  EXPECT_EQ(t.touches[1].sphere, 1);
  EXPECT_DOUBLE_EQ(t.touches[0].point_in_handling_base.x(), 1600.1);
  EXPECT_TRUE(t.touches[0].joints_rad.has_value());
  EXPECT_FALSE(t.touches[1].joints_rad.has_value());
  EXPECT_DOUBLE_EQ(*t.sphere_radius_mm, 25.0);
  EXPECT_DOUBLE_EQ(t.stated_sigma_mm, 0.05);
  ASSERT_TRUE(t.handling_flange_from_tool_tip.has_value());
  EXPECT_DOUBLE_EQ(t.handling_flange_from_tool_tip->translation().z(), 200.0);
}

// Simulation profile: ideal (the touches of DefaultSphereSweep).
TEST(ParseTouchesYaml, ReadsWhatTheSimulatorWrites) {
  const testing::SimulatedSphereSweep& sim = testing::DefaultSphereSweep();
  datasets::SimConfig config;
  const SphereTouches t =
      ParseTouchesYaml(datasets::TouchesRecordYaml(config, sim.touches), "records/touches.yaml");
  ASSERT_EQ(t.touches.size(), sim.touches.size());
  for (std::size_t i = 0; i < t.touches.size(); ++i) {
    EXPECT_LT(
        (t.touches[i].point_in_handling_base - sim.touches[i].measured_in_handling_base).norm(),
        1e-12);
    // Every recorded field reads back exactly (shortest round-trip numbers).
    EXPECT_EQ(t.touches[i].sphere, sim.touches[i].sphere);
    EXPECT_EQ(t.touches[i].point_in_handling_base, sim.touches[i].measured_in_handling_base);
    EXPECT_EQ(t.touches[i].joints_rad, sim.touches[i].joints_rad) << "touch " << i;
  }
  EXPECT_EQ(t.robot, "handling_robot");
  EXPECT_EQ(t.frame, "handling_base");
  EXPECT_EQ(t.stated_sigma_mm, config.touches.sigma_mm);
  EXPECT_EQ(t.sphere_radius_mm, config.spheres.radius_mm);
  EXPECT_FALSE(t.sphere_radius_tolerance_mm.has_value());  // the ideal spheres state none
  datasets::SimConfig realistic = datasets::SimConfigForProfile(datasets::SimProfile::kRealistic);
  EXPECT_EQ(ParseTouchesYaml(datasets::TouchesRecordYaml(realistic, sim.touches), "t.yaml")
                .sphere_radius_tolerance_mm,
            realistic.sphere_radius_tolerance_mm);
  ASSERT_TRUE(t.handling_flange_from_tool_tip.has_value());
  EXPECT_LT(
      (t.handling_flange_from_tool_tip->matrix() - datasets::PointingTool(config.touches).matrix())
          .norm(),
      1e-12);
}

void ExpectFileError(const std::string& text, const std::string& expected) {
  try {
    ParseTouchesYaml(text, "touches.yaml");
    FAIL() << "no error for: " << expected;
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).rfind("touches.yaml: ", 0), 0u) << e.what();
  }
}

std::string Replace(std::string s, const std::string& from, const std::string& to) {
  s.replace(s.find(from), from.size(), to);
  return s;
}

TEST(ParseTouchesYaml, RadiusToleranceIsReadAndChecked) {
  const std::string with = Replace(kTouchesYaml, "sphere_radius_mm: 25\n",
                                   "sphere_radius_mm: 25\nsphere_radius_tolerance_mm: 0.05\n");
  EXPECT_EQ(ParseTouchesYaml(with, "touches.yaml").sphere_radius_tolerance_mm, 0.05);
  ExpectFileError(Replace(with, "tolerance_mm: 0.05", "tolerance_mm: -0.05"),
                  "sphere_radius_tolerance_mm");
  ExpectFileError(Replace(with, "tolerance_mm: 0.05", "tolerance_mm: 5"),
                  "at most a tenth of sphere_radius_mm");
}

TEST(ParseTouchesYaml, UnknownFieldsAreErrors) {
  ExpectFileError(Replace(kTouchesYaml, "robot:", "robto:"),
                  "line 3: unknown field 'robto' (known fields here: format, version, robot, "
                  "frame,");
  ExpectFileError(Replace(kTouchesYaml, "joints_rad: null", "joint_rad: null"),
                  "line 14: unknown field 'touches[1].joint_rad'");
}

TEST(ParseTouchesYaml, MixedUnitsAreErrors) {
  // A field in another unit.
  ExpectFileError(Replace(kTouchesYaml, "stated_sigma_mm: 0.05", "stated_sigma_m: 0.00005"),
                  "line 6: unknown field 'stated_sigma_m'; did you mean 'stated_sigma_mm'? "
                  "(lasercell uses millimetres)");
  ExpectFileError(Replace(kTouchesYaml, "stated_sigma_mm: 0.05", "stated_sigma_in: 0.002"),
                  "line 6: unknown field 'stated_sigma_in'; did you mean 'stated_sigma_mm'? "
                  "(lasercell uses millimetres)");
  // One touch in metres among millimetres.
  ExpectFileError(
      Replace(kTouchesYaml, "[1120.0, 160.0, 274.0]", "[1.12, 0.16, 0.274]"),
      "line 13: field 'touches[1].point_in_handling_base' is 1.164077 from the base while "
      "another is 1623.185772");
  ExpectFileError(Replace(kTouchesYaml, "[1120.0, 160.0, 274.0]", "[1.12, 0.16, 0.274]"),
                  "mixed units (metres among millimetres?)");
  // Joints in degrees.
  ExpectFileError(
      Replace(kTouchesYaml, "[0.1, 0.2, 0.3, 0.4, 0.5, 0.6]", "[10, 20, 30, 40, 50, 60]"),
      "line 11: field 'touches[0].joints_rad' holds 10.000000, beyond +-2 pi: it looks like "
      "degrees");
  // A radius in metres.
  ExpectFileError(Replace(kTouchesYaml, "sphere_radius_mm: 25", "sphere_radius_mm: 0.025"),
                  "line 7: field 'sphere_radius_mm' is 0.025, which looks like metres");
}

TEST(ParseTouchesYaml, OtherProblemsNameTheField) {
  ExpectFileError(Replace(kTouchesYaml, "frame: handling_base", "frame: cell"),
                  "line 4: field 'frame' is 'cell': touches must be given in handling_base");
  ExpectFileError(Replace(kTouchesYaml, "- sphere: 1", "- sphere: 0"),
                  "line 12: field 'touches[1].sphere' repeats a label: sphere 0 is touched twice");
  ExpectFileError(Replace(kTouchesYaml, "[1120.0, 160.0, 274.0]", "[1120.0, 160.0]"),
                  "line 13: field 'touches[1].point_in_handling_base' must list exactly 3 numbers "
                  "(got 2)");
  ExpectFileError(Replace(kTouchesYaml, "format: lasercell.touches", "format: foo"),
                  "line 1: field 'format' is 'foo', expected 'lasercell.touches'");
  ExpectFileError(Replace(kTouchesYaml, "version: 1", "version: 2"),
                  "line 2: field 'version' is 2; this build reads lasercell.touches version 1");
  ExpectFileError("[1, 2]", "is not a touches file");
}

}  // namespace
}  // namespace lasercell::calib
