#pragma once
// The real kuka2 eye-in-hand set (Ali et al., Sensors 19(12):2837, 2019; no licence stated, so
// nothing of it is bundled) prepared from its originals: the 28 images `im_01..28.png`
// (1920 x 1200, 24 x 17 inner corners = 25 x 18 squares of 15 mm) and RobotPosesVec.txt (base ->
// TCP, metres; read with LoadRobotPoses(path, "kuka")). Corners: calib::DetectTarget (the
// detector of `calibrate camera` and `calibrate handeye --images`); intrinsics: the documented
// stand-in, OpenCV calibrateCamera (k1 k2 p1 p2 k3, mrcal LENSMODEL_OPENCV5) on those detections.
// The one loader of `lasercell bench calibration` and the tests.

#include <optional>
#include <string>

#include "calib/camera_model.hpp"
#include "calib/pose_io.hpp"
#include "calib/target_detection.hpp"

namespace lasercell::calib {

/// The prepared set.
struct Kuka2Set {
  std::string dir;                    ///< The set's folder.
  ChessboardDetections detections;    ///< Corners of every image (image names im_NN.png).
  std::optional<CameraModel> camera;  ///< The stand-in intrinsics (unset when error is set).
  double calibration_rms_px = 0;      ///< calibrateCamera's RMS reprojection error, px.
  /// Non-empty when a board was not found or an image could not be read ("kuka2: PATH: why").
  std::string error;
  /// kUnreadable when an image could not be decoded, kNotFound when a board was not found.
  DetectionStatus error_status = DetectionStatus::kFound;
};

/// Number of images of the set.
inline constexpr int kKuka2Images = 28;

/// True when `dir` holds the set's first image and its robot poses.
bool HasKuka2Set(const std::string& dir);

/// Detects the board in the 28 images (with `detection`, e.g. search_downscale 2 for tests:
/// the same corners, 4 times faster) and calibrates the stand-in intrinsics. A board that is not
/// found stops the preparation and is reported in `error`; FileError when an image file cannot
/// be read.
Kuka2Set LoadKuka2Set(const std::string& dir, const DetectionOptions& detection = {});

}  // namespace lasercell::calib
