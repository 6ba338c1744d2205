#pragma once
// The real kuka2 eye-in-hand set (Ali et al., Sensors 19(12):2837, 2019; no licence stated, so
// nothing of it is bundled) prepared for the tests from the shared originals: the 28 images
// `im_01..28.png` (1920 x 1200, 24 x 17 inner corners, 15 mm squares) and RobotPosesVec.txt
// (base -> TCP, metres). Corners: OpenCV findChessboardCornersSB on the half-resolution image
// (4x fewer pixels: the library's full-resolution CALIB_CB_ACCURACY search, used by `lasercell
// bench calibration`, takes ~1 s per image, too slow for a unit test run once per test process),
// then cornerSubPix (5 x 5 half window) at full resolution, as the library detector
// calib/internal/chessboard_cv.hpp refines; intrinsics: the documented stand-in, OpenCV
// calibrateCamera (k1 k2 p1 p2 k3, mrcal LENSMODEL_OPENCV5) on those detections — the same recipe
// as `lasercell bench calibration`. Computed once per test process (detection is the slow part).
#include <gtest/gtest.h>

#include <cstdio>
#include <memory>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <string>
#include <vector>

#include "calib/camera_model.hpp"
#include "calib/internal/chessboard_cv.hpp"
#include "calib/pose_io.hpp"
#include "tests/shared_data.hpp"

namespace lasercell::calib::realdata {

struct Kuka2 {
  std::string dir;  ///< The shared set's folder.
  ChessboardDetections detections;
  std::unique_ptr<CameraModel> camera;
  double calibration_rms_px = 0;
  std::string error;  ///< Non-empty when a board was not found.
};

/// Inner corners (OpenCV order, pixel (0, 0) = centre of the top-left pixel), or nullopt.
inline std::optional<std::vector<Eigen::Vector2d>> DetectKuka2Corners(const std::string& path,
                                                                      int cols, int rows,
                                                                      int* width, int* height) {
  const cv::Mat gray = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (gray.empty()) return std::nullopt;
  *width = gray.cols;
  *height = gray.rows;
  cv::Mat half;
  cv::resize(gray, half, cv::Size(gray.cols / 2, gray.rows / 2), 0, 0, cv::INTER_AREA);
  std::vector<cv::Point2f> corners;
  if (!cv::findChessboardCornersSB(half, cv::Size(cols, rows), corners) ||
      corners.size() != static_cast<std::size_t>(cols * rows)) {
    return std::nullopt;
  }
  // Half-resolution pixel centre x maps to full-resolution 2 x + 0.5 (2 x 2 area average).
  for (auto& c : corners) c = cv::Point2f(2.f * c.x + 0.5f, 2.f * c.y + 0.5f);
  cv::cornerSubPix(gray, corners, cv::Size(5, 5), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 100, 1e-4));
  std::vector<Eigen::Vector2d> out;
  for (const auto& c : corners) out.emplace_back(c.x, c.y);
  return out;
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
    const auto board = internal::ChessboardCorners(det.cols, det.rows, det.square_mm);
    std::vector<std::vector<cv::Point3f>> obj;
    std::vector<std::vector<cv::Point2f>> img;
    for (int i = 1; i <= 28; ++i) {
      char name[32];
      std::snprintf(name, sizeof name, "im_%02d.png", i);
      const auto c = DetectKuka2Corners(dir + "/" + name, det.cols, det.rows, &det.width_px,
                                        &det.height_px);
      if (!c) {
        k->error = std::string("kuka2: board not found in ") + name;
        return k;
      }
      det.images.push_back(name);
      det.corners_px.push_back(*c);
      std::vector<cv::Point3f> o;
      std::vector<cv::Point2f> p;
      for (std::size_t j = 0; j < c->size(); ++j) {
        o.emplace_back(static_cast<float>(board[j].x()), static_cast<float>(board[j].y()), 0.f);
        p.emplace_back(static_cast<float>((*c)[j].x()), static_cast<float>((*c)[j].y()));
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
