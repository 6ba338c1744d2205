// `lasercell calibrate handeye` end to end on the real kuka2 set (from ../shared/data when present,
// else skipped with the reason: not redistributable; its corners and stand-in intrinsics are
// computed by the test from the images, see kuka2_data.hpp, and written as CLI input files):
// the cell gets only the vision_flange -> sensor edge, the JSON re-reads with its version and
// poses in the file notation, the report has its plots; bad inputs exit 2 with a named error.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>

#include "calib/pose_io.hpp"
#include "core/frame_graph.hpp"
#include "core/io/file_util.hpp"
#include "core/random.hpp"
#include "datasets/calibration_captures.hpp"
#include "datasets/sensor.hpp"
#include "datasets/sim_config.hpp"
#include "datasets/simulate.hpp"
#include "tests/calib/kuka2_data.hpp"
#include "tests/cli_util.hpp"
#include "tests/sanitizer_scale.hpp"

namespace lasercell {
namespace {

namespace fs = std::filesystem;

// Skips the calling test (with the reason) when the shared kuka2 set is absent.
#define REQUIRE_KUKA2()                                                                   \
  do {                                                                                    \
    const calib::realdata::Kuka2* kuka2_ = calib::realdata::LoadKuka2();                  \
    if (kuka2_ == nullptr) LASERCELL_SHARED_DATA_ABSENT(calib::realdata::Kuka2Missing()); \
    ASSERT_TRUE(kuka2_->error.empty()) << kuka2_->error;                                  \
  } while (false)

using ::lasercell::test::CommandResult;
using ::lasercell::test::RunCliMerged;

class HandEyeCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::MakeTestDir("handeye_cli");
    FrameGraph g;
    g.AddFrame("vision_base");
    StaticEdge e;
    e.parent = "vision_base";
    e.child = "vision_flange";
    e.SetParentFromChild(Eigen::Isometry3d::Identity());
    g.SetStaticEdge(e);
    SaveFrameGraph((dir_ / "cell.yaml").string(), g);
  }
  void TearDown() override { test::RemoveTestDir(dir_); }

  // kuka2 input files: the shared RobotPosesVec.txt, and corners.txt / camera.cameramodel
  // written here from the detections computed in the test process (call after REQUIRE_KUKA2).
  std::string Data(const std::string& f) const {
    const calib::realdata::Kuka2* kuka2 = calib::realdata::LoadKuka2();
    if (f == "RobotPosesVec.txt") return kuka2->dir + "/" + f;
    const std::string path = (dir_ / f).string();
    if (!fs::exists(path)) {
      if (f == "corners.txt") {
        io::WriteFileAtomically(path, calib::ChessboardDetectionsText(kuka2->detections, "kuka2"));
      } else {
        calib::SaveCameraModel(path, *kuka2->camera, "kuka2 intrinsics stand-in");
      }
    }
    return path;
  }
  fs::path dir_;
};

