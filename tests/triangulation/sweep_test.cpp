#include "triangulation/sweep.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "datasets/calibration_captures.hpp"
#include "datasets/cell.hpp"
#include "datasets/laser_renderer.hpp"
#include "datasets/simulate.hpp"

namespace lasercell::triangulation {
namespace {

calib::CameraModel SimCamera(const datasets::SensorModel& sensor) { return sensor.camera; }

// Simulation profile: ideal (SimConfig{}); the robot sweep test turns the exposure jitter off.
struct SimCell {
  datasets::SimConfig config;
  datasets::CellTruth truth = datasets::MakeCellTruth(config);
  Triangulator tri{SimCamera(truth.sensor), truth.sensor.laser.Coefficients()};
};

// The row noise (N(0, row_sigma_px)) moves a point within the laser plane; its distance to a
// plane of unit normal m (sensor frame) changes by |m . dp/dv| per px of row. Tolerance: 6 sigma.
double PlaneTolMm(const Triangulator& tri, const Eigen::Vector3d& m_in_sensor, int column,
                  double row, double row_sigma_px) {
  const double dv = 1e-3;
  const Eigen::Vector3d dp_dv =
      (tri.TriangulateExact(column, row + dv) - tri.TriangulateExact(column, row - dv)) / (2 * dv);
  return 6.0 * row_sigma_px * std::abs(m_in_sensor.dot(dp_dv)) + 1e-6;
}

TEST(Sweep, LinearSweepOfTheWhitePlaneIsFlatInTheSweepFrame) {
  SimCell s;
  const double height = 250.0;
  const datasets::Scene scene = datasets::MakePlaneScene(s.truth.layout, height, {2000, 2000});
  const datasets::LaserRenderer renderer(scene, s.truth.sensor, s.config.render);
  const datasets::LinearSweep sweep = datasets::MakeLinearSweep(s.config, s.truth.sensor);
  datasets::SweepTiming timing = s.config.timing;
  timing.profiles = 20;
  timing.rate_hz = 10;
  const auto state_at = [&](double t) {
    datasets::SensorState st;
    st.scene_from_sensor = sweep.At(t);
    return st;
  };
  const datasets::SweepResult r = datasets::RenderSweep(renderer, state_at, timing, 9, 0, "", 1);
  // Sweep frame = sensor at the nominal t0 (timing.start_ns); velocity in that frame.
  const Eigen::Isometry3d cell_from_sweep = sweep.At(0.0);
  SweepOptions o;
  o.motion = SweepMotion::kLinear;
  o.velocity_mm_s = cell_from_sweep.linear().transpose() * sweep.velocity_mm_s;
  o.t0_ns = timing.start_ns;
  o.threads = 2;
  const SweepResult result = AssembleSweep(r.profiles, s.tri, o);
  EXPECT_EQ(result.frame, "sensor");  // the sensor frame at t0
  EXPECT_EQ(result.profiles, 20u);
  EXPECT_EQ(result.cloud.size(), result.counts.points);
  EXPECT_EQ(result.counts.points, r.valid_peaks);
  ASSERT_GT(result.cloud.size(), 15000u);
  result.cloud.Validate("sweep");
  EXPECT_TRUE(result.cloud.IsOrganized());
  const Eigen::Vector3d m = cell_from_sweep.linear().transpose() * Eigen::Vector3d::UnitZ();
  for (std::size_t k = 0; k < result.cloud.size(); k += 7) {
    const Eigen::Vector3d p_cell = cell_from_sweep * result.cloud.positions[k];
    const int c = result.cloud.column[k];
    const double row = r.profiles.profiles[result.cloud.profile[k]].row_px[c];
    ASSERT_LT(std::abs(p_cell.z() - height),
              PlaneTolMm(s.tri, m, c, row, s.config.render.row_sigma_px))
        << "point " << k;
  }
  // The sweep covers the travelled distance along the velocity.
  const Eigen::Vector3d dir = o.velocity_mm_s.normalized();
  double lo = 1e9, hi = -1e9;
  for (const auto& p : result.cloud.positions) {
    lo = std::min(lo, dir.dot(p));
    hi = std::max(hi, dir.dot(p));
  }
  EXPECT_NEAR(hi - lo, sweep.velocity_mm_s.norm() * 19 / timing.rate_hz, 1.0);
  // Attributes: profile index, column, timestamp relative to t0.
  for (std::size_t k = 0; k < result.cloud.size(); k += 997) {
    const int i = result.cloud.profile[k];
    const int c = result.cloud.column[k];
    EXPECT_FALSE(std::isnan(r.profiles.profiles[i].row_px[c]));
    EXPECT_EQ(result.cloud.intensity[k], r.profiles.profiles[i].intensity[c]);
    EXPECT_NEAR(result.cloud.timestamp_s[k],
                (r.profiles.profiles[i].timestamp_ns - timing.start_ns) * 1e-9, 1e-12);
  }
  // Lost profiles show as sequence gaps.
  datasets::SweepResult gappy = r;
  gappy.profiles.profiles.erase(gappy.profiles.profiles.begin() + 5,
                                gappy.profiles.profiles.begin() + 8);
  EXPECT_EQ(AssembleSweep(gappy.profiles, s.tri, o).sequence_gaps, 3u);
  EXPECT_EQ(result.sequence_gaps, 0u);
  // Without motion, every profile stays in the sensor frame.
  o.motion = SweepMotion::kNone;
  const SweepResult still = AssembleSweep(r.profiles, s.tri, o);
  EXPECT_EQ(still.cloud.size(), result.cloud.size());
  EXPECT_EQ(still.frame, "sensor");
  // Thread count does not change the result.
  o.motion = SweepMotion::kLinear;
  o.threads = 1;
  EXPECT_EQ(AssembleSweep(r.profiles, s.tri, o).cloud.positions, result.cloud.positions);
}

TEST(Sweep, RobotSweepThroughTheFrameGraphLandsOnThePlaneInTheCell) {
  SimCell s;
  const double height = 150.0;
  const datasets::Scene scene = datasets::MakePlaneScene(s.truth.layout, height, {1500, 1500});
  const datasets::LaserRenderer renderer(scene, s.truth.sensor, s.config.render);
  const datasets::JointTrajectory traj = datasets::MakeArcTrajectory(s.config, s.truth);
  datasets::SweepTiming timing = s.config.timing;
  timing.profiles = 12;
  timing.rate_hz = 11.0 / traj.times_s.back();
  timing.jitter_s = 0;
  const auto state_at = [&](double t) {
    datasets::SensorState st;
    st.joints_rad = traj.At(t);
    st.scene_from_sensor = datasets::TrueCellFromSensor(s.truth, st.joints_rad);
    return st;
  };
  const datasets::SweepResult r =
      datasets::RenderSweep(renderer, state_at, timing, 4, 6, "vision_robot", 1);
  const FrameGraph graph = s.truth.Graph();
  SweepOptions o;
  o.motion = SweepMotion::kRobot;
  o.target_frame = "cell";
  const SweepResult result = AssembleSweep(r.profiles, s.tri, o, &graph);
  EXPECT_EQ(result.frame, "cell");
  ASSERT_GT(result.cloud.size(), 5000u);
  for (std::size_t k = 0; k < result.cloud.size(); k += 5) {
    const Profile& p = r.profiles.profiles[result.cloud.profile[k]];
    const int c = result.cloud.column[k];
    const Eigen::Matrix3d cell_r_sensor =
        graph.Transform("cell", "sensor", {{"vision_robot", p.joints_rad}}).linear();
    const Eigen::Vector3d m = cell_r_sensor.transpose() * Eigen::Vector3d::UnitZ();
    ASSERT_LT(std::abs(result.cloud.positions[k].z() - height),
              PlaneTolMm(s.tri, m, c, p.row_px[c], s.config.render.row_sigma_px))
        << "point " << k;
  }
  // Each profile's sensor pose is the truth's at its joints (line of sight from there).
  ASSERT_EQ(result.frame_from_sensor.size(), r.profiles.profiles.size());
  for (std::size_t i = 0; i < r.profiles.profiles.size(); ++i) {
    const Eigen::Isometry3d truth =
        datasets::TrueCellFromSensor(s.truth, r.profiles.profiles[i].joints_rad);
    EXPECT_LT((result.frame_from_sensor[i].translation() - truth.translation()).norm(), 1e-6);
    EXPECT_LT((result.frame_from_sensor[i].linear() - truth.linear()).norm(), 1e-9);
  }
  // The exact path gives the same cloud within the fast path's tolerance.
  o.path = TriangulationPath::kExact;
  const SweepResult exact = AssembleSweep(r.profiles, s.tri, o, &graph);
  ASSERT_EQ(exact.cloud.size(), result.cloud.size());
  for (std::size_t k = 0; k < exact.cloud.size(); ++k) {
    EXPECT_LT((exact.cloud.positions[k] - result.cloud.positions[k]).norm(), 1e-4);
  }
  // Bad requests name the problem.
  o.target_frame = "nowhere";
  try {
    AssembleSweep(r.profiles, s.tri, o, &graph);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no path from frame 'sensor' to 'nowhere'"),
              std::string::npos)
        << e.what();
  }
  ProfileSet no_joints = r.profiles;
  no_joints.header.joint_count = 0;
  for (auto& p : no_joints.profiles) p.joints_rad.clear();
  o.target_frame = "cell";
  EXPECT_THROW(AssembleSweep(no_joints, s.tri, o, &graph), InputError);
}

TEST(Sweep, LinearSweepPlacedInACellFrameIsTheSensorSweepMovedThroughStaticEdges) {
  SimCell s;
  const datasets::Scene scene = datasets::MakePlaneScene(s.truth.layout, 250.0, {2000, 2000});
  const datasets::LaserRenderer renderer(scene, s.truth.sensor, s.config.render);
  const datasets::LinearSweep sweep = datasets::MakeLinearSweep(s.config, s.truth.sensor);
  datasets::SweepTiming timing = s.config.timing;
  timing.profiles = 6;
  const auto state_at = [&](double t) {
    datasets::SensorState st;
    st.scene_from_sensor = sweep.At(t);
    return st;
  };
  const datasets::SweepResult r = datasets::RenderSweep(renderer, state_at, timing, 5, 0, "", 1);
  SweepOptions o;
  o.motion = SweepMotion::kLinear;
  o.velocity_mm_s = sweep.At(0.0).linear().transpose() * sweep.velocity_mm_s;
  o.t0_ns = timing.start_ns;
  const SweepResult at_t0 = AssembleSweep(r.profiles, s.tri, o);
  // handling_base <- sensor (as calibrate spheres writes it) and a robot elsewhere in the graph.
  FrameGraph graph = s.truth.Graph();
  graph.RemoveEdge("vision_flange", "sensor");
  StaticEdge edge;
  edge.parent = "handling_base";
  edge.child = "sensor";
  const Eigen::Isometry3d hb_from_sensor =
      s.truth.layout.cell_from_handling_base.inverse() * sweep.At(0.0);
  edge.SetParentFromChild(hb_from_sensor);
  graph.SetStaticEdge(edge);
  o.target_frame = "cell";
  o.threads = 2;
  const SweepResult placed = AssembleSweep(r.profiles, s.tri, o, &graph);
  EXPECT_EQ(placed.frame, "cell");
  EXPECT_NE(placed.Summary().find("placed through static edges"), std::string::npos);
  ASSERT_EQ(placed.cloud.size(), at_t0.cloud.size());
  ASSERT_GT(placed.cloud.size(), 1000u);
  const Eigen::Isometry3d cell_from_sensor = graph.Transform("cell", "sensor");
  for (std::size_t k = 0; k < placed.cloud.size(); ++k) {
    ASSERT_EQ(placed.cloud.positions[k], cell_from_sensor * at_t0.cloud.positions[k]) << k;
  }
  EXPECT_EQ(placed.cloud.timestamp_s, at_t0.cloud.timestamp_s);
  // The sensor of profile i is where the axis carried it: cell <- sensor(t0) * t_i * velocity.
  ASSERT_EQ(placed.frame_from_sensor.size(), r.profiles.profiles.size());
  for (std::size_t i = 0; i < placed.frame_from_sensor.size(); ++i) {
    const double t =
        static_cast<double>(r.profiles.profiles[i].timestamp_ns - timing.start_ns) * 1e-9;
    const Eigen::Vector3d centre = cell_from_sensor * (o.velocity_mm_s * t);
    EXPECT_LT((placed.frame_from_sensor[i].translation() - centre).norm(), 1e-9) << i;
    EXPECT_LT((at_t0.frame_from_sensor[i].translation() - o.velocity_mm_s * t).norm(), 1e-12);
  }
  // The cell has no plane: ScanSetupFromCell takes the given one and checks the frame first.
  LaserPlaneSource source;
  source.plane = s.truth.sensor.laser.Coefficients();
  source.plane_label = "given";
  const ScanSetup setup = ScanSetupFromCell(&graph, "cell.yaml", source, o);
  EXPECT_EQ(setup.laser_plane, *source.plane);
  EXPECT_EQ(setup.laser_plane_source, "given");
  EXPECT_EQ(setup.options.target_frame, "cell");
  // Through a robot (the hand-eye edge instead): refused, naming the robot.
  FrameGraph robot_path = s.truth.Graph();
  o.target_frame = "vision_base";
  try {
    AssembleSweep(r.profiles, s.tri, o, &robot_path);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("passes robot 'vision_robot'"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(ScanSetupFromCell(&robot_path, "cell.yaml", source, o), InputError);
  EXPECT_THROW(AssembleSweep(r.profiles, s.tri, o, nullptr), InputError);
}

TEST(Sweep, ScanSetupTakesTheGivenPlaneOrTheCellsNamedPlane) {
  SweepOptions o;
  FrameGraph cell;
  LaserPlaneEntry entry;
  entry.normal = Eigen::Vector3d(0, 0.9, -0.3).normalized();
  entry.point_mm = -400.0 * entry.normal;
  cell.SetLaserPlane("laser", entry);
  LaserPlaneSource source;
  ScanSetup setup = ScanSetupFromCell(&cell, "cell.yaml", source, o);
  EXPECT_EQ(setup.laser_plane.head<3>(), entry.normal);
  EXPECT_NEAR(setup.laser_plane[3], entry.OffsetMm(), 0.0);
  EXPECT_EQ(setup.laser_plane_source, "cell.yaml");
  source.plane = Eigen::Vector4d(0, 1, 0, -5);
  source.plane_label = "--laser-plane";
  setup = ScanSetupFromCell(&cell, "cell.yaml", source, o);
  EXPECT_EQ(setup.laser_plane, *source.plane);
  EXPECT_EQ(setup.laser_plane_source, "--laser-plane");
  source.plane.reset();
  source.laser = "other";
  try {
    ScanSetupFromCell(&cell, "cell.yaml", source, o);
    FAIL();
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find("no laser plane named 'other'"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(ScanSetupFromCell(nullptr, "", source, o), InputError);
  o.motion = SweepMotion::kRobot;
  o.target_frame = "vision_base";
  source.plane = Eigen::Vector4d(0, 1, 0, -5);
  EXPECT_THROW(ScanSetupFromCell(nullptr, "", source, o), InputError);
}

TEST(Sweep, BadOptionsNameTheField) {
  SweepOptions o;
  o.velocity_mm_s.x() = std::numeric_limits<double>::quiet_NaN();
  try {
    o.Check();
    FAIL();
  } catch (const OptionError& e) {
    EXPECT_NE(std::string(e.what()).find("SweepOptions.velocity_mm_s"), std::string::npos);
  }
  SweepOptions robot;
  robot.motion = SweepMotion::kRobot;
  robot.target_frame = "";
  EXPECT_THROW(robot.Check(), OptionError);
}

TEST(Sweep, ProfilesOfAnotherSensorSizeAreRejected) {
  SimCell s;
  ProfileSet set;
  set.header.image_width = 640;
  set.header.image_height = 480;
  set.header.columns = 640;
  try {
    AssembleSweep(set, s.tri, {});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("640 x 480"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace lasercell::triangulation
