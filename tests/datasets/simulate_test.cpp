// Simulation profile: ideal (SimConfig{}, or SmallConfig()'s smaller capture set); a test that
// changes a noise field says so.
#include "datasets/simulate.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>

#include "calib/laser_plane_heights_record.hpp"
#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/io/file_util.hpp"
#include "core/io/mesh_io.hpp"
#include "core/io/point_cloud_io.hpp"
#include "datasets/robots.hpp"
#include "datasets/sim_config.hpp"
#include "datasets/simulate_records.hpp"
#include "tests/cli_util.hpp"
#include "tests/sanitizer_scale.hpp"
#include "triangulation/linear_sweep.hpp"
#include "triangulation/profile_io.hpp"

namespace lasercell::datasets {
namespace {

namespace fs = std::filesystem;
constexpr double kDeg = std::numbers::pi / 180.0;

// Message of the OptionError `f` throws ("" when none).
template <typename F>
std::string OptionErrorMessage(F&& f) {
  try {
    f();
  } catch (const OptionError& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("wrong exception type: ") + e.what();
  }
  return "no exception";
}

std::string ConfigError(const std::string& yaml) {
  return OptionErrorMessage([&] { SimConfigFromYaml(yaml, "sim.yaml").Check(); });
}

SimConfig SmallConfig() {
  SimConfig c;
  c.seed = 5;
  c.timing.profiles = 12;
  c.timing.rate_hz = 4;  // spread the 12 profiles over the whole sweep
  c.render.fan_rays = 400;
  c.plane_heights_mm = {150, 300};
  c.seat_count = 2;
  c.chessboard_images = 2;
  c.eye_in_hand.poses = 3;
  c.eye_in_hand.profiles = 8;
  c.joint_poses.poses = 4;
  c.joint_poses.profiles = 8;
  return c;
}

// Sanitizer time: under ASan the capture-set tests use a 512 x 512 camera of the same field of
// view, a quarter of the pixels to render (the camera images are most of a set's time); every
// capture runs the same code.
constexpr std::uint32_t kSetColumns = test::kSanitizerBuild ? 512 : 1024;

void ShrinkCameraUnderSanitizer(SimConfig& c) {
  if (!test::kSanitizerBuild) return;
  CameraIntrinsics& k = c.sensor.camera;
  k.width_px = k.height_px = static_cast<int>(kSetColumns);
  k.fx_px /= 2;
  k.fy_px /= 2;
  k.cx_px /= 2;
  k.cy_px /= 2;
}

TEST(SimConfig, DefaultsAreValidAndYamlRoundTrips) {
  SimConfig c;
  EXPECT_NO_THROW(c.Check());
  c.joint_offsets_deg = std::vector<double>{0.1, -0.2, 0.05, 0, 0.3, -0.01};
  c.render.row_sigma_px = 0.1234567890123;
  c.render.speckle_sigma_px = 0.075;
  c.render.speckle_correlation_px = 2.5;
  c.render.speckle_intensity_sigma = 0.3;
  c.hand_eye_images.distance_mm = 812.5;
  c.capture_hand_eye_images = true;
  c.spheres.positions_xy_mm[2] = {111.5, -3.25};
  c.touches.sigma_mm = 0.03;
  c.joint_poses.poses = 60;
  c.eye_in_hand.max_roll_deg = 45.5;
  c.capture_joint_poses = false;
  const std::string text = SimConfigToYaml(c);
  const SimConfig back = SimConfigFromYaml(text, "roundtrip.yaml");
  EXPECT_EQ(SimConfigToYaml(back), text);
  EXPECT_EQ(back.render.row_sigma_px, c.render.row_sigma_px);
  EXPECT_EQ(back.render.speckle_sigma_px, 0.075);
  EXPECT_EQ(back.render.speckle_correlation_px, 2.5);
  EXPECT_EQ(back.render.speckle_intensity_sigma, 0.3);
  EXPECT_EQ(back.hand_eye_images.distance_mm, 812.5);
  EXPECT_TRUE(back.capture_hand_eye_images);
  EXPECT_EQ(back.joint_poses.poses, 60);
  EXPECT_EQ(back.eye_in_hand.max_roll_deg, 45.5);
  EXPECT_FALSE(back.capture_joint_poses);
  ASSERT_TRUE(back.joint_offsets_deg.has_value());
  EXPECT_EQ(*back.joint_offsets_deg, *c.joint_offsets_deg);
  // An empty file is the default config.
  EXPECT_EQ(SimConfigToYaml(SimConfigFromYaml("", "empty.yaml")), SimConfigToYaml(SimConfig{}));
  // A partial file changes only what it lists.
  const SimConfig partial = SimConfigFromYaml("seed: 9\nrender: {row_sigma_px: 0.2}\n", "p.yaml");
  EXPECT_EQ(partial.seed, 9u);
  EXPECT_EQ(partial.render.row_sigma_px, 0.2);
  EXPECT_EQ(partial.render.fan_rays, SimConfig{}.render.fan_rays);
}

TEST(SimConfig, ErrorsNameTheField) {
  // Unknown fields, at any depth.
  std::string e = ConfigError("sensor:\n  camera: {fx: 1000}\n");
  EXPECT_NE(e.find("sim.yaml"), std::string::npos) << e;
  EXPECT_NE(e.find("unknown field 'sensor.camera.fx'"), std::string::npos) << e;
  e = ConfigError("sede: 3\n");
  EXPECT_NE(e.find("unknown field 'sede'"), std::string::npos) << e;
  // Wrong types and list lengths.
  e = ConfigError("render: {row_sigma_px: abc}\n");
  EXPECT_NE(e.find("'render.row_sigma_px'"), std::string::npos) << e;
  e = ConfigError("sensor: {camera: {distortion: [1, 2]}}\n");
  EXPECT_NE(e.find("'sensor.camera.distortion'"), std::string::npos) << e;
  EXPECT_NE(e.find("exactly 8"), std::string::npos) << e;
  e = ConfigError("format: something.else\n");
  EXPECT_NE(e.find("'format'"), std::string::npos) << e;
  e = ConfigError("version: 2\n");
  EXPECT_NE(e.find("'version'"), std::string::npos) << e;
  // Negative sizes and out-of-range values.
  e = ConfigError("planes: {size_mm: [-800, 600]}\n");
  EXPECT_NE(e.find("SimConfig.planes.size_mm"), std::string::npos) << e;
  e = ConfigError("sweep: {length_mm: -5}\n");
  EXPECT_NE(e.find("SimConfig.sweep.length_mm"), std::string::npos) << e;
  e = ConfigError("spheres: {radius_mm: -25}\n");
  EXPECT_NE(e.find("SimConfig.spheres.radius_mm"), std::string::npos) << e;
  e = ConfigError("seats: {shape: {thickness_mm: 0}}\n");
  EXPECT_NE(e.find("SimConfig.seats.shape.thickness_mm"), std::string::npos) << e;
  e = ConfigError("sensor: {camera: {fx_px: -1000}}\n");
  EXPECT_NE(e.find("SimConfig.sensor.camera.fx_px"), std::string::npos) << e;
  e = ConfigError("render: {dropout_probability: 1.5}\n");
  EXPECT_NE(e.find("SimConfig.render.dropout_probability"), std::string::npos) << e;
  e = ConfigError("timing: {profiles: 0}\n");
  EXPECT_NE(e.find("SimConfig.timing.profiles"), std::string::npos) << e;
  e = ConfigError("vision_robot: {joint_offsets_deg: [1, 2, 3]}\n");
  EXPECT_NE(e.find("SimConfig.vision_robot.joint_offsets_deg"), std::string::npos) << e;
  // Robot-side calibration captures.
  e = ConfigError("touches: {sigma_mm: -0.1}\n");
  EXPECT_NE(e.find("SimConfig.touches.sigma_mm"), std::string::npos) << e;
  e = ConfigError("touches: {sigma: 0.1}\n");
  EXPECT_NE(e.find("unknown field 'touches.sigma'"), std::string::npos) << e;
  e = ConfigError("eye_in_hand: {poses: 0}\n");
  EXPECT_NE(e.find("SimConfig.eye_in_hand.poses"), std::string::npos) << e;
  e = ConfigError("joint_poses: {min_tilt_deg: 30, max_tilt_deg: 10}\n");
  EXPECT_NE(e.find("SimConfig.joint_poses.max_tilt_deg"), std::string::npos) << e;
  e = ConfigError("joint_poses: {sweep_length_mm: -80}\n");
  EXPECT_NE(e.find("SimConfig.joint_poses.sweep_length_mm"), std::string::npos) << e;
  e = ConfigError("eye_in_hand: {profile: 8}\n");
  EXPECT_NE(e.find("unknown field 'eye_in_hand.profile'"), std::string::npos) << e;
  e = ConfigError("hand_eye_images: {images: 0}\n");
  EXPECT_NE(e.find("SimConfig.hand_eye_images.images"), std::string::npos) << e;
  e = ConfigError("hand_eye_images: {min_tilt_deg: 30, max_tilt_deg: 20}\n");
  EXPECT_NE(e.find("SimConfig.hand_eye_images.max_tilt_deg"), std::string::npos) << e;
  e = ConfigError("hand_eye_images: {distance: 500}\n");
  EXPECT_NE(e.find("unknown field 'hand_eye_images.distance'"), std::string::npos) << e;
  e = ConfigError("render: {speckle_sigma_px: -0.1}\n");
  EXPECT_NE(e.find("SimConfig.render.speckle_sigma_px"), std::string::npos) << e;
  e = ConfigError("render: {speckle_correlation_px: -1}\n");
  EXPECT_NE(e.find("SimConfig.render.speckle_correlation_px"), std::string::npos) << e;
  e = ConfigError("render: {speckle_intensity_sigma: -0.5}\n");
  EXPECT_NE(e.find("SimConfig.render.speckle_intensity_sigma"), std::string::npos) << e;
  e = ConfigError("render: {speckle_px: 0.1}\n");
  EXPECT_NE(e.find("unknown field 'render.speckle_px'"), std::string::npos) << e;
  e = ConfigError("render: {reflection_probability: 2}\n");
  EXPECT_NE(e.find("SimConfig.render.reflection_probability"), std::string::npos) << e;
  e = ConfigError("captures: {joint_pose: true}\n");
  EXPECT_NE(e.find("unknown field 'captures.joint_pose'"), std::string::npos) << e;
  // A sensor that sees nothing of the target.
  e = ConfigError("planes: {heights_mm: [150, 2000]}\n");
  EXPECT_NE(e.find("SimConfig.planes.heights_mm[1]"), std::string::npos) << e;
  EXPECT_NE(e.find("sees nothing"), std::string::npos) << e;
  e = ConfigError("sweep: {measuring_height_mm: 5000}\n");
  EXPECT_NE(e.find("sees nothing"), std::string::npos) << e;
  EXPECT_NE(e.find("sweep.measuring_height_mm"), std::string::npos) << e;
  e = ConfigError("spheres: {stand_heights_mm: [40, 80, 120, 1600]}\n");
  EXPECT_NE(e.find("SimConfig.spheres.stand_heights_mm[3]"), std::string::npos) << e;
  // Not YAML at all.
  e = ConfigError("seed: [1, 2\n");
  EXPECT_NE(e.find("sim.yaml"), std::string::npos) << e;
}

TEST(SimConfig, LoadingAMissingFileIsAFileError) {
  const test::TestDir empty("sim_missing");
  EXPECT_THROW(LoadSimConfig(empty.File("sim.yaml")), FileError);
}

TEST(SeatPlacement, DrawsCoverTableOneRangesAndRestOnThePallet) {
  const ChairSeat seat = MakeChairSeat();
  const SeatPlacementOptions o;
  double max_shift = 0, max_tilt = 0, max_yaw = 0;
  for (int i = 0; i < 500; ++i) {
    const SeatPlacement p = DrawSeatPlacement(o, seat, 77, i);
    ASSERT_LE(std::abs(p.shift_x_mm), 100.0);
    ASSERT_LE(std::abs(p.shift_y_mm), 100.0);
    ASSERT_LE(std::abs(p.tilt_x_rad), 25 * kDeg);
    ASSERT_LE(std::abs(p.tilt_y_rad), 25 * kDeg);
    ASSERT_LE(std::abs(p.yaw_rad), 180 * kDeg);
    max_shift = std::max({max_shift, std::abs(p.shift_x_mm), std::abs(p.shift_y_mm)});
    max_tilt = std::max({max_tilt, std::abs(p.tilt_x_rad), std::abs(p.tilt_y_rad)});
    max_yaw = std::max(max_yaw, std::abs(p.yaw_rad));
    // The pose is built as documented and the lowest vertex touches the deck.
    const Eigen::Matrix3d r = (Eigen::AngleAxisd(p.tilt_y_rad, Eigen::Vector3d::UnitY()) *
                               Eigen::AngleAxisd(p.tilt_x_rad, Eigen::Vector3d::UnitX()) *
                               Eigen::AngleAxisd(p.yaw_rad, Eigen::Vector3d::UnitZ()))
                                  .toRotationMatrix();
    ASSERT_LT((p.cell_from_part.linear() - r).norm(), 1e-12);
    if (i % 10 == 0) {
      double min_z = 1e9;
      for (const auto& v : seat.part.mesh.vertices.positions) {
        min_z = std::min(min_z, (p.cell_from_part * v).z());
      }
      ASSERT_NEAR(min_z, kPalletHeightMm, 1e-9);
    }
  }
  // The draws span the ranges (uniform: the max of 1000 draws is within 1 % of the bound).
  EXPECT_GT(max_shift, 97.0);
  EXPECT_GT(max_tilt, 24.0 * kDeg);
  EXPECT_GT(max_yaw, 175.0 * kDeg);
  // Same seed and index -> same placement; other index or seed -> another.
  EXPECT_TRUE(DrawSeatPlacement(o, seat, 77, 3)
                  .cell_from_part.isApprox(DrawSeatPlacement(o, seat, 77, 3).cell_from_part, 0));
  EXPECT_FALSE(DrawSeatPlacement(o, seat, 77, 3)
                   .cell_from_part.isApprox(DrawSeatPlacement(o, seat, 78, 3).cell_from_part));
}

TEST(CellTruth, RobotTrajectoryIsReachableAndTheTrueRobotMissesIt) {
  const SimConfig config;
  const CellTruth truth = MakeCellTruth(config);
  // Joint offsets drawn with sigma 0.1 deg.
  ASSERT_EQ(truth.joint_offsets_rad.size(), 6u);
  double norm = 0;
  for (double q : truth.joint_offsets_rad) norm += q * q;
  EXPECT_GT(std::sqrt(norm), 1e-4);
  EXPECT_LT(std::sqrt(norm), 6 * 0.1 * kDeg * std::sqrt(6.0));
  const JointTrajectory traj = MakeArcTrajectory(config, truth);
  ASSERT_EQ(static_cast<int>(traj.joints_rad.size()), config.arc_waypoints);
  const Eigen::Isometry3d& cell_from_base = truth.layout.cell_from_vision_base;
  double worst_true_miss = 0;
  for (std::size_t k = 0; k < traj.joints_rad.size(); ++k) {
    const auto& q = traj.joints_rad[k];
    const Eigen::Isometry3d nominal = cell_from_base *
                                      truth.nominal_vision_robot.BaseFromFlange(q) *
                                      truth.vision_flange_from_sensor;
    const Eigen::Isometry3d actual = cell_from_base * truth.true_vision_robot.BaseFromFlange(q) *
                                     truth.vision_flange_from_sensor;
    // The nominal pose looks straight down with the laser crossing at the measuring height.
    const Eigen::Vector3d central = nominal.linear() * truth.sensor.laser.center_in_sensor;
    EXPECT_NEAR(central.z(), -1.0, 1e-9);
    const Eigen::Vector3d crossing = nominal * Eigen::Vector3d(0, 0, config.sensor.standoff_mm);
    EXPECT_NEAR(crossing.z(), config.measuring_height_mm, 1e-6);
    EXPECT_NEAR((crossing.head<2>() - config.sweep_center_xy_mm).norm(), config.arc_radius_mm,
                1e-6);
    worst_true_miss =
        std::max(worst_true_miss, (actual.translation() - nominal.translation()).norm());
  }
  EXPECT_GT(worst_true_miss, 0.1);  // joint offsets of ~0.1 deg move the sensor by ~mm
  // Every joint stays inside the UR5's +-2 pi range.
  for (const auto& q : traj.joints_rad) {
    for (double v : q) EXPECT_LE(std::abs(v), 2 * std::numbers::pi);
  }
  // Interpolation is linear and clamped.
  const auto mid = traj.At(0.5 * (traj.times_s[0] + traj.times_s[1]));
  EXPECT_NEAR(mid[0], 0.5 * (traj.joints_rad[0][0] + traj.joints_rad[1][0]), 1e-12);
  EXPECT_EQ(traj.At(-1.0), traj.joints_rad.front());
  EXPECT_EQ(traj.At(1e9), traj.joints_rad.back());
}

// Simulation profile: ideal, plus DH length errors (drawn, then explicit).
TEST(CellTruth, DhLengthErrorsAreAppliedAndLeaveTheJointOffsetDrawsUnchanged) {
  SimConfig config;
  const CellTruth plain = MakeCellTruth(config);
  EXPECT_EQ(plain.dh_a_errors_mm, std::vector<double>(6, 0.0));
  config.dh_length_sigma_mm = 0.5;
  const CellTruth drawn = MakeCellTruth(config);
  EXPECT_EQ(drawn.joint_offsets_rad, plain.joint_offsets_rad);
  double rms = 0;
  for (int i = 0; i < 6; ++i) {
    rms += drawn.dh_a_errors_mm[i] * drawn.dh_a_errors_mm[i] +
           drawn.dh_d_errors_mm[i] * drawn.dh_d_errors_mm[i];
    EXPECT_DOUBLE_EQ(drawn.true_vision_robot.joints()[i].a_mm,
                     plain.nominal_vision_robot.joints()[i].a_mm + drawn.dh_a_errors_mm[i]);
    EXPECT_DOUBLE_EQ(drawn.true_vision_robot.joints()[i].d_mm,
                     plain.nominal_vision_robot.joints()[i].d_mm + drawn.dh_d_errors_mm[i]);
  }
  EXPECT_GT(std::sqrt(rms / 12), 0.1);
  EXPECT_LT(std::sqrt(rms / 12), 1.5);
  // Explicit values win over the draw, and round-trip through YAML.
  config.dh_a_errors_mm = std::vector<double>{0, 0.2, -0.3, 0, 0, 0};
  const CellTruth explicit_truth = MakeCellTruth(config);
  EXPECT_EQ(explicit_truth.dh_a_errors_mm, *config.dh_a_errors_mm);
  EXPECT_EQ(SimConfigToYaml(SimConfigFromYaml(SimConfigToYaml(config), "x.yaml")),
            SimConfigToYaml(config));
  EXPECT_NE(ConfigError("vision_robot: {dh_d_errors_mm: [1, 2]}\n")
                .find("SimConfig.vision_robot.dh_d_errors_mm must list 6 values"),
            std::string::npos);
  EXPECT_NE(ConfigError("vision_robot: {dh_length_sigma_mm: -1}\n")
                .find("SimConfig.vision_robot.dh_length_sigma_mm"),
            std::string::npos);
}

// Simulation profile: ideal, plus specular ghosts and speckle (their draws are compared too).
TEST(Simulate, SameSeedGivesIdenticalBytesForAnyThreadCount) {
  SimConfig config = SmallConfig();
  config.render.reflection_probability = 0.5;  // ghosts draw random numbers too
  config.render.speckle_sigma_px = 0.08;       // and speckle
  config.render.speckle_intensity_sigma = 0.2;
  ShrinkCameraUnderSanitizer(config);
  const test::TestDir scratch("sim_seeds");
  const std::string a = scratch.File("a"), b = scratch.File("b"), c = scratch.File("c");
  const SimulationReport ra = SimulateCell(config, a, {}, 1);
  const SimulationReport rb = SimulateCell(config, b, {}, 2);
  ASSERT_EQ(ra.files, rb.files);
  // The robot-side calibration captures are part of the comparison.
  for (const char* f :
       {"records/touches.yaml", "records/sphere_sweeps.yaml", "truth/touches.yaml",
        "profiles/eye_in_hand_02.lcp", "profiles/joint_pose_003.lcp", "models/seat.stl"}) {
    EXPECT_NE(std::find(ra.files.begin(), ra.files.end(), f), ra.files.end()) << f;
  }
  for (const std::string& f : ra.files) {
    EXPECT_EQ(io::ReadFileBytes(a + "/" + f), io::ReadFileBytes(b + "/" + f)) << f;
  }
  config.seed = 6;
  if (test::kSanitizerBuild) {
    // Sanitizer time: only the seats, the one file compared, for the other seed.
    config.capture_planes = config.capture_spheres = config.capture_trajectory = false;
    config.capture_chessboard_images = config.capture_laser_line_images = false;
    config.write_meshes = config.capture_touches = config.capture_eye_in_hand = false;
    config.capture_joint_poses = false;
  }
  const SimulationReport rc = SimulateCell(config, c, {}, 2);
  EXPECT_NE(io::ReadFileBytes(a + "/profiles/seat_000.lcp"),
            io::ReadFileBytes(c + "/profiles/seat_000.lcp"));
}

TEST(Simulate, RecordsTheLinearAxisAndThePlateHeightsWithoutTruth) {
  SimConfig config = SmallConfig();
  config.capture_seats = config.capture_trajectory = config.capture_eye_in_hand = false;
  config.capture_joint_poses = config.capture_chessboard_images = false;
  config.capture_laser_line_images = config.write_meshes = false;
  const test::TestDir scratch("sim_records");
  const std::string dir = scratch.path().string();
  SimulateCell(config, dir, {}, 2);
  const CellTruth truth = MakeCellTruth(config);
  const LinearSweep sweep = MakeLinearSweep(config, truth.sensor);
  // The simulator's file read through triangulation's reader of the linear sweep motion.
  const triangulation::LinearSweepRecord linear =
      triangulation::ReadLinearSweepRecord(dir + "/records/linear_sweep.yaml");
  EXPECT_EQ(linear.t0_ns, config.timing.start_ns);
  // The sensor-frame velocity moves the sensor like the true sweep does.
  const Eigen::Vector3d v_cell =
      sweep.cell_from_sensor_start.linear() * linear.velocity_mm_s_in_sensor;
  EXPECT_LT((v_cell - sweep.velocity_mm_s).norm(), 1e-9);
  EXPECT_NEAR(linear.speed_mm_s, sweep.velocity_mm_s.norm(), 1e-9);
  EXPECT_EQ(linear.Options().velocity_mm_s, linear.velocity_mm_s_in_sensor);
  // truth/sensor.yaml read back beside its writer: the true laser plane, exactly.
  const SimSensorTruth sensor = ReadSensorTruth(dir + "/truth/sensor.yaml");
  EXPECT_EQ(sensor.LaserPlane(), truth.sensor.laser.Coefficients());
  ASSERT_TRUE(sensor.laser_point_in_sensor_mm.has_value());
  EXPECT_EQ(*sensor.laser_point_in_sensor_mm, truth.sensor.laser.origin_in_sensor);
  // records/planes.yaml through its reader.
  const calib::PlaneHeightsRecord planes =
      calib::ReadPlaneHeightsYaml(dir + "/records/planes.yaml");
  const std::vector<double>& heights = planes.heights_mm;
  const Eigen::Vector3d& normal = planes.plate_normal_in_sensor;
  EXPECT_EQ(heights, config.plane_heights_mm);
  EXPECT_NEAR(normal.norm(), 1.0, 1e-12);
  // It points up, towards the sensor (which looks down).
  EXPECT_GT((sweep.cell_from_sensor_start.linear() * normal).z(), 0.999999);
}

TEST(Simulate, CaptureSetIsCompleteAndConsistent) {
  const SimConfig config = [] {
    SimConfig c = SmallConfig();
    c.timing.timestamp_noise_s = 50e-6;  // captures.yaml then lists the true exposure times
    ShrinkCameraUnderSanitizer(c);
    return c;
  }();
  const test::TestDir scratch("sim_set");
  const std::string dir = scratch.path().string();
  std::vector<std::string> stages;
  const SimulationReport report = SimulateCell(
      config, dir, [&](std::string_view stage, double) { stages.emplace_back(stage); });
  // 2 planes, spheres, 2 seats, 1 trajectory sweep, 3 eye-in-hand and 4 joint-pose sweeps.
  ASSERT_EQ(report.captures.size(), 13u);
  EXPECT_FALSE(stages.empty());
  for (const CaptureReport& c : report.captures) {
    const triangulation::ProfileSet set = triangulation::ReadProfiles(dir + "/" + c.profiles_file);
    const bool pose_sweep = c.kind == "eye_in_hand_sphere" || c.kind == "joint_poses_sphere";
    const std::size_t profiles = pose_sweep ? 8u : 12u;
    EXPECT_EQ(set.profiles.size(), profiles) << c.name;
    EXPECT_EQ(set.header.columns, kSetColumns);
    EXPECT_GT(c.valid_peaks, profiles * 100u) << c.name;
    EXPECT_NE(set.header.metadata.find("capture: " + c.name), std::string::npos);
    if (c.kind == "seat_trajectory" || pose_sweep) {
      EXPECT_EQ(set.header.joint_count, 6u);
      EXPECT_EQ(set.header.robot, "vision_robot");
    } else {
      EXPECT_EQ(set.header.joint_count, 0u);
    }
  }
  // The true camera reads back through mrcal exactly.
  const CameraIntrinsics cam = CameraIntrinsicsFromMrcalText(
      io::ReadFileBytes(dir + "/truth/camera.cameramodel"), "camera.cameramodel");
  EXPECT_EQ(cam.MrcalVector(), config.sensor.camera.MrcalVector());
  // The true frame graph: hole centre of seat_001 in handling_base matches captures.yaml's part
  // pose, and the true robot carries the joint offsets.
  const FrameGraph graph = LoadFrameGraph(dir + "/truth/cell.yaml");
  const CellTruth truth = MakeCellTruth(config);
  const SeatPlacement p1 = DrawSeatPlacement(config.seat_placement, truth.seat, config.seed, 1);
  const Eigen::Isometry3d hb_from_part = graph.Transform("handling_base", "seat_001");
  const Eigen::Isometry3d expected =
      truth.layout.cell_from_handling_base.inverse() * p1.cell_from_part;
  EXPECT_LT((hb_from_part.matrix() - expected.matrix()).norm(), 1e-9);
  const auto& robot = dynamic_cast<const DhChain&>(graph.Robot("vision_robot"));
  for (int j = 0; j < 6; ++j) {
    EXPECT_EQ(robot.joints()[j].joint_offset_rad, truth.joint_offsets_rad[j]);
  }
  const Eigen::Isometry3d flange_from_sensor = graph.Transform("vision_flange", "sensor");
  EXPECT_LT((flange_from_sensor.matrix() - truth.vision_flange_from_sensor.matrix()).norm(), 1e-12);
  // captures.yaml names every capture and the hole centres.
  const std::string captures = io::ReadFileBytes(dir + "/truth/captures.yaml");
  for (const CaptureReport& c : report.captures) {
    EXPECT_NE(captures.find("name: " + c.name), std::string::npos) << c.name;
  }
  EXPECT_NE(captures.find("hole_center_in_handling_base"), std::string::npos);
  // ... and is YAML a reader takes: every capture's true exposure times sit in its sweep.
  const YAML::Node parsed = YAML::Load(captures);
  std::size_t with_exposures = 0;
  for (const YAML::Node& c : parsed["captures"]) {
    const YAML::Node times = c["sweep"]["true_exposure_ns"];
    ASSERT_TRUE(times.IsSequence()) << c["name"].as<std::string>();
    const std::string kind = c["kind"].as<std::string>();
    const bool pose_sweep = kind == "eye_in_hand_sphere" || kind == "joint_poses_sphere";
    with_exposures += times.size() == (pose_sweep ? 8u : 12u);
  }
  EXPECT_EQ(with_exposures, report.captures.size());
  // Images and their truth.
  for (const char* f :
       {"records/touches.yaml", "records/sphere_sweeps.yaml", "truth/touches.yaml",
        "images/chessboard_000.png", "images/chessboard_001.png", "images/laser_line_plane.png",
        "images/laser_line_chessboard.png", "truth/chessboard.yaml", "truth/laser_lines.yaml"}) {
    EXPECT_TRUE(fs::exists(dir + "/" + f)) << f;
  }
  EXPECT_NE(io::ReadFileBytes(dir + "/truth/chessboard.yaml").find("corners_px"),
            std::string::npos);
  // The seat model is a readable PLY mesh with the seat's triangles.
  const TriangleMesh seat = io::ReadPlyMesh(dir + "/models/seat.ply");
  EXPECT_EQ(seat.faces.size(), truth.seat.part.mesh.faces.size());
  // ... and the same mesh as binary STL.
  EXPECT_EQ(io::ReadStlMesh(dir + "/models/seat.stl").faces.size(),
            truth.seat.part.mesh.faces.size());
  // The config written back reproduces the same config.
  EXPECT_EQ(SimConfigToYaml(LoadSimConfig(dir + "/truth/sim_config.yaml")),
            SimConfigToYaml(config));
}

TEST(Simulate, ASensorThatSeesNothingIsAnErrorNotAnEmptySet) {
  SimConfig config = SmallConfig();
  config.sweep_center_xy_mm = {1900, 1900};  // sweeping over the floor's corner: plates missed
  config.capture_spheres = config.capture_seats = config.capture_trajectory = false;
  config.capture_eye_in_hand = config.capture_joint_poses = false;
  config.albedo.floor = 0.0;  // and the floor is black
  const test::TestDir scratch("sim_nothing");
  const std::string dir = scratch.path().string();
  const std::string e = OptionErrorMessage([&] { SimulateCell(config, dir); });
  EXPECT_NE(e.find("capture 'plane_0'"), std::string::npos) << e;
  EXPECT_NE(e.find("sees nothing"), std::string::npos) << e;
  EXPECT_NE(e.find("SimConfig.planes.heights_mm[0]"), std::string::npos) << e;
}

TEST(Simulate, SeatScenesMatchTheCellSetForTheSameSeed) {
  const SimConfig config = SmallConfig();
  const test::TestDir scratch("sim_sets");
  const std::string cell = scratch.File("cellset"), seats = scratch.File("seatset");
  SimConfig only_seats = config;
  only_seats.capture_planes = only_seats.capture_spheres = only_seats.capture_trajectory = false;
  only_seats.capture_chessboard_images = only_seats.capture_laser_line_images = false;
  only_seats.capture_touches = only_seats.capture_eye_in_hand = false;
  only_seats.capture_joint_poses = false;
  SimulateCell(only_seats, cell, {}, 2);
  const SimulationReport r = SimulateSeats(config, 3, seats, {}, 2);
  ASSERT_EQ(r.captures.size(), 3u);
  EXPECT_EQ(io::ReadFileBytes(cell + "/profiles/seat_001.lcp"),
            io::ReadFileBytes(seats + "/profiles/seat_001.lcp"));
  EXPECT_THROW(SimulateSeats(config, 0, seats), OptionError);
}

// Simulation profile: ideal, with the row and intensity noise off and 1 ms exposure jitter.
TEST(Simulate, NoiseFreeProfilesTriangulateOntoTheTruth) {
  // The whole chain: profile file rows -> true camera ray -> true laser plane -> true sweep pose
  // must land on the white plane or the floor, to the float precision of the stored rows.
  SimConfig config = SmallConfig();
  config.render.row_sigma_px = 0;
  config.render.intensity_sigma = 0;
  config.capture_spheres = config.capture_seats = config.capture_trajectory = false;
  config.capture_eye_in_hand = config.capture_joint_poses = false;
  config.timing.jitter_s = 1e-3;  // irregular exposures: poses must follow the timestamps
  // Sanitizer time: no camera images (not read here; the capture-set tests render them).
  if (test::kSanitizerBuild) {
    config.capture_chessboard_images = config.capture_laser_line_images = false;
  }
  const test::TestDir scratch("sim_chain");
  const std::string dir = scratch.path().string();
  SimulateCell(config, dir, {}, 2);
  const CellTruth truth = MakeCellTruth(config);
  const LinearSweep sweep = MakeLinearSweep(config, truth.sensor);
  const triangulation::ProfileSet set = triangulation::ReadProfiles(dir + "/profiles/plane_1.lcp");
  const Eigen::Vector4d plane = truth.sensor.laser.Coefficients();
  int on_plate = 0, on_floor = 0;
  double worst = 0;
  for (const triangulation::Profile& p : set.profiles) {
    const double t = (p.timestamp_ns - config.timing.start_ns) * 1e-9;
    const Eigen::Isometry3d cell_from_sensor = sweep.At(t);
    for (std::uint32_t c = 0; c < set.header.columns; ++c) {
      if (std::isnan(p.row_px[c])) continue;
      const Eigen::Vector3d ray = truth.sensor.camera.Unproject({c, p.row_px[c]});
      const double depth = -plane[3] / plane.head<3>().dot(ray);
      const Eigen::Vector3d p_cell = cell_from_sensor * (depth * ray);
      const double to_plate = std::abs(p_cell.z() - config.plane_heights_mm[1]);
      const double to_floor = std::abs(p_cell.z());
      worst = std::max(worst, std::min(to_plate, to_floor));
      (to_plate < to_floor ? on_plate : on_floor)++;
    }
  }
  EXPECT_GT(on_plate, 12 * 400);
  EXPECT_GT(on_floor, 12 * 50);
  // float32 rows (<= 6e-5 px) at ~0.6 mm/px, plus ns timestamp rounding: well below 1e-3 mm.
  EXPECT_LT(worst, 1e-3);
}

}  // namespace
}  // namespace lasercell::datasets
