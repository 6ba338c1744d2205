// `lasercell calibrate laser` end to end: simulated white-plane sweeps -> JSON (versioned,
// re-read), HTML report, the `laser` plane in cell.yaml (only that section changes); bad input
// exits 2 with one line naming the problem.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "core/frame_graph.hpp"
#include "core/io/file_util.hpp"
#include "datasets/simulate.hpp"
#include "tests/cli_util.hpp"

namespace lasercell {
namespace {

namespace fs = std::filesystem;

using test::CommandResult;
using test::RunCli;

// Simulation profile: ideal (the `simulate cell` config below names no profile).
class CalibrateLaserCli : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = test::MakeTestDir("laser_cli"); }
  void TearDown() override { test::RemoveTestDir(dir_); }

  /// Simulates the white-plane sweeps only; returns the plate normal in the sensor frame.
  std::string SimulatePlanes() const {
    const std::string config = (dir_ / "sim.yaml").string();
    std::ofstream(config)
        << "captures: {planes: true, spheres: false, seats: false, trajectory: false, "
           "chessboard_images: false, laser_line_images: false, meshes: false, "
           "touches: false, eye_in_hand: false, joint_poses: false}\n";
    const CommandResult sim =
        RunCli("simulate cell --quiet --out " + (dir_ / "sim").string() + " --config " + config);
    EXPECT_EQ(sim.exit_code, 0) << sim.err;
    const datasets::SimConfig defaults;
    const datasets::CellTruth truth = datasets::MakeCellTruth(defaults);
    const Eigen::Vector3d m = datasets::MakeLinearSweep(defaults, truth.sensor)
                                  .cell_from_sensor_start.linear()
                                  .transpose() *
                              Eigen::Vector3d::UnitZ();
    std::ostringstream s;
    s.precision(17);
    s << m.x() << "," << m.y() << "," << m.z();
    return s.str();
  }

  fs::path dir_;
};

TEST_F(CalibrateLaserCli, PlanesWriteJsonReportAndOnlyTheCellsLaserPlane) {
  const std::string m = SimulatePlanes();
  const std::string sim = (dir_ / "sim").string();
  const std::string cell = (dir_ / "cell.yaml").string();
  fs::copy_file(sim + "/truth/cell.yaml", cell);
  const std::string before = io::ReadFileBytes(cell);
  const CommandResult r =
      RunCli("calibrate laser --camera " + sim + "/truth/camera.cameramodel --planes " + sim +
             " --heights-mm 150,250,350 --plate-normal=" + m + " --cell " + cell + " --report " +
             (dir_ / "laser.html").string() + " --json " + (dir_ / "laser.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(io::ReadFileBytes((dir_ / "laser.json").string()));
  EXPECT_EQ(j["format"], "lasercell.laser_plane");
  EXPECT_EQ(j["version"], 1);
  EXPECT_EQ(j["method"], "heights");
  EXPECT_EQ(j["heights"].size(), 3u);
  const datasets::CellTruth truth = datasets::MakeCellTruth(datasets::SimConfig{});
  Eigen::Vector4d c = truth.sensor.laser.Coefficients();
  if (c(3) > 0) c = -c;
  const Eigen::Vector3d n(j["plane"]["normal"][0], j["plane"]["normal"][1],
                          j["plane"]["normal"][2]);
  EXPECT_LT(std::acos(std::min(1.0, n.dot(c.head<3>()))) * 180 / M_PI, 0.01);
  EXPECT_NEAR(j["plane"]["offset_mm"].get<double>(), c(3), 0.02);
  EXPECT_LT(j["normal_sigma_deg"].get<double>(), 0.01);
  // 3 heights, D0 estimated: each leave-one-out refit holds D0 at the full fit's value.
  EXPECT_LT(j["leave_one_out"]["max_normal_change_deg"].get<double>(), 0.01);
  EXPECT_LT(j["leave_one_out"]["max_offset_change_mm"].get<double>(), 0.02);
  EXPECT_TRUE(j["heights"][0]["leave_one_out"]["plate_distance_held"].get<bool>());
  // The cell: the old text unchanged, the laser plane appended, equal to the JSON's.
  const std::string after = io::ReadFileBytes(cell);
  EXPECT_EQ(after.substr(0, before.size()), before);
  const FrameGraph graph = LoadFrameGraph(cell);
  const LaserPlaneEntry& plane = graph.laser_planes().at("laser");
  EXPECT_EQ(plane.frame, "sensor");
  EXPECT_EQ(plane.normal, n);
  EXPECT_NEAR(plane.OffsetMm(), j["plane"]["offset_mm"].get<double>(),
              1e-9);  // p0 = -d n, recomputed
  ASSERT_TRUE(plane.covariance.has_value());
  const std::string html = io::ReadFileBytes((dir_ / "laser.html").string());
  EXPECT_NE(html.find("data-plot='Laser-plane residuals'"), std::string::npos);
  EXPECT_NE(html.find("data-plot='Residual along the laser line'"), std::string::npos);
  EXPECT_NE(html.find("data-plot='Stripe coverage of the image'"), std::string::npos);
  EXPECT_NE(html.find("data-plot='RMS residual per height'"), std::string::npos);
}

TEST_F(CalibrateLaserCli, BadInputExitsTwoWithOneLine) {
  const std::string m = SimulatePlanes();
  const std::string sim = (dir_ / "sim").string();
  const std::string base = "calibrate laser --camera " + sim +
                           "/truth/camera.cameramodel --planes " + sim + " --plate-normal=" + m +
                           " --cell " + (dir_ / "cell.yaml").string();
  CommandResult r = RunCli(base + " --heights-mm 250,250,250");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("planes at one height only"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "cell.yaml"));
  r = RunCli(base + " --heights-mm 150,250");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--heights-mm is '150,250'; expected 3"), std::string::npos) << r.err;
  r = RunCli("calibrate laser --camera " + sim + "/truth/camera.cameramodel --stripe-images '" +
             sim + "/nothing*.png' --board chessboard:9x6:40 --cell " +
             (dir_ / "cell.yaml").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("matches no file"), std::string::npos) << r.err;
  // An unreadable image.
  std::ofstream(dir_ / "broken.png") << "not a png";
  r = RunCli("calibrate laser --camera " + sim + "/truth/camera.cameramodel --stripe-images '" +
             (dir_ / "broken.png").string() + "' --board chessboard:9x6:40 --cell " +
             (dir_ / "cell.yaml").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("broken.png: cannot decode the image"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1);
}

}  // namespace
}  // namespace lasercell
