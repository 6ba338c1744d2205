#pragma once
// The composition of `lasercell calibrate camera` (intrinsics from board images), usable
// without the CLI: detect the board in every image (calib/target_detection.hpp), keep the
// views of one image size, and write the results: the versioned JSON (format
// lasercell.camera_calibration, version 1; the HTML report is calib/intrinsics_report.hpp) and
// mrcal's corners cache (vnl "# filename x y level", as mrgingham writes it).

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "calib/board.hpp"
#include "calib/intrinsics.hpp"
#include "calib/target_detection.hpp"
#include "core/progress.hpp"

namespace lasercell::calib {

/// One input image and what became of it before the calibration.
struct CalibrationImage {
  std::string path;
  TargetDetection detection;
  std::string rejection;  ///< Why it gives no view (detection or image size); empty if it does.
};

/// The images, the views they give (one per usable image) and the image size.
struct CalibrationImages {
  std::vector<CalibrationImage> images;
  std::vector<BoardView> views;
  std::vector<int> view_image;  ///< Per view, its index into `images`.
  int width = 0, height = 0;    ///< Of the first image with a board; others must match.
};

/// Detects `board` in every file. An unreadable file is kept as kUnreadable with the reason;
/// `log` (optional) receives "path: message" per image, `progress` ("detect", fraction) after
/// each image.
CalibrationImages DetectCalibrationImages(const std::vector<std::string>& paths,
                                          const BoardSpec& board,
                                          const std::function<void(const std::string&)>& log,
                                          const ProgressCallback& progress = {});

/// Throws InputError when fewer than `min_views` views are usable; the message names the glob
/// `images`, the board and the first three rejections.
void CheckEnoughViews(const CalibrationImages& images, const BoardSpec& board, int min_views,
                      const std::string& images_glob);

/// The mrcal corners cache text: a complete chessboard per image in grid order, or
/// "filename - - -" when the board was not found. OptionError for a board other than a
/// chessboard.
std::string CornersCacheText(const BoardSpec& board, const std::vector<CalibrationImage>& images);

/// CalibrateIntrinsics with the fallback an engineer applies by hand: when an OPENCV8 fit is
/// otherwise usable but folds over somewhere in the imager (IntrinsicsResult::invertible or
/// imager_folds: its rational terms cancel where the boards were and diverge beyond), OPENCV5,
/// with fewer terms to cancel, is fitted too and kept, with a first warning saying so
/// (refitted_because), when it is usable and does not fold or leaves fewer pixels without a ray.
/// Any other model, or an OPENCV8 fit that inverts everywhere or fails for another reason, is
/// returned as fitted.
IntrinsicsResult CalibrateIntrinsicsFallingBackToOpencv5(const std::vector<BoardView>& views,
                                                         const BoardSpec& board, int width_px,
                                                         int height_px,
                                                         const IntrinsicsOptions& options);

/// The options as the JSON reports them.
struct CameraCalibrationRun {
  std::string model = "opencv8";  ///< --model name.
  bool fix_aspect = false;
  bool board_warp = false;
  double outlier_threshold_sigma = 4.0;
};

/// The lasercell.camera_calibration v1 document: lens model, intrinsics with 1 sigma, per image
/// detection and result, outliers, projection uncertainty grid, warnings, summary.
nlohmann::json CameraCalibrationJson(const IntrinsicsResult& result, const BoardSpec& board,
                                     const CalibrationImages& images,
                                     const CameraCalibrationRun& run);

}  // namespace lasercell::calib
