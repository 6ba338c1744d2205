// End-to-end: `lasercell simulate cell` (pose sweeps only) -> `lasercell calibrate joints` and
// `lasercell calibrate handeye-laser` on the written files; the JSON results are re-read, the
// updated cell.yaml reads back and rewrites to the same text, and only the robot / hand-eye
// parts changed.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>

#include "core/frame_graph.hpp"
#include "core/kinematics.hpp"
#include "tests/cli_util.hpp"
#include "tests/sanitizer_scale.hpp"

// In lasercell::test: the shared helpers of tests/cli_util.hpp (RunCli, Slurp, ...) by name.
namespace lasercell::test {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

/// Simulated pose sweeps, written once for the whole binary.
/// Simulation profile: ideal (sim.yaml names no profile).
class CalibrateJointsCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = MakeTestDir("joints_cli");
    Spit(dir_ / "sim.yaml",
         "format: lasercell.sim_config\nversion: 1\nseed: 5\n"
         "eye_in_hand: {profiles: 12}\njoint_poses: {profiles: 10}\n"
         "captures: {planes: false, spheres: false, seats: false, trajectory: false, "
         "chessboard_images: false, laser_line_images: false, meshes: false}\n");
    const CommandResult run = RunCli("simulate cell --quiet --out " + (dir_ / "sim").string() +
                                     " --config " + (dir_ / "sim.yaml").string());
    ASSERT_EQ(run.exit_code, 0) << run.err;
    // The laser plane from the truth: n . p + d = 0.
    const std::string sensor = Slurp(dir_ / "sim/truth/sensor.yaml");
    std::smatch m;
    ASSERT_TRUE(std::regex_search(
        sensor, m, std::regex(R"(normal: \[([^,]+), ([^,]+), ([^\]]+)\]\n  d_mm: ([^\n]+))")));
    plane_ = std::string(m[1]) + "," + std::string(m[2]) + "," + std::string(m[3]) + "," +
             std::string(m[4]);
    // A cell whose vision robot is nominal (joint offsets zeroed): what a user starts from.
    const std::string truth = Slurp(dir_ / "sim/truth/cell.yaml");
    Spit(dir_ / "nominal_cell.yaml",
         std::regex_replace(truth, std::regex(R"(joint_offset_rad: [-0-9.e]+)"),
                            "joint_offset_rad: 0"));
  }
  static void TearDownTestSuite() { RemoveTestDir(dir_); }

  static std::string Common(const std::string& cell) {
    return " --cell " + cell + " --camera " + (dir_ / "sim/truth/camera.cameramodel").string() +
           " --sweeps " + (dir_ / "sim/records/sphere_sweeps.yaml").string() +
           " --laser-plane=" + plane_;
  }

  static fs::path dir_;
  static std::string plane_;
};
fs::path CalibrateJointsCli::dir_;
std::string CalibrateJointsCli::plane_;

TEST_F(CalibrateJointsCli, JointsUpdatesOnlyTheRobotAndWritesAVersionedJson) {
  const fs::path cell = dir_ / "joints_cell.yaml";
  fs::copy_file(dir_ / "nominal_cell.yaml", cell, fs::copy_options::overwrite_existing);
  const std::string before = Slurp(cell);
  const CommandResult run =
      RunCli("calibrate joints" + Common(cell.string()) + " --json " +
             (dir_ / "joints.json").string() + " --report " + (dir_ / "joints.html").string());
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json j = nlohmann::json::parse(Slurp(dir_ / "joints.json"));
  EXPECT_EQ(j["format"], "lasercell.joint_calibration");
  EXPECT_EQ(j["version"], 1);
  EXPECT_TRUE(j["converged"].get<bool>());
  ASSERT_EQ(j["joint_offsets"].size(), 6u);
  // The cell's link lengths are the true ones here: the sweeps are unbiased, no model warning
  // (the biased case: JointIdentification.DhDeltasNameTheUnidentifiableAndFixThePositioning).
  EXPECT_LT(j["sweep_bias_ratio"].get<double>(), 4.0);
  EXPECT_EQ(run.out.find("model misses something"), std::string::npos) << run.out;
  // Sphere centres free: joint 1 is not identifiable and stays at its input value.
  EXPECT_FALSE(j["joint_offsets"][0]["estimated"].get<bool>());
  EXPECT_EQ(j["observability"]["unidentifiable"][0]["parameters"][0], "joint_offset_1");
  // The true offsets (truth/cell.yaml's vision robot) of joints 2..6 are recovered.
  const lasercell::FrameGraph truth =
      lasercell::LoadFrameGraph((dir_ / "sim/truth/cell.yaml").string());
  const auto& true_chain = dynamic_cast<const lasercell::DhChain&>(truth.Robot("vision_robot"));
  for (int k = 1; k < 6; ++k) {
    const double true_deg = true_chain.joints()[k].joint_offset_rad * 180 / M_PI;
    EXPECT_NEAR(j["joint_offsets"][k]["offset_deg"].get<double>(), true_deg, 0.005) << k + 1;
  }
  // The cell: the vision robot changed, nothing else; it reads back and rewrites identically.
  const std::string after = Slurp(cell);
  const lasercell::FrameGraph updated = lasercell::LoadFrameGraph(cell.string());
  EXPECT_EQ(lasercell::FrameGraphToYaml(updated), after);
  const lasercell::FrameGraph original = lasercell::FrameGraphFromYaml(before, "nominal_cell.yaml");
  EXPECT_EQ(updated.static_edges().size(), original.static_edges().size());
  for (std::size_t e = 0; e < original.static_edges().size(); ++e) {
    EXPECT_EQ(lasercell::PoseToFileNotation(updated.static_edges()[e].parent_from_child),
              lasercell::PoseToFileNotation(original.static_edges()[e].parent_from_child));
  }
  const auto& chain = dynamic_cast<const lasercell::DhChain&>(updated.Robot("vision_robot"));
  EXPECT_NEAR(chain.joints()[2].joint_offset_rad * 180 / M_PI,
              j["joint_offsets"][2]["offset_deg"].get<double>(), 1e-12);
  EXPECT_NE(Slurp(dir_ / "joints.html").find("<svg"), std::string::npos);
}

