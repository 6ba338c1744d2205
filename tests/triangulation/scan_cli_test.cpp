// `lasercell scan triangulate` end to end: a simulated plane sweep written as files, the CLI run
// as a process, its PLY read back.
// Simulation profile: ideal (SimConfig{}); the robot sweep also turns the exposure jitter off.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>

#include "calib/camera_model.hpp"
#include "core/frame_graph.hpp"
#include "core/io/file_util.hpp"
#include "core/io/point_cloud_io.hpp"
#include "datasets/calibration_captures.hpp"
#include "datasets/cell.hpp"
#include "datasets/laser_renderer.hpp"
#include "datasets/simulate.hpp"
#include "tests/cli_util.hpp"
#include "triangulation/profile_io.hpp"

namespace lasercell::triangulation {
namespace {

namespace fs = std::filesystem;

using test::CommandResult;
using test::RunCli;

class ScanCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::MakeTestDir("scan");
    // A 10-profile linear sweep of the white plane at 250 mm, camera and truth files.
    const datasets::Scene scene = datasets::MakePlaneScene(truth_.layout, height_, {2000, 2000});
    const datasets::LaserRenderer renderer(scene, truth_.sensor, config_.render);
    sweep_ = datasets::MakeLinearSweep(config_, truth_.sensor);
    datasets::SweepTiming timing = config_.timing;
    timing.profiles = 10;
    timing.rate_hz = 5;
    const auto state_at = [&](double t) {
      datasets::SensorState st;
      st.scene_from_sensor = sweep_.At(t);
      return st;
    };
    const datasets::SweepResult r = datasets::RenderSweep(renderer, state_at, timing, 3, 0, "", 1);
    valid_ = r.valid_peaks;
    WriteProfiles((dir_ / "plane.lcp").string(), r.profiles);
    io::WriteFileAtomically((dir_ / "camera.cameramodel").string(),
                            datasets::MrcalCameraModelText(config_.sensor.camera));
    plane_ = truth_.sensor.laser.Coefficients();
    velocity_ = sweep_.At(0).linear().transpose() * sweep_.velocity_mm_s;
  }
  void TearDown() override { test::RemoveTestDir(dir_); }
  std::string P(const std::string& f) const { return (dir_ / f).string(); }
  static std::string Csv(const Eigen::VectorXd& v) {
    std::ostringstream o;
    o.precision(17);
    for (int i = 0; i < v.size(); ++i) o << (i ? "," : "") << v[i];
    return o.str();
  }
  // Every point within 1 mm of the plane (6 sigma of the row noise is < 0.6 mm here: the
  // sensitivity is ~1.8 mm/px at these depths) and the points of the sweep are all there.
  void ExpectOnPlane(const std::string& ply) const {
    const PointCloud cloud = io::ReadPointCloud(ply);
    EXPECT_EQ(cloud.size(), valid_);
    EXPECT_TRUE(cloud.HasProfile());
    EXPECT_TRUE(cloud.HasIntensity());
    const Eigen::Isometry3d cell_from_sweep = sweep_.At(0);
    for (const auto& p : cloud.positions) {
      ASSERT_NEAR((cell_from_sweep * p).z(), height_, 1.0);
    }
  }

  fs::path dir_;
  datasets::SimConfig config_;
  datasets::CellTruth truth_ = datasets::MakeCellTruth(config_);
  datasets::LinearSweep sweep_;
  Eigen::Vector4d plane_;
  Eigen::Vector3d velocity_;
  std::size_t valid_ = 0;
  double height_ = 250.0;
};

