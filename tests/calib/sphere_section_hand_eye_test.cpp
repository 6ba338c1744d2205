// Eye-in-hand calibration of a line profiler from one profile per pose across a fixed sphere:
// synthetic recovery with calibrated uncertainty, bad input, and the real AT C5 / Fanuc set
// (../shared/data/laser_robot_sphere) scored as its source scores its own result.
#include "calib/sphere_section_hand_eye.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <vector>

#include "calib/pose_io.hpp"
#include "core/error.hpp"
#include "datasets/rng.hpp"
#include "tests/shared_data.hpp"
#include "triangulation/foreign_profiles.hpp"

namespace lasercell::calib {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

Eigen::Matrix3d RandomTilt(datasets::Rng& rng, double max_deg) {
  Eigen::Vector3d axis{rng.Normal(), rng.Normal(), rng.Normal()};
  return Eigen::AngleAxisd(rng.Uniform(-max_deg, max_deg) * kDeg, axis.normalized())
      .toRotationMatrix();
}

struct SyntheticSet {
  Eigen::Isometry3d flange_from_sensor = Eigen::Isometry3d::Identity();
  Eigen::Vector3d centre_in_base;
  std::vector<SphereSectionProfile> profiles;
};

// A 40 mm sphere seen from `poses` sensor poses tilted by up to 15 deg; each profile is the
// arc of the laser plane's section that faces the sensor (+-60 deg about the direction to the
// sensor), with 0.01 mm radial noise. The poses the "controller reports" are off by
// `robot_sigma_mm` per translation coordinate and robot_sigma_mm / 500 rad per rotation axis
// (a robot's positioning error), the error eq. (2) leaves in its residual.
SyntheticSet MakeSet(std::uint64_t seed, int poses, double robot_sigma_mm) {
  datasets::Rng rng(seed);
  SyntheticSet set;
  set.flange_from_sensor.linear() =
      (Eigen::AngleAxisd(-std::numbers::pi / 2, Eigen::Vector3d::UnitZ()) *
       Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d::UnitX()))
          .toRotationMatrix() *
      RandomTilt(rng, 3);
  set.flange_from_sensor.translation() = Eigen::Vector3d(-150, 714, 482) * 0.1;
  set.centre_in_base = Eigen::Vector3d(-100, 1300, 100);
  const double radius = 40.0;
  for (int i = 0; i < poses; ++i) {
    const double h = rng.Uniform(5, 30);  // r / R <= 0.992: every section is used
    const double r = std::sqrt(radius * radius - h * h);
    const Eigen::Vector3d s{rng.Uniform(40, 70), -h, rng.Uniform(-160, -130)};
    Eigen::Isometry3d base_from_sensor = Eigen::Isometry3d::Identity();
    base_from_sensor.linear() = RandomTilt(rng, 15);
    base_from_sensor.translation() = set.centre_in_base - base_from_sensor.linear() * s;
    SphereSectionProfile p;
    p.name = "pose " + std::to_string(i);
    const Eigen::Isometry3d true_base_from_flange =
        base_from_sensor * set.flange_from_sensor.inverse();
    Eigen::Isometry3d error = Eigen::Isometry3d::Identity();
    const Eigen::Vector3d w{rng.Normal(), rng.Normal(), rng.Normal()};
    error.linear() =
        Eigen::AngleAxisd(w.norm() * robot_sigma_mm / 500, w.normalized()).toRotationMatrix();
    error.translation() =
        robot_sigma_mm * Eigen::Vector3d{rng.Normal(), rng.Normal(), rng.Normal()};
    p.base_from_flange = error * true_base_from_flange;
    // The facing arc: about the direction from the circle centre to the sensor origin.
    const double towards = std::atan2(-s.z(), -s.x());
    for (int k = 0; k < 600; ++k) {
      const double a = towards + (k / 599.0 - 0.5) * 120 * kDeg;
      const double rr = r + 0.01 * rng.Normal();
      p.points_in_sensor.emplace_back(s.x() + rr * std::cos(a), 0.0, s.z() + rr * std::sin(a));
    }
    set.profiles.push_back(std::move(p));
  }
  return set;
}

SphereSectionHandEyeOptions Options40() {
  SphereSectionHandEyeOptions o;
  o.sphere_radius_mm = 40;
  o.sphere_side = -1;
  return o;
}

