// Fuzz targets for calib's files: the mrcal .cameramodel, touches files, robot-pose files (every
// layout) and chessboard-corner files. Where lasercell has a writer, what it wrote must read back
// to the same text.

#include <string>
#include <vector>

#include "calib/camera_model.hpp"
#include "calib/half_sphere_calibration.hpp"
#include "calib/pose_io.hpp"
#include "tests/fuzz/harness/fuzz_target.hpp"

namespace lasercell::fuzz {

static std::vector<std::string> CameraModelSeeds() {
  const calib::CameraModel opencv8(
      "LENSMODEL_OPENCV8", {1200, 1190, 640.5, 480.25, -0.1, 0.05, 1e-4, -2e-4, 0.01, 0, 0, 0.001},
      1280, 960);
  const calib::CameraModel pinhole("LENSMODEL_PINHOLE", {800, 800, 511.5, 383.5}, 1024, 768);
  return {calib::CameraModelText(opencv8, "seed camera"), calib::CameraModelText(pinhole)};
}

LASERCELL_FUZZ_TARGET(cameramodel, CameraModelSeeds) {
  const calib::CameraModel model = calib::ParseCameraModel(std::string(bytes), "fuzz.cameramodel");
  const std::string written = calib::CameraModelText(model);
  calib::CameraModel again = model;
  LASERCELL_FUZZ_MUST_ACCEPT(again = calib::ParseCameraModel(written, "written.cameramodel"));
  LASERCELL_FUZZ_ASSERT(calib::CameraModelText(again) == written,
                        ".cameramodel: write(read(write(read(x)))) differs from write(read(x))");
}

// Twelve spheres on a 3 x 4 grid, one touch each, joints recorded for every other touch.
static std::vector<std::string> TouchesSeeds() {
  std::string text =
      "format: lasercell.touches\nversion: 1\nrobot: handling_robot\nframe: handling_base\n"
      "handling_flange_from_tool_tip: {translation_mm: [0, 0, 150], rotation_wxyz: [1, 0, 0, "
      "0]}\nstated_sigma_mm: 0.02\nsphere_radius_mm: 20\nsphere_radius_tolerance_mm: 0.005\n"
      "touches:\n";
  for (int k = 0; k < 12; ++k) {
    text += "  - sphere: " + std::to_string(k) + "\n    point_in_handling_base: [" +
            std::to_string(900 + 200 * (k / 4)) + ", " + std::to_string(-300 + 150 * (k % 4)) +
            ", 250.5]\n    joints_rad: " + (k % 2 == 0 ? "[0.1, -0.5, 0.9, 0, 1.2, 0.3]" : "null") +
            "\n";
  }
  return {text};
}

LASERCELL_FUZZ_TARGET(touches, TouchesSeeds) {
  const calib::SphereTouches t = calib::ParseTouchesYaml(std::string(bytes), "fuzz_touches.yaml");
  for (const calib::SphereTouch& touch : t.touches) {
    LASERCELL_FUZZ_ASSERT(touch.point_in_handling_base.allFinite(), "touches: a non-finite point");
  }
}

// The first byte chooses the layout the rest is read as (the CLI's --poses-format).
static const char* const kPoseFormats[] = {"auto", "kuka", "yaml", "xyzwpr", "xyzabc"};

static std::vector<std::string> RobotPoseSeeds() {
  calib::RobotPoses poses;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(500, -250, 1125);
  poses.base_from_flange = {pose, pose};
  poses.images = {"a.png", "b.png"};
  return {
      WithSelector(2, calib::RobotPosesYaml(poses)),
      WithSelector(1,
                   "# comment\n0 -1 0 0.5  1 0 0 -0.25  0 0 1 1.125  0 0 0 1\n"
                   "1,0,0,0.6,0,1,0,0.1,0,0,1,0.9,0,0,0,1\n"),
      WithSelector(
          3, "# x y z w p r\n\n 100, 200, 300, 90, 0, 0\r\n   \n# next\n-100\t50 400 0 0 -45"),
      WithSelector(
          4,
          "  \n{ \"RobPoses\": [ [100, 200, 300, 90, 0, 0],\n [-100, 50, 400.0, 0, 0, -45] ] }\n"),
  };
}

LASERCELL_FUZZ_TARGET(robot_poses, RobotPoseSeeds) {
  if (bytes.empty()) return;
  const char* format = kPoseFormats[static_cast<unsigned char>(bytes[0]) % 5];
  const calib::RobotPoses poses =
      calib::ParseRobotPoses(std::string(bytes.substr(1)), "fuzz_poses.txt", format);
  LASERCELL_FUZZ_ASSERT(
      poses.images.empty() || poses.images.size() == poses.base_from_flange.size(),
      "robot poses: image names and poses disagree in number");
  for (const Eigen::Isometry3d& p : poses.base_from_flange) {
    LASERCELL_FUZZ_ASSERT(p.matrix().allFinite(), "robot poses: a non-finite pose");
  }
  // The file stores rotations as quaternions, read into matrices: equal to rounding.
  calib::RobotPoses again;
  LASERCELL_FUZZ_MUST_ACCEPT(
      again = calib::ParseYamlPoses(calib::RobotPosesYaml(poses), "written_poses.yaml"));
  LASERCELL_FUZZ_ASSERT(again.images == poses.images &&
                            again.base_from_flange.size() == poses.base_from_flange.size(),
                        "robot poses: images or pose count changed by write -> read");
  for (std::size_t i = 0; i < poses.base_from_flange.size(); ++i) {
    const Eigen::Matrix4d a = poses.base_from_flange[i].matrix();
    const Eigen::Matrix4d b = again.base_from_flange[i].matrix();
    LASERCELL_FUZZ_ASSERT((a - b).cwiseAbs().maxCoeff() <= 1e-12 * (1.0 + a.cwiseAbs().maxCoeff()),
                          "robot poses: a pose changed by write -> read beyond rounding");
  }
}

static std::vector<std::string> CornerSeeds() {
  calib::ChessboardDetections d;
  d.board = calib::BoardSpec::Chessboard(3, 2, 25.0);
  d.width_px = 640;
  d.height_px = 480;
  d.images = {"left01.jpg", "left02.jpg"};
  for (int i = 0; i < 2; ++i) {
    std::vector<Eigen::Vector2d> corners;
    for (int k = 0; k < 6; ++k)
      corners.emplace_back(100.25 + 30 * (k % 3) + i, 80.5 + 30 * (k / 3));
    d.corners_px.push_back(corners);
  }
  return {calib::ChessboardDetectionsText(d, "seed")};
}

LASERCELL_FUZZ_TARGET(corners, CornerSeeds) {
  const calib::ChessboardDetections d =
      calib::ParseChessboardDetections(std::string(bytes), "fuzz_corners.txt");
  LASERCELL_FUZZ_ASSERT(d.corners_px.size() == d.images.size(),
                        "corners: images and their corner lists disagree in number");
  const std::string written = calib::ChessboardDetectionsText(d);
  calib::ChessboardDetections again;
  LASERCELL_FUZZ_MUST_ACCEPT(again = calib::ParseChessboardDetections(written, "written.txt"));
  LASERCELL_FUZZ_ASSERT(calib::ChessboardDetectionsText(again) == written,
                        "corners: write(read(write(read(x)))) differs from write(read(x))");
}

}  // namespace lasercell::fuzz
