// `lasercell calibrate spheres` end to end on the simulated sweep: JSON, report, cell.yaml edge,
// and the CLI's bad-input paths (exit 2, one line naming the problem).
// Simulation profile: ideal (DefaultSphereSweep, tests/calib/sphere_sweep_sim.hpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "core/frame_graph.hpp"
#include "core/io/file_util.hpp"
#include "core/io/point_cloud_io.hpp"
#include "core/se3.hpp"
#include "datasets/simulate.hpp"
#include "datasets/simulate_records.hpp"
#include "tests/calib/realistic_cli_util.hpp"
#include "tests/calib/sphere_sweep_sim.hpp"
#include "tests/cli_util.hpp"
#include "triangulation/linear_sweep.hpp"

namespace lasercell::calib {
namespace {

namespace fs = std::filesystem;

using ::lasercell::test::CommandResult;
using ::lasercell::test::RunCli;

class CalibrateSpheresCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = ::lasercell::test::MakeTestDir("spheres_cli");
    const testing::SimulatedSphereSweep& sim = testing::DefaultSphereSweep();
    io::WritePointCloud((dir_ / "sweep.ply").string(), sim.cloud);
    datasets::SimConfig config;
    config.seed = 7;
    io::WriteFileAtomically((dir_ / "touches.yaml").string(),
                            datasets::TouchesRecordYaml(config, sim.touches));
    truth_ = datasets::MakeCellTruth(config);
    FrameGraph graph;
    StaticEdge e;
    e.parent = "cell";
    e.child = "handling_base";
    e.SetParentFromChild(truth_.layout.cell_from_handling_base);
    graph.SetStaticEdge(e);
    SaveFrameGraph((dir_ / "cell.yaml").string(), graph);
  }
  // LASERCELL_KEEP_TEST_FILES=1 keeps the folder (sweep, touches, cell, JSON, report) to look at.
  void TearDown() override { ::lasercell::test::RemoveTestDir(dir_); }

  std::string Args(const std::string& cell = "cell.yaml", const std::string& sweep = "sweep.ply",
                   const std::string& touches = "touches.yaml") const {
    return "calibrate spheres --cell " + (dir_ / cell).string() + " --sweep " +
           (dir_ / sweep).string() + " --touches " + (dir_ / touches).string();
  }

  fs::path dir_;
  datasets::CellTruth truth_;
};

TEST_F(CalibrateSpheresCli, WritesTheEdgeTheJsonAndTheReport) {
  const CommandResult run = RunCli(Args() + " --report " + (dir_ / "r.html").string() + " --json " +
                                   (dir_ / "r.json").string());
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const testing::SimulatedSphereSweep& sim = testing::DefaultSphereSweep();

  // JSON: versioned, the pose in the file notation, residuals and 1-sigma.
  const nlohmann::json j = nlohmann::json::parse(io::ReadFileBytes((dir_ / "r.json").string()));
  EXPECT_EQ(j["format"], "lasercell.calibration_spheres");
  EXPECT_EQ(j["version"], 1);
  const auto& pose = j["handling_base_from_sensor"];
  const Eigen::Quaterniond q(pose["rotation_wxyz"][0], pose["rotation_wxyz"][1],
                             pose["rotation_wxyz"][2], pose["rotation_wxyz"][3]);
  const Eigen::Vector3d t(pose["translation_mm"][0], pose["translation_mm"][1],
                          pose["translation_mm"][2]);
  const Eigen::Isometry3d est = PoseFromQuaternion(q, t);
  // Within 5 reported sigmas (chi2 6 dof at 5 sigma-norm is far beyond p = 1e-4).
  const Vector6d xi = RotationVectorTranslation(sim.handling_base_from_sweep * est.inverse());
  Matrix6d cov;
  for (int i = 0; i < 36; ++i)
    cov.data()[i] = j["covariance"]["values"][static_cast<std::size_t>(i)];
  EXPECT_LT(std::sqrt(xi.dot(cov.inverse() * xi)), 5.0);
  ASSERT_EQ(j["spheres"].size(), 4u);
  for (const auto& s : j["spheres"]) {
    EXPECT_LT(s["residual_norm_mm"].get<double>(), 0.3);
    EXPECT_EQ(s["residual_mm"].size(), 3u);
  }
  EXPECT_EQ(j["sigma"]["translation_mm"].size(), 3u);

  // cell.yaml: the new edge with provenance and covariance; the old edge untouched.
  const FrameGraph graph = LoadFrameGraph((dir_ / "cell.yaml").string());
  ASSERT_EQ(graph.static_edges().size(), 2u);
  const StaticEdge& edge = graph.static_edges()[1];
  EXPECT_EQ(edge.parent, "handling_base");
  EXPECT_EQ(edge.child, "sensor");
  EXPECT_EQ(edge.provenance.tool.rfind("lasercell calibrate spheres", 0), 0u);
  EXPECT_EQ(edge.provenance.input_digest.rfind("fnv1a64:", 0), 0u);
  ASSERT_TRUE(edge.covariance.has_value());
  EXPECT_LT(RotationDistance(edge.ParentFromChild(), est), 1e-12);
  EXPECT_LT(RotationDistance(graph.Transform("cell", "handling_base"),
                             truth_.layout.cell_from_handling_base),
            1e-15);

  // Report: the per-sphere bars, one residual histogram per sphere.
  const std::string html = io::ReadFileBytes((dir_ / "r.html").string());
  std::size_t plots = 0;
  for (std::size_t p = html.find("data-plot="); p != std::string::npos;
       p = html.find("data-plot=", p + 1)) {
    ++plots;
  }
  EXPECT_GE(plots, 5u);
  EXPECT_NE(html.find("Residual per sphere"), std::string::npos);

  // A second run replaces the edge, it does not add one.
  ASSERT_EQ(RunCli(Args()).exit_code, 0);
  EXPECT_EQ(LoadFrameGraph((dir_ / "cell.yaml").string()).static_edges().size(), 2u);
}