// Over 100 synthetic sets of 15 poses with a 0.1 mm robot, the reported 1-sigma of the six
// hand-eye coordinates covers the truth 60-76 % of the time (binomial sd ~1.9 % over 600), and
// no error exceeds 5 sigma.
TEST(SphereSectionHandEye, ReportedSigmaCoversTheTruth) {
  int inside = 0, total = 0;
  double worst_z = 0;
  for (int trial = 0; trial < 100; ++trial) {
    const SyntheticSet set = MakeSet(7000 + trial, 15, 0.1);
    SphereSectionHandEyeOptions o = Options40();
    o.leave_one_out = false;
    const SphereSectionHandEyeResult r = CalibrateHandEyeFromSphereSections(set.profiles, o);
    ASSERT_TRUE(r.converged) << r.Summary();
    ASSERT_EQ(r.sections_used, 15u);
    const Eigen::AngleAxisd dr(r.flange_from_sensor.linear() *
                               set.flange_from_sensor.linear().transpose());
    Eigen::Matrix<double, 6, 1> err;
    err.head<3>() = dr.angle() * dr.axis();
    err.tail<3>() = r.flange_from_sensor.translation() - set.flange_from_sensor.translation();
    for (int k = 0; k < 6; ++k) {
      const double z = std::abs(err[k]) / std::sqrt(r.covariance(k, k));
      inside += z <= 1.0;
      ++total;
      worst_z = std::max(worst_z, z);
    }
  }
  const double share = static_cast<double>(inside) / total;
  EXPECT_GT(share, 0.60);
  EXPECT_LT(share, 0.76);
  EXPECT_LT(worst_z, 5.0);
}

// Leave-one-out runs one solve per pose and predicts each pose's centre; with a 0.1 mm robot
// the prediction error is a few tenths of a millimetre, and the sphere radius and centre, the
// radius free, are found within their reported 4 sigma.
TEST(SphereSectionHandEye, LeaveOneOutAndFreeRadius) {
  const SyntheticSet set = MakeSet(7200, 15, 0.1);
  SphereSectionHandEyeOptions o = Options40();
  o.estimate_radius = true;
  const SphereSectionHandEyeResult r = CalibrateHandEyeFromSphereSections(set.profiles, o);
  ASSERT_TRUE(r.converged) << r.Summary();
  EXPECT_NEAR(r.radius_mm, 40.0, 4 * r.radius_sigma_mm);
  EXPECT_GT(r.radius_sigma_mm, 0.0);
  EXPECT_GT(r.loo_rms_mm, r.spread_rms_mm) << "a left-out pose is predicted, not fitted";
  EXPECT_LT(r.loo_rms_mm, 1.0);
  for (const SphereSection& s : r.sections) EXPECT_TRUE(std::isfinite(s.loo_distance_mm));
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(r.sphere_centre_in_base[k], set.centre_in_base[k],
                4 * std::sqrt(r.sphere_centre_covariance(k, k)));
  }
}

TEST(SphereSectionHandEye, BadInput) {
  const SyntheticSet set = MakeSet(7300, 8, 0.05);
  SphereSectionHandEyeOptions no_side = Options40();
  no_side.sphere_side = 0;
  EXPECT_THROW(CalibrateHandEyeFromSphereSections(set.profiles, no_side), OptionError);
  SphereSectionHandEyeOptions no_radius = Options40();
  no_radius.sphere_radius_mm = 0;
  EXPECT_THROW(CalibrateHandEyeFromSphereSections(set.profiles, no_radius), OptionError);
  // Four poses: too few, and the message names why.
  const std::vector<SphereSectionProfile> four(set.profiles.begin(), set.profiles.begin() + 4);
  EXPECT_THROW(CalibrateHandEyeFromSphereSections(four, Options40()), InputError);
  // Points off the laser plane.
  std::vector<SphereSectionProfile> off = set.profiles;
  off[2].points_in_sensor[10].y() = 0.5;
  EXPECT_THROW(CalibrateHandEyeFromSphereSections(off, Options40()), InputError);
  // Pure translations: every flange rotation the same -> the hand-eye is not determined.
  std::vector<SphereSectionProfile> shifted = set.profiles;
  for (SphereSectionProfile& p : shifted) p.base_from_flange.linear() = Eigen::Matrix3d::Identity();
  try {
    CalibrateHandEyeFromSphereSections(shifted, Options40());
    ADD_FAILURE() << "pure translations accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("tilted"), std::string::npos) << e.what();
  }
  // A profile that misses the sphere (a flat line) is left out with its reason, not fitted.
  std::vector<SphereSectionProfile> miss = set.profiles;
  for (std::size_t k = 0; k < miss[0].points_in_sensor.size(); ++k) {
    miss[0].points_in_sensor[k] = Eigen::Vector3d(k * 0.1, 0, -120);
  }
  SphereSectionHandEyeOptions o = Options40();
  o.leave_one_out = false;
  const SphereSectionHandEyeResult r = CalibrateHandEyeFromSphereSections(miss, o);
  EXPECT_FALSE(r.sections[0].used);
  EXPECT_NE(r.sections[0].why_not.find("no circle"), std::string::npos) << r.sections[0].why_not;
  EXPECT_EQ(r.sections_used, 7u);
}

