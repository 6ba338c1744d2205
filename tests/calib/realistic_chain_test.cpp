// The calibration chain on the realistic simulation profile, as a user runs it from the command
// line: `calibrate camera` on the rendered chessboard images, `calibrate laser` through that
// calibrated camera (never the true one), `calibrate handeye` through it too.
//
// Simulation profile: realistic (datasets/SIMULATOR.md, Profiles: noisier, blurrier images with
// detector-level corner noise, speckle and reflections on the plate sweeps, timestamp and
// encoder noise), seed 413 (not a seed any tool was tuned on). The robot posing the hand-eye
// views is the simulated truth's: the robot's own calibration on this profile is measured by
// scripts/bench-robot-realistic (BENCHMARKS.md), not here.
//
// Asserted, with tolerances from the noise each tool reports:
//  - camera: fx fy cx cy within 4 reported sigma of the truth;
//  - laser plane: normal and offset within 3 reported sigma, where the sigma now holds the
//    calibrated camera's uncertainty (calib/camera_uncertainty.hpp). The camera's part is what
//    keeps the plane from the 0.01 deg / 0.02 mm target at this image noise, and without it the
//    stated sigma would not cover the error (checked: the plane's own part alone does not);
//  - hand-eye (images): error within 3 reported sigma (with the camera's part), and the
//    solver's own part within a third of the target (0.02 deg / 0.05 mm). The target itself is
//    not met through a camera calibrated at this noise: the camera's part alone is ~0.08 mm.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "calib/camera_model.hpp"
#include "core/frame_graph.hpp"
#include "core/se3.hpp"
#include "datasets/sensor.hpp"
#include "datasets/sim_profile.hpp"
#include "datasets/simulate.hpp"
#include "tests/calib/realistic_cli_util.hpp"
#include "tests/cli_util.hpp"
#include "tests/sanitizer_scale.hpp"