TEST_F(CalibrateSpheresCli, FreeRadiusFitsTheRadiiAndAgreesWithTheTruth) {
  const CommandResult run = RunCli(Args() + " --free-radius --sweep-frame sweep_start --json " +
                                   (dir_ / "f.json").string());
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json j = nlohmann::json::parse(io::ReadFileBytes((dir_ / "f.json").string()));
  ASSERT_EQ(j["spheres"].size(), 4u);
  for (const auto& s : j["spheres"]) {
    const double sigma = s["fit"]["radius_sigma_mm"];
    EXPECT_GT(sigma, 0.0);
    EXPECT_NEAR(s["radius_mm"].get<double>(), 25.0, std::max(5 * sigma, 0.01));
  }
  const auto& pose = j["handling_base_from_sweep_start"];
  const Eigen::Vector3d t(pose["translation_mm"][0], pose["translation_mm"][1],
                          pose["translation_mm"][2]);
  const double sigma_t =
      Eigen::Vector3d(j["sigma"]["translation_mm"][0], j["sigma"]["translation_mm"][1],
                      j["sigma"]["translation_mm"][2])
          .norm();
  EXPECT_LT((t - testing::DefaultSphereSweep().handling_base_from_sweep.translation()).norm(),
            4 * sigma_t);
}

TEST_F(CalibrateSpheresCli, RefusesAnEdgeThatWouldCloseACycle) {
  SaveFrameGraph((dir_ / "truth_cell.yaml").string(), truth_.Graph());
  const CommandResult run = RunCli(Args("truth_cell.yaml"));
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("handling_base and 'sensor' are already connected through other edges"),
            std::string::npos)
      << run.err;
  EXPECT_NE(run.err.find("--sweep-frame"), std::string::npos);
  // With a frame of its own it works.
  EXPECT_EQ(RunCli(Args("truth_cell.yaml") + " --sweep-frame sweep_start").exit_code, 0);
}

TEST_F(CalibrateSpheresCli, NoSphereInTheSweepIsAClearError) {
  // The real UWA rs1 scan (no calibration spheres in it).
  fs::copy_file(fs::path(LASERCELL_SOURCE_DIR) / "datasets/real/uwa/rs1_normals.bin.ply",
                dir_ / "rs1.ply");
  const CommandResult run = RunCli(Args("cell.yaml", "rs1.ply"));
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("rs1.ply: no sphere of radius 25 mm found"), std::string::npos) << run.err;
  EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << run.err;
}

TEST_F(CalibrateSpheresCli, BadTouchesFilesAreClearErrors) {
  std::string text = io::ReadFileBytes((dir_ / "touches.yaml").string());
  io::WriteFileAtomically((dir_ / "t1.yaml").string(), text + "units: m\n");
  CommandResult run = RunCli(Args("cell.yaml", "sweep.ply", "t1.yaml"));
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("t1.yaml: line"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("unknown field 'units'"), std::string::npos) << run.err;
  // Only two spheres touched.
  const std::size_t third = text.find("  - sphere: 2");
  ASSERT_NE(third, std::string::npos);
  io::WriteFileAtomically((dir_ / "t2.yaml").string(), text.substr(0, third));
  run = RunCli(Args("cell.yaml", "sweep.ply", "t2.yaml"));
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("2 sphere touches: at least 3 non-collinear spheres"), std::string::npos)
      << run.err;
  // The cell file is untouched by failed runs.
  EXPECT_EQ(LoadFrameGraph((dir_ / "cell.yaml").string()).static_edges().size(), 1u);
}