// --- Real data: AT C5-2040 profiler on a Fanuc robot, 15 profiles of a 40 mm sphere. ---------

struct RealSphereSet {
  std::vector<SphereSectionProfile> profiles;
  Eigen::Isometry3d their_flange_from_sensor = Eigen::Isometry3d::Identity();
};

RealSphereSet LoadRealSet(const std::string& dir) {
  RealSphereSet set;
  const RobotPoses poses = LoadRobotPoses(dir + "/RobPoses.rob", "xyzwpr");
  for (std::size_t i = 0; i < poses.base_from_flange.size(); ++i) {
    const std::string file = dir + "/p" + std::to_string(i + 1) + ".yml";
    set.profiles.push_back({file, poses.base_from_flange[i],
                            triangulation::ReadScanLineProfile(file).points_in_sensor});
  }
  std::ifstream in(dir + "/calibration.sec");
  std::stringstream text;
  text << in.rdbuf();
  const nlohmann::json htm = nlohmann::json::parse(text.str())["Solution"]["HTM"];
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) set.their_flange_from_sensor.matrix()(r, c) = htm[r][c];
  }
  return set;
}

// The source repository's own hand-eye result, scored by its centre spread, is 0.38 mm RMS (a
// trimmed circle per profile). Ours, scored the same way (our sections, their X), must spread
// the centres no more than 0.3 mm RMS and less than theirs; the leave-one-pose-out prediction
// (poses the fit did not see) must stay below a millimetre at every pose.
TEST(SphereSectionHandEyeReal, BeatsTheSourceCalibrationOnItsOwnScore) {
  const std::string dir = shared_data::SharedDataSet("laser_robot_sphere");
  if (dir.empty())
    LASERCELL_SHARED_DATA_ABSENT(shared_data::SharedDataMissing("laser_robot_sphere"));
  const RealSphereSet set = LoadRealSet(dir);
  ASSERT_EQ(set.profiles.size(), 15u);
  const SphereSectionHandEyeOptions o = Options40();
  const SphereSectionHandEyeResult ours = CalibrateHandEyeFromSphereSections(set.profiles, o);
  ASSERT_TRUE(ours.converged) << ours.Summary();
  EXPECT_EQ(ours.sections_used, 15u);
  for (const SphereSection& s : ours.sections) {
    EXPECT_LT(s.circle.rms_mm, 0.1) << s.name << ": " << s.circle.Summary();
  }
  // Their X through our sections, with the nominal radius as they use it.
  std::vector<Eigen::Vector3d> theirs;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < set.profiles.size(); ++i) {
    const Eigen::Vector3d s = ours.sections[i].centre_in_sensor;
    theirs.push_back(set.profiles[i].base_from_flange * (set.their_flange_from_sensor * s));
    mean += theirs.back();
  }
  mean /= static_cast<double>(theirs.size());
  double sum = 0;
  for (const Eigen::Vector3d& c : theirs) sum += (c - mean).squaredNorm();
  const double their_spread = std::sqrt(sum / static_cast<double>(theirs.size()));
  std::printf("real sphere: ours %s; theirs spread %.3f mm RMS\n", ours.Summary().c_str(),
              their_spread);
  EXPECT_LE(ours.spread_rms_mm, 0.3);
  EXPECT_LT(ours.spread_rms_mm, their_spread);
  EXPECT_LT(ours.loo_max_mm, 1.0);
  // The two calibrations describe one mounting: within 4 sigma of ours (the sigma of the
  // translation vector itself: the covariance's translation block is over the left perturbation,
  // t = Exp(w) t0 + u, so d t = -[t0]x w + u).
  const Eigen::Vector3d t0 = ours.flange_from_sensor.translation();
  Eigen::Matrix<double, 3, 6> j_t;
  j_t << 0, t0.z(), -t0.y(), 1, 0, 0, -t0.z(), 0, t0.x(), 0, 1, 0, t0.y(), -t0.x(), 0, 0, 0, 1;
  const double sigma_t = std::sqrt((j_t * ours.covariance * j_t.transpose()).trace());
  const double dt = (t0 - set.their_flange_from_sensor.translation()).norm();
  // Their rotation differs from ours by 1.2 deg, 4 of our sigma (0.29 deg): printed, not
  // asserted, since theirs is not a ground truth and which one is closer cannot be told here.
  std::printf(
      "translation sigma %.3f mm, theirs differs by %.3f mm; rotation sigma %.3f deg, "
      "theirs differs by %.3f deg\n",
      sigma_t, dt, std::sqrt(ours.covariance.topLeftCorner<3, 3>().trace()) / kDeg,
      RotationDistance(ours.flange_from_sensor, set.their_flange_from_sensor) / kDeg);
  EXPECT_LT(dt, 4 * sigma_t);
}

}  // namespace
}  // namespace lasercell::calib
