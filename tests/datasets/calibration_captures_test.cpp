// Simulation profile: ideal (SimConfig{}); a test that changes a noise field says so.
#include "datasets/calibration_captures.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>

#include "core/error.hpp"
#include "core/io/file_util.hpp"
#include "datasets/rng.hpp"
#include "tests/cli_util.hpp"
#include "tests/sanitizer_scale.hpp"
#include "triangulation/profile_io.hpp"

namespace lasercell::datasets {
namespace {

namespace fs = std::filesystem;
constexpr double kRadToDeg = 180.0 / std::numbers::pi;

TEST(Touches, AreWithinNoiseOfTheTrueSphereTopsAndTheirJointsReachThem) {
  SimConfig config;
  config.touches.sigma_mm = 0.05;
  const CellTruth truth = MakeCellTruth(config);
  const std::vector<Touch> touches = SimulateTouches(config, truth, 77);
  const std::vector<Eigen::Vector3d> centers = config.spheres.CentersInCell();
  ASSERT_EQ(touches.size(), centers.size());
  const Eigen::Isometry3d hb_from_cell = truth.layout.cell_from_handling_base.inverse();
  const Eigen::Isometry3d tool = PointingTool(config.touches);
  double sum_sq = 0;
  for (const Touch& t : touches) {
    const Eigen::Vector3d top =
        hb_from_cell * (centers[t.sphere] + Eigen::Vector3d(0, 0, config.spheres.radius_mm));
    EXPECT_LT((t.true_top_in_handling_base - top).norm(), 1e-9);
    const Eigen::Vector3d err = t.measured_in_handling_base - top;
    // 5 sigma per axis.
    EXPECT_LT(err.cwiseAbs().maxCoeff(), 5 * config.touches.sigma_mm) << t.sphere;
    sum_sq += err.squaredNorm();
    // The recorded joints put the tool tip at the recorded point (handling robot IK).
    ASSERT_TRUE(t.joints_rad.has_value()) << "sphere " << t.sphere << " unreachable";
    std::printf("touch %d: tool tilt %.0f deg, error %.3f mm\n", t.sphere, t.tool_tilt_deg,
                err.norm());
    const Eigen::Vector3d tip =
        (truth.handling_robot.BaseFromFlange(*t.joints_rad) * tool).translation();
    EXPECT_LT((tip - t.measured_in_handling_base).norm(), 1e-3) << t.sphere;
  }
  // Not noise-free: the touches scatter with about the configured sigma.
  EXPECT_GT(std::sqrt(sum_sq / (3.0 * touches.size())), 0.1 * config.touches.sigma_mm);
  // Without noise the touch is the true top.
  config.touches.sigma_mm = 0;
  for (const Touch& t : SimulateTouches(config, truth, 77)) {
    EXPECT_LT((t.measured_in_handling_base - t.true_top_in_handling_base).norm(), 1e-12);
  }
}

// Rotation axes (unit, flange frame) of the relative flange motions between all pose pairs.
std::vector<Eigen::Vector3d> RelativeAxes(const std::vector<Eigen::Isometry3d>& flanges,
                                          double* smallest_angle_deg) {
  std::vector<Eigen::Vector3d> axes;
  *smallest_angle_deg = 1e9;
  for (std::size_t i = 0; i < flanges.size(); ++i) {
    for (std::size_t j = i + 1; j < flanges.size(); ++j) {
      const Eigen::AngleAxisd aa(flanges[i].linear().transpose() * flanges[j].linear());
      *smallest_angle_deg = std::min(*smallest_angle_deg, aa.angle() * kRadToDeg);
      if (aa.angle() > 1e-3) axes.push_back(aa.axis());
    }
  }
  return axes;
}

// Eigenvalues (ascending) of the axes' scatter matrix sum a a^T / n.
Eigen::Vector3d AxisSpread(const std::vector<Eigen::Vector3d>& axes) {
  Eigen::Matrix3d s = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& a : axes) s += a * a.transpose();
  s /= static_cast<double>(axes.size());
  return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(s).eigenvalues();
}

TEST(PoseSweeps, EyeInHandPosesAreDistinctAndRotateAboutSeveralAxes) {
  const SimConfig config;
  const CellTruth truth = MakeCellTruth(config);
  const std::vector<PoseSweep> plans =
      PlanPoseSweeps(config, truth, config.eye_in_hand, 1234, "SimConfig.eye_in_hand");
  ASSERT_EQ(plans.size(), static_cast<std::size_t>(config.eye_in_hand.poses));
  std::vector<Eigen::Isometry3d> flanges;
  std::vector<int> per_sphere(config.spheres.stand_heights_mm.size(), 0);
  const std::vector<double>& offsets = config.eye_in_hand.range_offsets_mm;
  const std::vector<Eigen::Vector3d> centers = config.spheres.CentersInCell();
  for (std::size_t i = 0; i < plans.size(); ++i) {
    const PoseSweep& p = plans[i];
    flanges.push_back(truth.nominal_vision_robot.BaseFromFlange(p.trajectory.joints_rad[1]));
    ++per_sphere[p.sphere];
    EXPECT_GE(p.sphere_columns_at_middle, 30u);
    // Range offsets cycle; the sphere centre then lies that much farther from the emitter
    // along the laser's central ray (the mid waypoint, as commanded).
    EXPECT_EQ(p.range_offset_mm, offsets[i % offsets.size()]);
    const Eigen::Isometry3d& cell_from_sensor = p.commanded_cell_from_sensor[1];
    const Eigen::Vector3d c_in_sensor = cell_from_sensor.inverse() * centers[p.sphere];
    const double along_ray = (c_in_sensor - truth.sensor.laser.origin_in_sensor)
                                 .dot(truth.sensor.laser.center_in_sensor);
    const Eigen::Vector3d crossing_in_sensor(0, 0, config.sensor.standoff_mm);
    const double nominal = (crossing_in_sensor - truth.sensor.laser.origin_in_sensor)
                               .dot(truth.sensor.laser.center_in_sensor);
    EXPECT_NEAR(along_ray - nominal, p.range_offset_mm, 0.5 * config.spheres.radius_mm + 1.0) << i;
  }
  for (int n : per_sphere) {
    EXPECT_EQ(n, config.eye_in_hand.poses / static_cast<int>(per_sphere.size()));
  }
  double smallest_deg = 0;
  const Eigen::Vector3d spread = AxisSpread(RelativeAxes(flanges, &smallest_deg));
  EXPECT_GT(smallest_deg, 2.0);  // every pair of poses differs in orientation
  // Rotation axes span more than one direction: the second-largest eigenvalue of the axis
  // scatter is far from zero (all rotations about one axis would give ~0).
  EXPECT_GT(spread[1], 0.1) << spread.transpose();
  std::printf(
      "eye-in-hand: smallest relative rotation %.1f deg, axis scatter eigenvalues %.3f "
      "%.3f %.3f\n",
      smallest_deg, spread[0], spread[1], spread[2]);

  // The check fails on a degenerate set: rotations only about the vertical.
  PoseSweepOptions one_axis = config.eye_in_hand;
  one_axis.min_tilt_deg = one_axis.max_tilt_deg = 0;
  const std::vector<PoseSweep> flat =
      PlanPoseSweeps(config, truth, one_axis, 1234, "SimConfig.eye_in_hand");
  std::vector<Eigen::Isometry3d> flat_flanges;
  for (const PoseSweep& p : flat) {
    flat_flanges.push_back(truth.nominal_vision_robot.BaseFromFlange(p.trajectory.joints_rad[1]));
  }
  EXPECT_LT(AxisSpread(RelativeAxes(flat_flanges, &smallest_deg))[1], 0.01);
}

TEST(PoseSweeps, ImpossiblePosesAreAnErrorNamingTheField) {
  SimConfig config;
  config.eye_in_hand.sweep_length_mm = 1000;  // far beyond the UR5's reach at the ends
  // A 60 deg tilt also puts the middle out of reach: each of the 60 attempts then runs the IK
  // to its iteration limit from all 16 UR5 seeds (~1 min under ASan). Sanitizer time: only the
  // ends out of reach there (the middle solves, the ends fail: the same error, ~10x sooner).
  if (!test::kSanitizerBuild) {
    config.eye_in_hand.max_tilt_deg = 60;
    config.eye_in_hand.min_tilt_deg = 59;
  }
  const CellTruth truth = MakeCellTruth(config);
  try {
    PlanPoseSweeps(config, truth, config.eye_in_hand, 1, "SimConfig.eye_in_hand");
    ADD_FAILURE() << "no exception";
  } catch (const OptionError& e) {
    EXPECT_NE(std::string(e.what()).find("SimConfig.eye_in_hand"), std::string::npos) << e.what();
  }
}

struct SweepCheck {
  std::size_t on_sphere = 0;      // points within 1e-3 mm of the aimed sphere (true robot)
  double worst_near_true = 0;     // worst |distance - r| of points within 1 mm (true robot)
  double worst_near_nominal = 0;  // same points, posed by the nominal robot
};

// Triangulates noise-free profiles with the recorded joints through the true (and nominal)
// robot and compares with the aimed sphere.
SweepCheck CheckSweep(const triangulation::ProfileSet& set, const CellTruth& truth,
                      const Eigen::Vector3d& center, double radius) {
  SweepCheck r;
  const Eigen::Vector4d plane = truth.sensor.laser.Coefficients();
  for (const triangulation::Profile& p : set.profiles) {
    const Eigen::Isometry3d true_pose = TrueCellFromSensor(truth, p.joints_rad);
    const Eigen::Isometry3d nominal_pose = truth.layout.cell_from_vision_base *
                                           truth.nominal_vision_robot.BaseFromFlange(p.joints_rad) *
                                           truth.vision_flange_from_sensor;
    for (std::uint32_t c = 0; c < set.header.columns; ++c) {
      if (std::isnan(p.row_px[c])) continue;
      const Eigen::Vector3d ray = truth.sensor.camera.Unproject({c, p.row_px[c]});
      const Eigen::Vector3d p_sensor = (-plane[3] / plane.head<3>().dot(ray)) * ray;
      const Eigen::Vector3d p_cell = true_pose * p_sensor;
      const double d = std::abs((p_cell - center).norm() - radius);
      // Near the half sphere (upper hemisphere; the stand below has the sphere's radius).
      if (d > 1.0 || p_cell.z() < center.z() + 1e-6) continue;
      r.worst_near_true = std::max(r.worst_near_true, d);
      r.on_sphere += d < 1e-3;
      r.worst_near_nominal = std::max(
          r.worst_near_nominal, std::abs(((nominal_pose * p_sensor) - center).norm() - radius));
    }
  }
  return r;
}

// Simulation profile: ideal, with the row and intensity noise off and 1 ms exposure jitter.
TEST(PoseSweeps, JointPoseSetIsLargeVariedAndEverySweepSeesItsSphereOnTheTruth) {
  SimConfig config;
  config.seed = 3;
  config.render.row_sigma_px = 0;  // noise-free rows: truth consistency to float precision
  config.render.intensity_sigma = 0;
  config.timing.jitter_s = 1e-3;  // the joints must follow the true exposure times
  config.joint_poses.profiles = 12;
  config.eye_in_hand.profiles = 12;
  config.capture_planes = config.capture_spheres = config.capture_seats = false;
  config.capture_trajectory = config.capture_chessboard_images = false;
  config.capture_laser_line_images = config.write_meshes = false;
  const test::TestDir scratch("calcap_joints");
  const std::string dir = scratch.path().string();
  const SimulationReport report = SimulateCell(config, dir, {}, 2);
  const CellTruth truth = MakeCellTruth(config);
  const std::vector<Eigen::Vector3d> centers = config.spheres.CentersInCell();
  // The sets as recorded: records/sphere_sweeps.yaml lists every sweep and its sphere.
  const std::string records = io::ReadFileBytes(dir + "/records/sphere_sweeps.yaml");
  std::size_t joint_sweeps = 0, eye_sweeps = 0;
  Eigen::Matrix<double, 6, 1> lo = Eigen::Matrix<double, 6, 1>::Constant(1e9);
  Eigen::Matrix<double, 6, 1> hi = -lo;
  double worst_true = 0, worst_nominal = 0;
  std::size_t fewest_on_sphere = SIZE_MAX;
  for (const CaptureReport& c : report.captures) {
    ASSERT_TRUE(c.kind == "joint_poses_sphere" || c.kind == "eye_in_hand_sphere") << c.kind;
    (c.kind == "joint_poses_sphere" ? joint_sweeps : eye_sweeps)++;
    const std::string entry = "profiles_file: " + c.profiles_file + ", aimed_at_sphere: ";
    const std::size_t at = records.find(entry);
    ASSERT_NE(at, std::string::npos) << c.profiles_file;
    const int sphere = std::stoi(records.substr(at + entry.size()));
    const triangulation::ProfileSet set = triangulation::ReadProfiles(dir + "/" + c.profiles_file);
    ASSERT_EQ(set.header.joint_count, 6u);
    EXPECT_EQ(set.header.robot, "vision_robot");
    EXPECT_GT(c.valid_peaks, 0u);
    const SweepCheck check = CheckSweep(set, truth, centers[sphere], config.spheres.radius_mm);
    EXPECT_GT(check.on_sphere, 100u) << c.name << " does not see sphere " << sphere;
    fewest_on_sphere = std::min(fewest_on_sphere, check.on_sphere);
    worst_true = std::max(worst_true, check.worst_near_true);
    worst_nominal = std::max(worst_nominal, check.worst_near_nominal);
    if (c.kind == "joint_poses_sphere") {
      for (int j = 0; j < 6; ++j) {
        lo[j] = std::min(lo[j], set.profiles.front().joints_rad[j]);
        hi[j] = std::max(hi[j], set.profiles.front().joints_rad[j]);
      }
    }
  }
  EXPECT_EQ(joint_sweeps, 50u);
  EXPECT_EQ(eye_sweeps, static_cast<std::size_t>(SimConfig{}.eye_in_hand.poses));
  // Points from noise-free rows posed by the TRUE robot at the recorded joints lie on the true
  // sphere to the float32 precision of the rows; the nominal robot misses by its joint offsets.
  EXPECT_LT(worst_true, 1e-3);
  EXPECT_GT(worst_nominal, 0.05);
  // The poses spread over the workspace: every joint moves through a wide range.
  const Eigen::Matrix<double, 6, 1> range_deg = (hi - lo) * kRadToDeg;
  for (int j = 0; j < 6; ++j) EXPECT_GT(range_deg[j], 20.0) << "joint " << j + 1;
  std::printf(
      "joint poses: %zu sweeps, joint ranges (deg) %s, fewest sphere points %zu, worst "
      "true %.2e mm, worst nominal %.3f mm\n",
      joint_sweeps,
      [&] {
        std::ostringstream o;
        o.precision(3);
        o << range_deg.transpose();
        return o.str();
      }()
          .c_str(),
      fewest_on_sphere, worst_true, worst_nominal);
  // The touches were recorded without truth; the truth file has the centres.
  const std::string touches = io::ReadFileBytes(dir + "/records/touches.yaml");
  EXPECT_NE(touches.find("point_in_handling_base"), std::string::npos);
  EXPECT_EQ(touches.find("center"), std::string::npos);
  EXPECT_EQ(touches.find("true"), std::string::npos);
  EXPECT_NE(io::ReadFileBytes(dir + "/truth/touches.yaml").find("sphere_center_in_handling_base"),
            std::string::npos);
}

// Eye-in-hand chessboard images: the recorded joints, posed by the TRUE robot chain, put the
// camera where the truth says, and the true corner pixels are the board's projection through it.
TEST(HandEyeImages, TruthIsTheTrueChainAndPosesRotateAboutSeveralAxes) {
  const SimConfig config;
  const CellTruth truth = MakeCellTruth(config);
  ChessboardTarget target = config.chessboard;
  const HandEyeImageSet set = PlanHandEyeImages(config, truth, target, 99);
  ASSERT_EQ(set.images.size(), 15u);
  const std::vector<Eigen::Vector3d> corners = target.CornersInTarget();
  std::vector<Eigen::Isometry3d> flanges;
  double worst_px = 0, worst_commanded_mm = 0, largest_offset_effect_px = 0;
  for (const HandEyeImage& im : set.images) {
    ASSERT_EQ(im.joints_rad.size(), 6u);
    const Eigen::Isometry3d base_from_flange =
        truth.true_vision_robot.BaseFromFlange(im.joints_rad);
    flanges.push_back(base_from_flange);
    const Eigen::Isometry3d cell_from_camera =
        truth.layout.cell_from_vision_base * base_from_flange * truth.vision_flange_from_sensor;
    const Eigen::Isometry3d nominal_cell_from_camera =
        truth.layout.cell_from_vision_base *
        truth.nominal_vision_robot.BaseFromFlange(im.joints_rad) * truth.vision_flange_from_sensor;
    // The joints are the nominal IK of the planned pose.
    worst_commanded_mm = std::max(
        worst_commanded_mm,
        (nominal_cell_from_camera.matrix() - im.commanded_cell_from_camera.matrix()).norm());
    ASSERT_EQ(im.corners_px.size(), corners.size());
    for (std::size_t k = 0; k < corners.size(); ++k) {
      const Eigen::Vector3d p_in_cell = set.cell_from_board * corners[k];
      const auto q = ProjectInView(truth.sensor.camera, cell_from_camera.inverse() * p_in_cell);
      const auto q_nominal =
          ProjectInView(truth.sensor.camera, nominal_cell_from_camera.inverse() * p_in_cell);
      ASSERT_TRUE(q && q_nominal);
      worst_px = std::max(worst_px, (*q - im.corners_px[k]).norm());
      largest_offset_effect_px =
          std::max(largest_offset_effect_px, (*q_nominal - im.corners_px[k]).norm());
      EXPECT_GT(q->x(), 25.0);
      EXPECT_LT(q->y(), truth.sensor.camera.height_px() - 26.0);
    }
    const Eigen::Isometry3d camera_from_board = cell_from_camera.inverse() * set.cell_from_board;
    EXPECT_LT((camera_from_board.matrix() - im.camera_from_board.matrix()).norm(), 1e-9);
  }
  EXPECT_LT(worst_px, 1e-6);
  EXPECT_LT(worst_commanded_mm, 1e-6);
  // The joint offsets move the camera: the nominal chain misses the true corners.
  EXPECT_GT(largest_offset_effect_px, 1.0);
  double smallest_deg = 0;
  const Eigen::Vector3d spread = AxisSpread(RelativeAxes(flanges, &smallest_deg));
  EXPECT_GT(smallest_deg, 2.0);
  EXPECT_GT(spread[1], 0.1) << spread.transpose();
  std::printf(
      "hand-eye images: truth chain %.1e px, commanded %.1e, nominal chain off by up to %.1f px, "
      "smallest relative rotation %.1f deg, axis scatter eigenvalues %.3f %.3f %.3f\n",
      worst_px, worst_commanded_mm, largest_offset_effect_px, smallest_deg, spread[0], spread[1],
      spread[2]);
}

// The capture set: images, records (joints, no truth), truth; OpenCV finds the board.
TEST(HandEyeImages, CaptureWritesRecordsAndTruth) {
  SimConfig config;
  config.capture_planes = config.capture_spheres = config.capture_seats = false;
  config.capture_trajectory = config.capture_chessboard_images = false;
  config.capture_laser_line_images = config.write_meshes = false;
  config.capture_touches = config.capture_eye_in_hand = config.capture_joint_poses = false;
  config.capture_hand_eye_images = true;
  config.hand_eye_images.images = 3;  // small: the renderer is slow under ASan
  const test::TestDir scratch("calcap_hand_eye");
  const std::string dir = scratch.path().string();
  SimulateCell(config, dir, {}, 2);
  const std::string records = io::ReadFileBytes(dir + "/records/hand_eye_images.yaml");
  const std::string truth = io::ReadFileBytes(dir + "/truth/hand_eye_images.yaml");
  std::size_t joints = 0;
  for (std::size_t at = records.find("joints_rad: ["); at != std::string::npos;
       at = records.find("joints_rad: [", at + 1)) {
    ++joints;
  }
  EXPECT_EQ(joints, 3u);
  EXPECT_EQ(records.find("true"), std::string::npos);
  EXPECT_EQ(records.find("camera_from_board"), std::string::npos);
  EXPECT_NE(truth.find("vision_base_from_board"), std::string::npos);
  EXPECT_NE(truth.find("camera_from_board"), std::string::npos);
  EXPECT_NE(truth.find("corners_px"), std::string::npos);
  const std::string png = io::ReadFileBytes(dir + "/images/hand_eye_000.png");
  const cv::Mat image =
      cv::imdecode(cv::Mat(1, static_cast<int>(png.size()), CV_8UC1, const_cast<char*>(png.data())),
                   cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(image.empty());
  std::vector<cv::Point2f> found;
  EXPECT_TRUE(cv::findChessboardCornersSB(
      image, cv::Size(config.chessboard.board.cols, config.chessboard.board.rows), found));
}

}  // namespace
}  // namespace lasercell::datasets