// With the touched sphere tops (records/touches.yaml, 0.05 mm per axis) the centres are known
// in vision_base through the cell, and joint 1 becomes identifiable: all 6 offsets recovered.
TEST_F(CalibrateJointsCli, TouchesMakeJointOneIdentifiable) {
  const fs::path cell = dir_ / "touch_cell.yaml";
  fs::copy_file(dir_ / "nominal_cell.yaml", cell, fs::copy_options::overwrite_existing);
  const CommandResult run = RunCli("calibrate joints" + Common(cell.string()) + " --touches " +
                                   (dir_ / "sim/records/touches.yaml").string() + " --json " +
                                   (dir_ / "touch.json").string());
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json j = nlohmann::json::parse(Slurp(dir_ / "touch.json"));
  EXPECT_TRUE(j["observability"]["unidentifiable"].empty());
  // The predicted positioning 1 sigma of the working point, at every sweep's pose.
  const auto& pos = j["positioning_sigma_mm"];
  EXPECT_EQ(pos["poses"].get<std::size_t>(), j["sweeps"].size());
  EXPECT_EQ(pos["includes"], "robot parameters (hand-eye held)");
  EXPECT_GT(pos["rms"].get<double>(), 0.0);
  EXPECT_LE(pos["rms"].get<double>(), pos["max"].get<double>());
  EXPECT_NE(run.out.find("positioning 1-sigma"), std::string::npos) << run.out;
  const lasercell::FrameGraph truth =
      lasercell::LoadFrameGraph((dir_ / "sim/truth/cell.yaml").string());
  const auto& true_chain = dynamic_cast<const lasercell::DhChain&>(truth.Robot("vision_robot"));
  for (int k = 0; k < 6; ++k) {
    const double true_deg = true_chain.joints()[k].joint_offset_rad * 180 / M_PI;
    EXPECT_TRUE(j["joint_offsets"][k]["estimated"].get<bool>());
    EXPECT_NEAR(j["joint_offsets"][k]["offset_deg"].get<double>(), true_deg, 0.005) << k + 1;
  }
}

TEST_F(CalibrateJointsCli, HandEyeLaserUpdatesTheFlangeSensorEdge) {
  // The true robot model (as after joint calibration) and a perturbed hand-eye start.
  const fs::path cell = dir_ / "he_cell.yaml";
  fs::copy_file(dir_ / "sim/truth/cell.yaml", cell, fs::copy_options::overwrite_existing);
  const CommandResult run = RunCli("calibrate handeye-laser" + Common(cell.string()) + " --json " +
                                   (dir_ / "he.json").string());
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json j = nlohmann::json::parse(Slurp(dir_ / "he.json"));
  EXPECT_EQ(j["format"], "lasercell.laser_hand_eye");
  EXPECT_EQ(j["version"], 1);
  EXPECT_EQ(j["positioning_sigma_mm"]["includes"], "hand-eye only (robot held)");
  const lasercell::FrameGraph truth =
      lasercell::LoadFrameGraph((dir_ / "sim/truth/cell.yaml").string());
  const Eigen::Isometry3d x_true = truth.Transform("vision_flange", "sensor");
  const auto& t = j["vision_flange_from_sensor"]["translation_mm"];
  const Eigen::Vector3d t_est(t[0].get<double>(), t[1].get<double>(), t[2].get<double>());
  // The 12-pose default set sees every sphere at the same range: the camera centre is weakly
  // determined (calib/laser_hand_eye tests); the error must lie within the reported 4 sigma.
  const auto& s = j["covariance"]["sigma_translation_mm"];
  const double sigma = std::hypot(s[0].get<double>(), s[1].get<double>(), s[2].get<double>());
  EXPECT_LT((t_est - x_true.translation()).norm(), 4 * sigma);
  EXPECT_GT(sigma, 0.0);
  const lasercell::FrameGraph updated = lasercell::LoadFrameGraph(cell.string());
  EXPECT_LT((updated.Transform("vision_flange", "sensor").translation() - t_est).norm(), 1e-9);
  EXPECT_EQ(lasercell::FrameGraphToYaml(updated), Slurp(cell));
}