// From the profiles: the sweep triangulated through the camera and the cell's plane, whose
// error modes the edge then answers (sensor_response, tied to the plane's calibration digest).
// A plane-only offset mode moves every point along its line of sight, so the placement moves.
TEST(CalibrateSpheresFromProfilesCli, TheEdgeKeepsItsResponseToThePlanesErrorModes) {
  datasets::SimConfig config;
  config.seed = 17;
  config.capture_planes = config.capture_seats = config.capture_trajectory = false;
  config.capture_chessboard_images = config.capture_laser_line_images = false;
  config.capture_eye_in_hand = config.capture_joint_poses = config.write_meshes = false;
  const fs::path dir = ::lasercell::test::MakeTestDir("spheres_profiles_cli");
  datasets::SimulateCell(config, (dir / "sim").string(), {}, 0);
  const Eigen::Vector4d truth =
      datasets::ReadSensorTruth((dir / "sim/truth/sensor.yaml").string()).LaserPlane();
  LaserPlaneEntry plane;
  plane.normal = truth.head<3>();
  plane.point_mm = -truth[3] * truth.head<3>();
  SensorErrorMode offset, tilt;
  offset.plane_step << 0, 0, 0, 0.02;
  tilt.plane_step << 1e-4 * truth.head<3>().unitOrthogonal(), 0;
  plane.error_modes = {offset, tilt};
  plane.covariance = (offset.plane_step * offset.plane_step.transpose() +
                      tilt.plane_step * tilt.plane_step.transpose())
                         .eval();
  plane.provenance.input_digest = "fnv1a64:feed";
  FrameGraph cell;
  cell.SetLaserPlane("laser", plane);
  SaveFrameGraph((dir / "cell.yaml").string(), cell);
  const triangulation::LinearSweepRecord record =
      triangulation::ReadLinearSweepRecord((dir / "sim/records/linear_sweep.yaml").string());
  const std::string args =
      "calibrate spheres --cell " + (dir / "cell.yaml").string() + " --touches " +
      (dir / "sim/records/touches.yaml").string() + " --camera " +
      (dir / "sim/truth/camera.cameramodel").string() + " --profiles " +
      (dir / "sim/profiles/spheres.lcp").string() +
      " --velocity-mm-s=" + ::lasercell::test::CsvOf(record.velocity_mm_s_in_sensor) + " --t0-ns " +
      std::to_string(record.t0_ns);
  const CommandResult run = RunCli(args);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("error modes: propagated"), std::string::npos) << run.out;
  const FrameGraph read = LoadFrameGraph((dir / "cell.yaml").string());
  ASSERT_EQ(read.static_edges().size(), 1u);
  const StaticEdge& edge = read.static_edges()[0];
  ASSERT_TRUE(edge.sensor_response.has_value());
  EXPECT_EQ(edge.sensor_response->laser, "laser");
  EXPECT_EQ(edge.sensor_response->plane_digest, "fnv1a64:feed");
  ASSERT_EQ(edge.sensor_response->columns.cols(), 2);
  // 0.02 mm along ~0.7 m lines of sight scales the sweep by ~3e-5: tens of micrometres at
  // the spheres, and the placement follows by as much.
  const double moved = edge.sensor_response->columns.col(0).tail<3>().norm();
  EXPECT_GT(moved, 0.005);
  EXPECT_LT(moved, 0.2);

  // Either the cloud or the profiles, and the profiles need the camera and the motion.
  CommandResult bad = RunCli(args + " --sweep " + (dir / "x.ply").string());
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("one of them"), std::string::npos) << bad.err;
  bad = RunCli("calibrate spheres --cell " + (dir / "cell.yaml").string() + " --touches " +
               (dir / "sim/records/touches.yaml").string() + " --profiles " +
               (dir / "sim/profiles/spheres.lcp").string());
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--profiles needs --camera"), std::string::npos) << bad.err;
  ::lasercell::test::RemoveTestDir(dir);
}

}  // namespace
}  // namespace lasercell::calib