TEST_F(HandEyeCli, Kuka2CornersUpdateOnlyTheFlangeEdgeAndWriteJsonAndReport) {
  REQUIRE_KUKA2();
  const std::string cell = (dir_ / "cell.yaml").string();
  const std::string json = (dir_ / "he.json").string();
  const std::string html = (dir_ / "he.html").string();
  const CommandResult r =
      RunCliMerged("calibrate handeye --cell " + cell + " --camera " + Data("camera.cameramodel") +
                   " --corners " + Data("corners.txt") + " --poses " + Data("RobotPosesVec.txt") +
                   " --pose-format kuka --json " + json + " --report " + html);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const FrameGraph g = LoadFrameGraph(cell);
  ASSERT_EQ(g.static_edges().size(), 2u);
  EXPECT_EQ(g.static_edges()[0].child, "vision_flange");  // untouched
  EXPECT_LT(g.static_edges()[0].ParentFromChild().translation().norm(), 1e-12);
  const StaticEdge& he = g.static_edges()[1];
  EXPECT_EQ(he.parent, "vision_flange");
  EXPECT_EQ(he.child, "sensor");
  ASSERT_TRUE(he.covariance.has_value());

  const nlohmann::json j = nlohmann::json::parse(io::ReadFileBytes(json));
  EXPECT_EQ(j["format"], "lasercell.hand_eye");
  EXPECT_EQ(j["version"], 1);
  ASSERT_EQ(j["flange_from_camera"]["translation_mm"].size(), 3u);
  ASSERT_EQ(j["flange_from_camera"]["rotation_wxyz"].size(), 4u);
  ASSERT_EQ(j["base_from_board"]["translation_mm"].size(), 3u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(j["flange_from_camera"]["translation_mm"][k].get<double>(),
                he.parent_from_child.translation_mm[k], 1e-9);
  }
  EXPECT_EQ(j["views"].size(), 28u);
  EXPECT_EQ(j["axxb"]["motions"].size(), 27u);
  EXPECT_GT(j["reprojection_rms_px"].get<double>(), 0.0);
  const std::string page = io::ReadFileBytes(html);
  EXPECT_NE(page.find("data-plot='Corner residuals, u'"), std::string::npos);
  EXPECT_NE(page.find("data-plot='AX-XB rotation residual per motion'"), std::string::npos);
}

TEST_F(HandEyeCli, MismatchedPoseCountIsRejected) {
  REQUIRE_KUKA2();
  std::istringstream in(io::ReadFileBytes(Data("RobotPosesVec.txt")));
  std::string line, text;
  for (int i = 0; i < 27 && std::getline(in, line); ++i) text += line + "\n";
  const std::string poses = (dir_ / "poses27.txt").string();
  io::WriteFileAtomically(poses, text);
  const CommandResult r =
      RunCliMerged("calibrate handeye --cell " + (dir_ / "cell.yaml").string() + " --camera " +
                   Data("camera.cameramodel") + " --corners " + Data("corners.txt") + " --poses " +
                   poses + " --pose-format kuka");
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("28 images in"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("but 27 poses in"), std::string::npos) << r.out;
}

TEST_F(HandEyeCli, PosesInMetresGivenAsYamlAreRejected) {
  REQUIRE_KUKA2();
  const std::string poses = (dir_ / "poses.yaml").string();
  io::WriteFileAtomically(poses,
                          "format: lasercell.robot_poses\nversion: 1\nposes:\n"
                          "  - {translation_mm: [0.5, 0.1, 0.9], rotation_wxyz: [1, 0, 0, 0]}\n"
                          "  - {translation_mm: [0.6, 0.1, 0.9], rotation_wxyz: "
                          "[0.9950041652780258, 0.09983341664682815, 0, 0]}\n");
  const CommandResult r = RunCliMerged("calibrate handeye --cell " + (dir_ / "cell.yaml").string() +
                                       " --camera " + Data("camera.cameramodel") + " --corners " +
                                       Data("corners.txt") + " --poses " + poses);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("look like metres"), std::string::npos) << r.out;
}