TEST_F(ScanCli, TriangulatesALinearSweepWithAPlaneFromTheCommandLine) {
  const std::string common = "scan triangulate --camera " + P("camera.cameramodel") +
                             " --profiles " + P("plane.lcp") + " --t0-ns 1000000000" +
                             " --velocity-mm-s " + Csv(velocity_) + " --laser-plane=" + Csv(plane_);
  CommandResult r = RunCli(common + " --out " + P("fast.ply"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ExpectOnPlane(P("fast.ply"));
  r = RunCli(common + " --exact --out " + P("exact.ply"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ExpectOnPlane(P("exact.ply"));
}

TEST_F(ScanCli, ReadsTheLaserPlaneFromCellYamlOrTheSimulatorTruth) {
  // cell.yaml with the laser_planes section of `lasercell calibrate laser` (core's writer).
  FrameGraph graph;
  LaserPlaneEntry entry;
  entry.normal = plane_.head<3>();
  entry.point_mm = -plane_[3] * entry.normal;
  graph.SetLaserPlane("laser", entry);
  io::WriteFileAtomically(P("cell.yaml"), FrameGraphToYaml(graph));
  const std::string common = "scan triangulate --camera " + P("camera.cameramodel") +
                             " --profiles " + P("plane.lcp") + " --t0-ns 1000000000" +
                             " --velocity-mm-s " + Csv(velocity_);
  CommandResult r = RunCli(common + " --cell " + P("cell.yaml") + " --out " + P("cell.ply"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ExpectOnPlane(P("cell.ply"));
  // The simulator's truth/sensor.yaml.
  std::ostringstream truth;
  truth.precision(17);
  const Eigen::Vector3d n = plane_.head<3>();
  truth << "format: lasercell.sim_sensor\nversion: 1\nlaser_plane_in_sensor:\n  normal: [" << n.x()
        << ", " << n.y() << ", " << n.z() << "]\n  d_mm: " << plane_[3] << "\n";
  io::WriteFileAtomically(P("sensor.yaml"), truth.str());
  r = RunCli(common + " --sensor-truth " + P("sensor.yaml") + " --out " + P("truth.ply"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ExpectOnPlane(P("truth.ply"));
}

TEST_F(ScanCli, RobotSweepIsPosedThroughTheCellFile) {
  // The simulator's arc sweep over the plane, joints in the profiles; the true cell.yaml plus
  // a laser_planes section.
  const datasets::Scene scene = datasets::MakePlaneScene(truth_.layout, 150.0, {1500, 1500});
  const datasets::LaserRenderer renderer(scene, truth_.sensor, config_.render);
  const datasets::JointTrajectory traj = datasets::MakeArcTrajectory(config_, truth_);
  datasets::SweepTiming timing = config_.timing;
  timing.profiles = 8;
  timing.rate_hz = 7.0 / traj.times_s.back();
  timing.jitter_s = 0;
  const auto state_at = [&](double t) {
    datasets::SensorState st;
    st.joints_rad = traj.At(t);
    st.scene_from_sensor = datasets::TrueCellFromSensor(truth_, st.joints_rad);
    return st;
  };
  const datasets::SweepResult r =
      datasets::RenderSweep(renderer, state_at, timing, 4, 6, "vision_robot", 1);
  WriteProfiles(P("robot.lcp"), r.profiles);
  FrameGraph graph = truth_.Graph();
  LaserPlaneEntry entry;
  entry.normal = plane_.head<3>();
  entry.point_mm = -plane_[3] * entry.normal;
  graph.SetLaserPlane("laser", entry);
  io::WriteFileAtomically(P("cell.yaml"), FrameGraphToYaml(graph));
  const CommandResult run = RunCli("scan triangulate --camera " + P("camera.cameramodel") +
                                   " --profiles " + P("robot.lcp") + " --cell " + P("cell.yaml") +
                                   " --frame cell --out " + P("robot.ply"));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const PointCloud cloud = io::ReadPointCloud(P("robot.ply"));
  EXPECT_EQ(cloud.size(), r.valid_peaks);
  ASSERT_GT(cloud.size(), 3000u);
  for (const auto& p : cloud.positions) ASSERT_NEAR(p.z(), 150.0, 1.0);  // see ExpectOnPlane
}

TEST_F(ScanCli, LinearSweepIsPlacedThroughStaticEdges) {
  // A handling_base <- sensor edge (as `calibrate spheres` writes it) places the linear sweep.
  FrameGraph graph;
  LaserPlaneEntry entry;
  entry.normal = plane_.head<3>();
  entry.point_mm = -plane_[3] * entry.normal;
  graph.SetLaserPlane("laser", entry);
  StaticEdge edge;
  edge.parent = "handling_base";
  edge.child = "sensor";
  const Eigen::Isometry3d hb_from_sensor =
      Eigen::Translation3d(1500, -20, 900) *
      Eigen::AngleAxisd(3.0, Eigen::Vector3d(1, 1, 0).normalized());
  edge.parent_from_child = QuaternionPose::FromIsometry(hb_from_sensor);
  graph.SetStaticEdge(edge);
  io::WriteFileAtomically(P("cell.yaml"), FrameGraphToYaml(graph));
  const std::string common = "scan triangulate --camera " + P("camera.cameramodel") +
                             " --profiles " + P("plane.lcp") + " --t0-ns 1000000000" +
                             " --velocity-mm-s " + Csv(velocity_) + " --cell " + P("cell.yaml");
  CommandResult r = RunCli(common + " --out " + P("t0.ply"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = RunCli(common + " --frame handling_base --out " + P("hb.ply"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const PointCloud t0 = io::ReadPointCloud(P("t0.ply"));
  const PointCloud hb = io::ReadPointCloud(P("hb.ply"));
  ASSERT_EQ(t0.size(), hb.size());
  ASSERT_GT(t0.size(), 1000u);
  const Eigen::Isometry3d placed =
      FrameGraphFromYaml(FrameGraphToYaml(graph), "g").Transform("handling_base", "sensor");
  for (std::size_t i = 0; i < t0.size(); i += 97) {
    // Both files hold float32 positions: 2 ulp at ~2 m is ~5e-4 mm.
    const double ulp = 1.2e-7 * (placed * t0.positions[i]).norm();
    EXPECT_LT((placed * t0.positions[i] - hb.positions[i]).norm(), 4 * ulp);
  }
}

TEST_F(ScanCli, BadInputExitsTwoWithOneLine) {
  const std::string base = "scan triangulate --camera " + P("camera.cameramodel") + " --profiles " +
                           P("plane.lcp") + " --out " + P("x.ply");
  CommandResult r = RunCli(base);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("no laser plane"), std::string::npos) << r.err;
  r = RunCli(base + " --laser-plane=0,1,0,0");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("passes through the camera centre"), std::string::npos) << r.err;
  r = RunCli(base + " --laser-plane=" + Csv(plane_) + " --velocity-mm-s 1,2");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--velocity-mm-s"), std::string::npos) << r.err;
  r = RunCli(base + " --laser-plane=" + Csv(plane_) + " --frame vision_base");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--frame needs --cell"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(P("x.ply")));
}

TEST_F(ScanCli, BenchPeaksPrintsOneRowPerEstimatorAndSnr) {
  const CommandResult run = RunCli("bench peaks --snr 20,50 --images 1 --shape sampled-gaussian");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  std::istringstream in(run.out);
  std::string line;
  int rows = 0;
  while (std::getline(in, line)) {
    if (line.rfind("| 20 |", 0) == 0 || line.rfind("| 50 |", 0) == 0) ++rows;
  }
  EXPECT_EQ(rows, 6);
  const CommandResult bad = RunCli("bench peaks --snr 500");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("saturation"), std::string::npos) << bad.err;
}

}  // namespace
}  // namespace lasercell::triangulation