TEST_F(CalibrateJointsCli, TakesTheLaserPlaneFromTheCellWhenNotGiven) {
  // The cell's calibrated `laser` plane (what `calibrate laser` writes) replaces --laser-plane.
  lasercell::FrameGraph graph = lasercell::LoadFrameGraph((dir_ / "nominal_cell.yaml").string());
  std::vector<double> v;
  std::stringstream in(plane_);
  for (std::string item; std::getline(in, item, ',');) v.push_back(std::stod(item));
  ASSERT_EQ(v.size(), 4u);
  lasercell::LaserPlaneEntry entry;
  entry.normal = Eigen::Vector3d(v[0], v[1], v[2]);
  entry.point_mm = -v[3] * entry.normal;
  graph.SetLaserPlane("laser", entry);
  const fs::path cell = dir_ / "cell_with_plane.yaml";
  Spit(cell, lasercell::FrameGraphToYaml(graph));
  // Sanitizer time: both runs (from the nominal robot, slow to converge) use 300 points per
  // sweep instead of 5000; they are compared with each other, not with the truth.
  const std::string points = kSanitizerBuild ? " --max-points 300" : "";
  const std::string args = " --cell " + cell.string() + " --camera " +
                           (dir_ / "sim/truth/camera.cameramodel").string() + " --sweeps " +
                           (dir_ / "sim/records/sphere_sweeps.yaml").string() + points;
  CommandResult run =
      RunCli("calibrate handeye-laser" + args + " --json " + (dir_ / "he_cellplane.json").string());
  ASSERT_EQ(run.exit_code, 0) << run.err;
  // The same as giving the plane on the command line.
  const fs::path cell2 = dir_ / "cell_with_plane_2.yaml";
  fs::copy_file(dir_ / "nominal_cell.yaml", cell2, fs::copy_options::overwrite_existing);
  run = RunCli("calibrate handeye-laser" + Common(cell2.string()) + points + " --json " +
               (dir_ / "he_cliplane.json").string());
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json a = nlohmann::json::parse(Slurp(dir_ / "he_cellplane.json"));
  const nlohmann::json b = nlohmann::json::parse(Slurp(dir_ / "he_cliplane.json"));
  EXPECT_EQ(a["format"], "lasercell.laser_hand_eye");
  // Same plane up to rounding (the cell stores a point, d = -n . p0 is recomputed).
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(a["vision_flange_from_sensor"]["translation_mm"][k].get<double>(),
                b["vision_flange_from_sensor"]["translation_mm"][k].get<double>(), 1e-6);
  }
  EXPECT_NEAR(a["residual_rms_mm"].get<double>(), b["residual_rms_mm"].get<double>(), 1e-9);
}

TEST_F(CalibrateJointsCli, MissingLaserPlaneAndUnknownSetAreNamed) {
  const std::string cam = (dir_ / "sim/truth/camera.cameramodel").string();
  const std::string sweeps = (dir_ / "sim/records/sphere_sweeps.yaml").string();
  const std::string cell = (dir_ / "nominal_cell.yaml").string();
  CommandResult run =
      RunCli("calibrate joints --cell " + cell + " --camera " + cam + " --sweeps " + sweeps);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_THAT(run.err, HasSubstr("--laser-plane"));
  run = RunCli("calibrate joints" + Common(cell) + " --set nope");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_THAT(run.err, HasSubstr("has no sweep set 'nope'"));
  run = RunCli("calibrate joints --cell " + cell + " --camera " + cam + " --sweeps " + sweeps +
               " --laser-plane=0,0,0,5");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_THAT(run.err, HasSubstr("--laser-plane: the normal must be non-zero"));
  run = RunCli("calibrate joints" + Common(cell) + " --up 0,1");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_THAT(run.err, HasSubstr("--up"));
}

}  // namespace
}  // namespace lasercell::test