// The simulator's record path: records/hand_eye_images.yaml (commanded joints) through the robot
// of the true cell.yaml, corners = the plan's true projections + N(0, 0.03 px) as a corners file;
// the new edge is within the 0.05 mm / 0.02 deg of the true one.
// Simulation profile: ideal (SimConfig{}'s plan and truth; the corner noise is drawn here).
TEST_F(HandEyeCli, SimulatorRecordThroughCellRobot) {
  datasets::SimConfig config;
  const datasets::CellTruth truth = datasets::MakeCellTruth(config);
  const datasets::ChessboardTarget target = config.chessboard;
  const datasets::HandEyeImageSet set = datasets::PlanHandEyeImages(config, truth, target, 11);
  const std::string cell = (dir_ / "cell.yaml").string();
  io::WriteFileAtomically(cell, FrameGraphToYaml(truth.Graph()));
  io::WriteFileAtomically((dir_ / "camera.cameramodel").string(),
                          datasets::MrcalCameraModelText(config.sensor.camera));
  io::WriteFileAtomically((dir_ / "record.yaml").string(),
                          datasets::HandEyeImagesRecordYaml(target, set));
  calib::ChessboardDetections det;
  det.board = target.board;
  det.width_px = config.sensor.camera.width_px;
  det.height_px = config.sensor.camera.height_px;
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0.0, 0.03);
  for (std::size_t i = 0; i < set.images.size(); ++i) {
    det.images.push_back(fs::path(datasets::HandEyeImageFile(i)).filename().string());
    det.corners_px.emplace_back();
    for (const auto& q : set.images[i].corners_px) {
      det.corners_px.back().push_back(q + Draws<2>(noise, rng));
    }
  }
  io::WriteFileAtomically((dir_ / "corners.txt").string(), calib::ChessboardDetectionsText(det));
  const CommandResult r =
      RunCliMerged("calibrate handeye --cell " + cell + " --camera " +
                   (dir_ / "camera.cameramodel").string() + " --corners " +
                   (dir_ / "corners.txt").string() + " --poses " + (dir_ / "record.yaml").string());
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const FrameGraph g = LoadFrameGraph(cell);
  const Eigen::Isometry3d got = g.Transform("vision_flange", "sensor");
  EXPECT_LT(TranslationDistance(got, truth.vision_flange_from_sensor), 0.05) << r.out;
  EXPECT_LT(RotationDistance(got, truth.vision_flange_from_sensor) * 180 / M_PI, 0.02) << r.out;
}

// `calibrate handeye` creates the cell file when it is absent (as `calibrate laser` does): with
// poses in the lasercell YAML form (mm, the true robot's flange poses) no robot of the cell is
// needed, and the new file holds just the vision_flange -> sensor edge.
// Simulation profile: ideal (SimConfig{}'s plan and truth; the corner noise is drawn here).
TEST_F(HandEyeCli, CreatesTheCellFileWhenAbsent) {
  datasets::SimConfig config;
  const datasets::CellTruth truth = datasets::MakeCellTruth(config);
  const datasets::ChessboardTarget target = config.chessboard;
  const datasets::HandEyeImageSet set = datasets::PlanHandEyeImages(config, truth, target, 11);
  io::WriteFileAtomically((dir_ / "camera.cameramodel").string(),
                          datasets::MrcalCameraModelText(config.sensor.camera));
  calib::RobotPoses poses;
  calib::ChessboardDetections det;
  det.board = target.board;
  det.width_px = config.sensor.camera.width_px;
  det.height_px = config.sensor.camera.height_px;
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 0.03);
  for (std::size_t i = 0; i < set.images.size(); ++i) {
    const std::string name = fs::path(datasets::HandEyeImageFile(i)).filename().string();
    poses.base_from_flange.push_back(
        truth.true_vision_robot.BaseFromFlange(set.images[i].joints_rad));
    poses.images.push_back(name);
    det.images.push_back(name);
    det.corners_px.emplace_back();
    for (const auto& q : set.images[i].corners_px) {
      det.corners_px.back().push_back(q + Draws<2>(noise, rng));
    }
  }
  io::WriteFileAtomically((dir_ / "poses.yaml").string(), calib::RobotPosesYaml(poses));
  io::WriteFileAtomically((dir_ / "corners.txt").string(), calib::ChessboardDetectionsText(det));
  const std::string cell = (dir_ / "new" / "cell.yaml").string();
  fs::create_directories(dir_ / "new");
  ASSERT_FALSE(fs::exists(cell));
  const CommandResult r =
      RunCliMerged("calibrate handeye --cell " + cell + " --camera " +
                   (dir_ / "camera.cameramodel").string() + " --corners " +
                   (dir_ / "corners.txt").string() + " --poses " + (dir_ / "poses.yaml").string());
  ASSERT_EQ(r.exit_code, 0) << r.out;
  ASSERT_TRUE(fs::exists(cell));
  const FrameGraph g = LoadFrameGraph(cell);
  ASSERT_EQ(g.static_edges().size(), 1u);
  EXPECT_EQ(g.static_edges()[0].parent, "vision_flange");
  EXPECT_EQ(g.static_edges()[0].child, "sensor");
  const Eigen::Isometry3d got = g.Transform("vision_flange", "sensor");
  EXPECT_LT(TranslationDistance(got, truth.vision_flange_from_sensor), 0.05) << r.out;
  EXPECT_LT(RotationDistance(got, truth.vision_flange_from_sensor) * 180 / M_PI, 0.02) << r.out;
}

