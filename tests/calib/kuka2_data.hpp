#pragma once
// The real kuka2 eye-in-hand set (Ali et al., Sensors 19(12):2837, 2019; no licence stated, so
// nothing of it is bundled) prepared for the tests from the shared originals: the 28 images
// `im_01..28.png` (1920 x 1200, 24 x 17 inner corners, 15 mm squares) and RobotPosesVec.txt
// (base -> TCP, metres). Corners: the library detector calib::DetectTarget (the one `calibrate
// camera`, `calibrate handeye --images` and `lasercell bench calibration` use) with the board
// searched at half resolution (search_downscale 2: the SB search takes 1.8 s for the 28 images
// instead of 6.7 s at full resolution, measured; too slow for a unit test run once per test
// process) and refined at full resolution (the same corners as the full-resolution search: the
// bench's kuka2 numbers equal these tests'); intrinsics: the documented stand-in, OpenCV calibrateCamera
// (k1 k2 p1 p2 k3, mrcal LENSMODEL_OPENCV5) on those detections — the same recipe as `lasercell
// bench calibration`. Computed once per test process (detection is the slow part).
#include <gtest/gtest.h>

#include <cstdio>
#include <memory>
#include <opencv2/calib3d.hpp>
#include <string>
#include <vector>

#include "calib/camera_model.hpp"
#include "calib/board.hpp"
#include "calib/pose_io.hpp"
#include "calib/target_detection.hpp"
#include "core/io/file_util.hpp"
#include "tests/shared_data.hpp"

namespace lasercell::calib::realdata {

struct Kuka2 {
  std::string dir;  ///< The shared set's folder.
  ChessboardDetections detections;
  std::unique_ptr<CameraModel> camera;
  double calibration_rms_px = 0;
  std::string error;  ///< Non-empty when a board was not found.
};

/// The board in one kuka2 image, detected as the preamble says.
inline TargetDetection DetectKuka2Corners(const std::string& path, const BoardSpec& board) {
  DetectionOptions options;
  options.search_downscale = 2;
  return DetectTargetInEncodedImage(io::ReadFileBytes(path), board, options);
}

/// The prepared set, or nullptr when it is absent (then SKIP with Kuka2Missing()).
inline const Kuka2* LoadKuka2() {
  static const std::unique_ptr<Kuka2> data = []() -> std::unique_ptr<Kuka2> {
    const std::string dir = lasercell::shared_data::SharedDataSet("handeye_kuka2");
    if (dir.empty()) return nullptr;
    auto k = std::make_unique<Kuka2>();
    k->dir = dir;
    ChessboardDetections& det = k->detections;
    det.cols = 24;
    det.rows = 17;
    det.square_mm = 15.0;
    const BoardSpec spec = det.Board();
    const std::vector<Eigen::Vector3d> board = spec.Corners();
    std::vector<std::vector<cv::Point3f>> obj;
    std::vector<std::vector<cv::Point2f>> img;
    for (int i = 1; i <= 28; ++i) {
      char name[32];
      std::snprintf(name, sizeof name, "im_%02d.png", i);
      const TargetDetection found = DetectKuka2Corners(dir + "/" + name, spec);
      if (!found.found()) {
        k->error = std::string("kuka2: ") + name + ": " + found.message;
        return k;
      }
      det.width_px = found.width;
      det.height_px = found.height;
      det.images.push_back(name);
      det.corners_px.push_back(found.corners_px);
      std::vector<cv::Point3f> o;
      std::vector<cv::Point2f> p;
      for (std::size_t j = 0; j < found.corners_px.size(); ++j) {
        const Eigen::Vector2d& c = found.corners_px[j];
        o.emplace_back(static_cast<float>(board[j].x()), static_cast<float>(board[j].y()), 0.f);
        p.emplace_back(static_cast<float>(c.x()), static_cast<float>(c.y()));
      }
      obj.push_back(o);
      img.push_back(p);
    }
    cv::Mat km, d;
    std::vector<cv::Mat> rv, tv;
    k->calibration_rms_px =
        cv::calibrateCamera(obj, img, cv::Size(det.width_px, det.height_px), km, d, rv, tv);
    std::vector<double> intr = {km.at<double>(0, 0), km.at<double>(1, 1), km.at<double>(0, 2),
                                km.at<double>(1, 2)};
    for (int i = 0; i < 5; ++i) intr.push_back(d.at<double>(i));
    k->camera = std::make_unique<CameraModel>("LENSMODEL_OPENCV5", intr, det.width_px,
                                              det.height_px);
    std::printf("kuka2 stand-in intrinsics: calibrateCamera RMS %.3f px, fx %.2f fy %.2f cx %.2f "
                "cy %.2f\n",
                k->calibration_rms_px, intr[0], intr[1], intr[2], intr[3]);
    return k;
  }();
  return data.get();
}

inline std::string Kuka2Missing() {
  return lasercell::shared_data::SharedDataMissing("handeye_kuka2");
}

}  // namespace lasercell::calib::realdata