namespace lasercell {
namespace {

namespace fs = std::filesystem;
using test::CommandResult;
using test::RunCliMerged;

TEST(RealisticChain, CameraThenLaserPlaneThenHandEyeFromTheirOwnCaptures) {
  if (test::kSanitizerBuild) {
    GTEST_SKIP() << "35 rendered images and three calibrations take minutes under the "
                    "sanitizer; their pieces run there in CameraUncertainty, LaserPlane* and "
                    "HandEyeCli";
  }
  datasets::SimConfig config = test::RealisticConfigWithoutCaptures(413);
  config.capture_planes = config.capture_chessboard_images = true;
  config.capture_hand_eye_images = true;
  const test::TestDir dir("realistic_chain");
  const fs::path sim = dir.path() / "sim";
  datasets::SimulateCell(config, sim.string(), {}, 0);
  const datasets::CellTruth truth = datasets::MakeCellTruth(config);
  const fs::path cam = dir.path() / "camera.cameramodel";
  const fs::path cell = dir.path() / "cell.yaml";

  // 1. The camera from its rendered chessboard views.
  CommandResult r = test::CalibrateCameraByCli(sim, cam, dir.path() / "cam.json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const calib::CameraModel camera = calib::LoadCameraModel(cam.string());
  ASSERT_EQ(camera.intrinsics_covariance().rows(), camera.NumIntrinsics());
  const std::vector<double>& truth_intrinsics = truth.sensor.camera.intrinsics();
  for (int i = 0; i < 4; ++i) {
    const double sigma = std::sqrt(camera.intrinsics_covariance()(i, i));
    const double error = camera.intrinsics()[i] - truth_intrinsics[i];
    std::printf("[ measured ] realistic camera intrinsic %d: error %+.4f px, 1 sigma %.4f px\n", i,
                error, sigma);
    EXPECT_LT(std::abs(error), 4 * sigma) << "intrinsic " << i << "\n" << r.out;
  }

  // 2. The laser plane through the calibrated camera.
  const fs::path laser_json = dir.path() / "laser.json";
  r = test::CalibrateLaserByCli(sim, cam, cell, laser_json);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const nlohmann::json laser = nlohmann::json::parse(test::Slurp(laser_json));
  ASSERT_TRUE(laser.at("camera_uncertainty_included").get<bool>()) << laser.dump();
  const LaserPlaneEntry plane = LoadFrameGraph(cell.string()).laser_planes().at("laser");
  ASSERT_TRUE(plane.camera_covariance.has_value());  // what a job must not count twice
  // The error modes: the camera's axes (each with its refitted plane), then the fit's own; they
  // add up to the plane's covariance, and the camera's ones to its camera part.
  ASSERT_GT(plane.error_modes.size(), 3u);
  Eigen::Matrix4d all = Eigen::Matrix4d::Zero(), camera_modes = Eigen::Matrix4d::Zero();
  for (const SensorErrorMode& m : plane.error_modes) {
    all += m.plane_step * m.plane_step.transpose();
    if (m.intrinsics_step.empty()) continue;
    EXPECT_EQ(m.intrinsics_step.size(), static_cast<std::size_t>(camera.NumIntrinsics()));
    camera_modes += m.plane_step * m.plane_step.transpose();
  }
  EXPECT_LT((all - *plane.covariance).cwiseAbs().maxCoeff(),
            1e-6 * plane.covariance->cwiseAbs().maxCoeff());
  EXPECT_LT((camera_modes - *plane.camera_covariance).cwiseAbs().maxCoeff(),
            1e-6 * plane.camera_covariance->cwiseAbs().maxCoeff());
  Eigen::Vector4d t = truth.sensor.laser.Coefficients();
  if (t(3) > 0) t = -t;
  const double normal_error_deg =
      std::atan2(plane.normal.cross(t.head<3>()).norm(), plane.normal.dot(t.head<3>())) * 180 /
      M_PI;
  const double offset_error_mm = plane.OffsetMm() - t(3);
  const double normal_sigma = laser.at("normal_sigma_deg").get<double>();
  const double offset_sigma = laser.at("offset_sigma_mm").get<double>();
  const double camera_normal_sigma = laser.at("camera_normal_sigma_deg").get<double>();
  const double camera_offset_sigma = laser.at("camera_offset_sigma_mm").get<double>();
  std::printf(
      "[ measured ] realistic laser plane: normal %.5f deg (1 sigma %.5f, the camera's %.5f), "
      "offset %+.4f mm (1 sigma %.4f, the camera's %.4f)\n",
      normal_error_deg, normal_sigma, camera_normal_sigma, offset_error_mm, offset_sigma,
      camera_offset_sigma);
  EXPECT_LT(normal_error_deg, 3 * normal_sigma) << r.out;
  EXPECT_LT(std::abs(offset_error_mm), 3 * offset_sigma) << r.out;
  // The plane's own fit determines it to better than the targets; the camera's part is what
  // the chain adds.
  const double own_normal =
      std::sqrt(normal_sigma * normal_sigma - camera_normal_sigma * camera_normal_sigma);
  const double own_offset =
      std::sqrt(offset_sigma * offset_sigma - camera_offset_sigma * camera_offset_sigma);
  EXPECT_LT(own_normal, 0.01) << r.out;
  EXPECT_LT(own_offset, 0.02) << r.out;

  // 3. The eye-in-hand camera through the calibrated camera.
  const fs::path he_cell = dir.path() / "handeye_cell.yaml";
  fs::copy_file(sim / "truth/cell.yaml", he_cell, fs::copy_options::overwrite_existing);
  r = RunCliMerged("calibrate handeye --cell " + he_cell.string() + " --camera " + cam.string() +
                   " --images '" + (sim / "images").string() + "/hand_eye_*.png' --board " +
                   "chessboard:" + std::to_string(config.chessboard.board.cols) + "x" +
                   std::to_string(config.chessboard.board.rows) + ":" +
                   std::to_string(static_cast<int>(config.chessboard.board.square_mm)) +
                   " --poses " + (sim / "records/hand_eye_images.yaml").string() + " --json " +
                   (dir.path() / "handeye.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const Eigen::Isometry3d got =
      LoadFrameGraph(he_cell.string()).Transform("vision_flange", "sensor");
  const double rot_deg = RotationDistance(got, truth.vision_flange_from_sensor) * 180 / M_PI;
  const double trans_mm = TranslationDistance(got, truth.vision_flange_from_sensor);
  const nlohmann::json he = nlohmann::json::parse(test::Slurp(dir.path() / "handeye.json"));
  ASSERT_TRUE(he.at("camera_uncertainty_included").get<bool>()) << he.dump();
  const nlohmann::json& sigma = he.at("flange_from_camera_sigma");
  const nlohmann::json& camera_part = he.at("flange_from_camera_sigma_camera_part");
  std::printf(
      "[ measured ] realistic hand-eye through the calibrated camera: %.4f deg, %.4f mm; "
      "1 sigma %s (the camera's part %s)\n",
      rot_deg, trans_mm, sigma.dump().c_str(), camera_part.dump().c_str());
  // Error within 3 sigma of the reported covariance (norms over the axes).
  const auto norm = [](const nlohmann::json& v) {
    return std::sqrt(v[0].get<double>() * v[0].get<double>() +
                     v[1].get<double>() * v[1].get<double>() +
                     v[2].get<double>() * v[2].get<double>());
  };
  const double rot_sigma = norm(sigma.at("rotation_deg"));
  const double trans_sigma = norm(sigma.at("translation_mm"));
  EXPECT_LT(rot_deg, 3 * rot_sigma) << r.out;
  EXPECT_LT(trans_mm, 3 * trans_sigma) << r.out;
  // The solver's own part meets the targets (0.02 deg / 0.05 mm); the camera's does not: a
  // focal length known to ~0.13 px (1.2e-4) scales the ~700 mm board distances by ~0.08 mm,
  // which no number of hand-eye views averages away (BENCHMARKS.md states the shortfall).
  const double cam_rot = norm(camera_part.at("rotation_deg"));
  const double cam_trans = norm(camera_part.at("translation_mm"));
  EXPECT_LT(std::sqrt(rot_sigma * rot_sigma - cam_rot * cam_rot), 0.02 / 3) << r.out;
  EXPECT_LT(std::sqrt(trans_sigma * trans_sigma - cam_trans * cam_trans), 0.05 / 3) << r.out;
}

}  // namespace
}  // namespace lasercell