// The images path of the CLI: the simulator renders the eye-in-hand chessboard images, the
// shared detector (calib/target_detection) finds the corners, the record's joints pose the
// flange through the cell's (true) robot -> within the 0.05 mm / 0.02 deg.
// Simulation profile: ideal (SimConfig{} with only the hand-eye images captured).
TEST_F(HandEyeCli, SimulatedImagesThroughTheSharedDetector) {
  datasets::SimConfig config;
  config.capture_planes = config.capture_spheres = config.capture_seats = false;
  config.capture_trajectory = config.capture_chessboard_images = false;
  config.capture_laser_line_images = config.write_meshes = false;
  config.capture_joint_poses = config.capture_touches = config.capture_eye_in_hand = false;
  config.capture_hand_eye_images = true;
  // Sanitizer time: 4 of the 15 images (render + detect + solve run the same); the 0.05 mm /
  // 0.02 deg accuracy holds only over the full set and is asserted in the normal build.
  if (test::kSanitizerBuild) config.hand_eye_images.images = 4;
  const fs::path sim = dir_ / "sim_images";
  datasets::SimulateCell(config, sim.string(), {}, 2);
  const std::string cell = (dir_ / "images_cell.yaml").string();
  fs::copy_file(sim / "truth/cell.yaml", cell, fs::copy_options::overwrite_existing);
  const datasets::ChessboardTarget target;
  const std::string spec = "chessboard:" + std::to_string(target.board.cols) + "x" +
                           std::to_string(target.board.rows) + ":" +
                           std::to_string(static_cast<int>(target.board.square_mm));
  const CommandResult r =
      RunCliMerged("calibrate handeye --cell " + cell + " --camera " +
                   (sim / "truth/camera.cameramodel").string() + " --images '" +
                   (sim / "images").string() + "/hand_eye_*.png' --board " + spec + " --poses " +
                   (sim / "records/hand_eye_images.yaml").string());
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const datasets::CellTruth truth = datasets::MakeCellTruth(config);
  const Eigen::Isometry3d got = LoadFrameGraph(cell).Transform("vision_flange", "sensor");
  if (test::StatisticsAsserted()) {
    EXPECT_LT(TranslationDistance(got, truth.vision_flange_from_sensor), 0.05) << r.out;
    EXPECT_LT(RotationDistance(got, truth.vision_flange_from_sensor) * 180 / M_PI, 0.02) << r.out;
  } else {
    EXPECT_LT(TranslationDistance(got, truth.vision_flange_from_sensor), 2.0) << r.out;
  }
  // An unreadable image is a one-line error naming it.
  io::WriteFileAtomically((sim / "images/hand_eye_000.png").string(), "not a png");
  const CommandResult bad =
      RunCliMerged("calibrate handeye --cell " + cell + " --camera " +
                   (sim / "truth/camera.cameramodel").string() + " --images '" +
                   (sim / "images").string() + "/hand_eye_*.png' --board " + spec + " --poses " +
                   (sim / "records/hand_eye_images.yaml").string());
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.out.find("hand_eye_000.png: is not a readable image"), std::string::npos)
      << bad.out;
  fs::remove_all(sim);
}

}  // namespace
}  // namespace lasercell
