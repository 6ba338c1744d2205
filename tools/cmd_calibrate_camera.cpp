// `lasercell calibrate camera --images 'GLOB' --board chessboard:9x6:25
//  [--model opencv8|opencv5|splined] [--fix-aspect] [--warp] --out
//  CAMERA.cameramodel
//  [--report CAMERA.html] [--json CAMERA.json]`: board detection and views
// (calib/camera_calibration.hpp), intrinsics (calib/intrinsics.hpp), result
// JSON (calib/camera_calibration.hpp) and report (calib/intrinsics_report.hpp).
// Unreadable images and images without the board are listed with the reason and
// skipped; too few usable views, views that leave the focal length
// unobservable, or a lens model that folds over inside the imager (the default
// opencv8 is refitted as opencv5 first) are an error (exit 2) after the
// JSON/report are written, and no camera model is written then.
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "calib/camera_calibration.hpp"
#include "calib/camera_model.hpp"
#include "calib/intrinsics.hpp"
#include "calib/intrinsics_report.hpp"
#include "core/error.hpp"
#include "core/io/file_util.hpp"
#include "core/json_io.hpp"
#include "tools/commands.hpp"

namespace lasercell::tools {
namespace {

struct CalibrateCameraArgs {
  std::string images, board, model = "opencv8", out, report, json, corners_out;
  bool fix_aspect = false, warp = false, quiet = false;
  bool model_given = false;  // --model on the command line (else the default may fall back)
  int spline_order = 3, spline_nx = 10, spline_ny = 8;
  double spline_fov_x_deg = 0;
  double outlier_sigma = 4.0;
  double uncertainty_range_mm = 0;
  int threads = 1;
};

void Run(const CalibrateCameraArgs& args) {
  const calib::BoardSpec board = calib::ParseBoardSpec(args.board);
  calib::IntrinsicsOptions options;
  options.model = calib::ParseLensModelKind(args.model, "--model");
  options.fix_aspect_ratio = args.fix_aspect;
  options.estimate_board_warp = args.warp;
  options.spline_order = args.spline_order;
  options.spline_nx = args.spline_nx;
  options.spline_ny = args.spline_ny;
  options.spline_fov_x_deg = args.spline_fov_x_deg;
  options.outlier_threshold_sigma = args.outlier_sigma;
  options.uncertainty_range_mm = args.uncertainty_range_mm;
  options.threads = args.threads;
  options.Check();

  const calib::CalibrationImages images = calib::DetectCalibrationImages(
      io::GlobFiles(args.images, "--images"), board, [&](const std::string& line) {
        if (!args.quiet) std::fprintf(stderr, "%s\n", line.c_str());
      });
  calib::CheckEnoughViews(images, board, options.min_views, args.images);
  if (!args.corners_out.empty()) {
    io::WriteFileAtomically(args.corners_out, calib::CornersCacheText(board, images.images));
  }
  // The default model falls back to OPENCV5 when OPENCV8 folds over; an explicit choice stands.
  const calib::IntrinsicsResult result =
      args.model_given
          ? calib::CalibrateIntrinsics(images.views, board, images.width, images.height, options)
          : calib::CalibrateIntrinsicsFallingBackToOpencv5(images.views, board, images.width,
                                                           images.height, options);
  json::WriteFile(args.json, calib::CameraCalibrationJson(
                                 result, board, images,
                                 {args.model, args.fix_aspect, args.warp, args.outlier_sigma}));
  if (!args.report.empty()) {
    report::WriteHtmlReport(
        args.report, calib::IntrinsicsReport(result, "lasercell camera calibration",
                                             "images " + args.images + ", board " +
                                                 board.ToString() + ", model " + args.model));
  }
  if (const std::string reason = result.RejectionReason(); !reason.empty()) {
    throw InputError("--images '" + args.images +
                     "': calibration rejected, no camera model written: " + reason);
  }
  calib::SaveCameraModel(args.out, *result.camera,
                         "lasercell calibrate camera: " + result.Summary() + "\nboard " +
                             board.ToString() + ", images " + args.images);
  if (!args.quiet) std::printf("%s -> %s\n", result.Summary().c_str(), args.out.c_str());
}

}  // namespace

void AddCalibrateCameraCommand(CLI::App& calibrate) {
  CLI::App* cmd = calibrate.add_subcommand(
      "camera", "Camera intrinsics (mrcal lens model) from chessboard / ChArUco images");
  auto args = std::make_shared<CalibrateCameraArgs>();
  cmd->add_option("--images", args->images, "Glob of the board images (quote it)")->required();
  cmd->add_option("--board", args->board,
                  "chessboard:COLSxROWS:SQUARE_MM (inner corners) or "
                  "charuco:SXxSY:SQUARE_MM:MARKER_MM[:DICT] (squares)")
      ->required();
  CLI::Option* model = cmd->add_option(
      "--model", args->model,
      "opencv8 (default; refitted as opencv5 when it folds over inside the imager), opencv5 or "
      "splined");
  cmd->add_flag("--fix-aspect", args->fix_aspect, "Hold fy = fx");
  cmd->add_flag("--warp", args->warp, "Estimate the board's bow (2 terms, mm)");
  cmd->add_option("--spline-order", args->spline_order, "Splined model: B-spline order (2 or 3)");
  cmd->add_option("--spline-nx", args->spline_nx, "Splined model: knots along x (default 10)");
  cmd->add_option("--spline-ny", args->spline_ny, "Splined model: knots along y (default 8)");
  cmd->add_option("--spline-fov-x-deg", args->spline_fov_x_deg,
                  "Splined model: horizontal field of view of the knots (0: automatic)");
  cmd->add_option("--outlier-sigma", args->outlier_sigma,
                  "Corner outlier threshold, multiples of the residual sigma (default 4)");
  cmd->add_option("--uncertainty-range-mm", args->uncertainty_range_mm,
                  "Range of the projection-uncertainty point (0: median board distance)");
  cmd->add_option("--threads", args->threads, "Solver threads")->check(CLI::PositiveNumber);
  cmd->add_option("--out", args->out, "Output .cameramodel (mrcal format)")->required();
  cmd->add_option("--json", args->json, "Output JSON summary");
  cmd->add_option("--report", args->report, "Output HTML report");
  cmd->add_option("--corners-out", args->corners_out,
                  "Also write the detections as a mrcal corners cache (vnl) for "
                  "mrcal-calibrate-cameras --corners-cache");
  cmd->add_flag("--quiet", args->quiet, "No per-image lines, no summary");
  cmd->callback([args, model] {
    args->model_given = model->count() > 0;
    Run(*args);
  });
}

}  // namespace lasercell::tools
