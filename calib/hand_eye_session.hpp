#pragma once
// The composition of `lasercell calibrate handeye` (eye-in-hand camera from chessboard views,
// calib/hand_eye.hpp), usable without the CLI: robot poses from a kuka/yaml pose file or from a
// simulator record of joints posed through the cell's frame graph; chessboard detection of the
// images (calib/target_detection.hpp) or committed corner detections; matching of images to
// poses; the versioned JSON (format lasercell.hand_eye, version 1), the HTML report and the
// vision_flange -> sensor edge. Units mm, rad (degrees only in the result files' *_deg fields).

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "calib/board.hpp"
#include "calib/camera_model.hpp"
#include "calib/hand_eye.hpp"
#include "calib/pose_io.hpp"
#include "core/frame_graph.hpp"
#include "core/html_report.hpp"
#include "core/progress.hpp"

namespace lasercell::calib {

/// Receives one line per skipped or unreadable-board image (the CLI prints them to stderr).
using HandEyeLog = std::function<void(const std::string&)>;

/// The hand-eye method named `name` (tsai-lenz, park-martin, daniilidis); OptionError else.
HandEyeMethod ParseHandEyeMethod(const std::string& name);

/// A chessboard:COLSxROWS:SQUARE_MM spec (the hand-eye solver takes full chessboards only);
/// OptionError naming --board else.
BoardSpec ParseHandEyeBoard(const std::string& spec);

/// Where the robot poses come from and which frames the edge joins.
struct HandEyePoseSource {
  std::string path;             ///< Pose file.
  std::string format = "auto";  ///< auto, kuka (metres), yaml (mm) or record (joints).
  /// For a joint record: the robot whose dynamic edge poses the flange ("" = the record's).
  std::string robot;
  std::string flange_frame = "vision_flange";  ///< Parent frame of the edge.
  std::string camera_frame = "sensor";         ///< Child frame of the edge.
};

/// base_from_flange per image. A record (format record, or auto and the text is a
/// lasercell.hand_eye_images record) goes through the robot's dynamic edge in `graph` (`cell`
/// names it in messages; FileError when the robot has no edge, InputError when its flange frame
/// is not source.flange_frame); kuka and yaml files are read by calib/pose_io.
RobotPoses LoadHandEyePoses(const HandEyePoseSource& source, const FrameGraph& graph,
                            const std::string& cell);

/// Detects the board in every image (sorted file order = pose order). InputError when the count
/// differs from the poses'; FileError for an unreadable image; images without the board keep an
/// empty corner list (and a `log` line).
ChessboardDetections DetectHandEyeImages(const std::vector<std::string>& files,
                                         const BoardSpec& board, const RobotPoses& poses,
                                         const std::string& poses_path, const HandEyeLog& log,
                                         const ProgressCallback& progress = {});

/// Reads committed corner detections; `board_spec` (optional) must match their board.
ChessboardDetections LoadHandEyeCorners(const std::string& path, const std::string& board_spec);

/// The views for CalibrateHandEye and the image name of each.
struct HandEyeViews {
  std::vector<HandEyeView> views;
  std::vector<std::string> images;
};

/// Pairs detections with poses, in order: counts must agree, the image size must be the
/// camera's, image names must match when the pose file names them (InputError naming both);
/// images without the board are skipped (a `log` line each). `corners_path`, `poses_path` and
/// `camera_path` appear in messages.
HandEyeViews MatchHandEyeViews(const ChessboardDetections& detections, const RobotPoses& poses,
                               const CameraModel& camera, const std::string& corners_path,
                               const std::string& poses_path, const std::string& camera_path,
                               const HandEyeLog& log);

/// What the result files record about the run.
struct HandEyeRun {
  std::string camera_path, poses_path;
  std::string flange_frame = "vision_flange", camera_frame = "sensor";
  HandEyeMethod method = HandEyeMethod::kParkMartin;
  std::string tool;  ///< e.g. "lasercell calibrate handeye 0.1.0".
  std::string date;  ///< ISO 8601 UTC.
};

/// The flange -> camera edge with covariance (when valid) and provenance.
StaticEdge HandEyeEdge(const HandEyeResult& result, const HandEyeViews& views,
                       const HandEyeRun& run);
/// The lasercell.hand_eye v1 document (poses in the file notation, 1 sigma, covariances,
/// closed forms, per view and per motion residuals).
nlohmann::json HandEyeJson(const HandEyeResult& result, const HandEyeViews& views,
                           const HandEyeRun& run);
/// The report: result, per-pose and per-motion residuals, corner residuals, covariance.
report::HtmlReport HandEyeReport(const HandEyeResult& result, const HandEyeViews& views,
                                 const HandEyeRun& run);

/// What `calibrate handeye` reads: the camera, the board views (images or corner detections)
/// and the robot poses.
struct HandEyeInputs {
  std::string camera;               ///< The .cameramodel file.
  std::vector<std::string> images;  ///< Image files in pose order; or, instead, ...
  std::string corners;  ///< ... committed corner detections (lasercell-chessboard-corners text).
  std::string board;    ///< chessboard:COLSxROWS:SQUARE_MM; required with images.
  HandEyePoseSource poses;
  std::string method = "park-martin";  ///< Closed form that starts the refinement.
  int threads = 1;                     ///< Ceres threads.
  std::string tool;           ///< Provenance of the edge, e.g. "lasercell calibrate handeye 0.1.0".
  ProgressCallback progress;  ///< ("detect", fraction) after each image, ("solve", 1) at the end.
};

/// A hand-eye calibration and what the cell and the result files need of it.
struct HandEyeSession {
  HandEyeResult result;
  HandEyeViews views;
  HandEyeRun run;
  StaticEdge edge;  ///< HandEyeEdge: poses.flange_frame <- poses.camera_frame.
};

/// `calibrate handeye` without its files: LoadHandEyePoses (a joint record through `cell`,
/// named `cell_name` in messages), detection of the images or the corners file,
/// MatchHandEyeViews, CalibrateHandEye and HandEyeEdge. OptionError unless exactly one of
/// images and corners is given, or when images come without a board; the other errors of those
/// steps.
HandEyeSession CalibrateHandEyeFromFiles(const HandEyeInputs& inputs, const FrameGraph& cell,
                                         const std::string& cell_name, const HandEyeLog& log);

}  // namespace lasercell::calib
