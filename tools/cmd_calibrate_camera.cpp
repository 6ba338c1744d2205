// `lasercell calibrate camera --images 'GLOB' --board chessboard:9x6:25
//  [--model opencv8|opencv5|splined] [--fix-aspect] [--warp] --out CAMERA.cameramodel
//  [--report CAMERA.html] [--json CAMERA.json]`: board detection (calib/target_detection.hpp) and
// intrinsics (calib/intrinsics.hpp). Unreadable images and images without the board are listed
// with the reason and skipped; too few usable views, or views that leave the focal length
// unobservable, are an error (exit 2) after the JSON/report are written, and no camera model is
// written then.
#include <glob.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "calib/camera_model.hpp"
#include "calib/intrinsics.hpp"
#include "calib/intrinsics_report.hpp"
#include "calib/target_detection.hpp"
#include "core/error.hpp"
#include "core/io/file_util.hpp"
#include "core/se3.hpp"
#include "tools/commands.hpp"

namespace lasercell::tools {
namespace {

struct CalibrateCameraArgs {
  std::string images, board, model = "opencv8", out, report, json, corners_out;
  bool fix_aspect = false, warp = false, quiet = false;
  int spline_order = 3, spline_nx = 10, spline_ny = 8;
  double spline_fov_x_deg = 0;
  double outlier_sigma = 4.0;
  double uncertainty_range_mm = 0;
  int threads = 1;
};

std::vector<std::string> Glob(const std::string& pattern) {
  glob_t g{};
  const int rc = ::glob(pattern.c_str(), 0, nullptr, &g);
  std::vector<std::string> paths;
  if (rc == 0) {
    for (std::size_t i = 0; i < g.gl_pathc; ++i) paths.emplace_back(g.gl_pathv[i]);
  }
  ::globfree(&g);
  if (paths.empty()) {
    throw InputError("--images '" + pattern +
                     "' matches no file (quote the pattern so the shell does not expand it)");
  }
  std::sort(paths.begin(), paths.end());
  return paths;
}

calib::LensModelKind Model(const std::string& name) {
  if (name == "opencv5") return calib::LensModelKind::kOpenCV5;
  if (name == "opencv8") return calib::LensModelKind::kOpenCV8;
  if (name == "splined") return calib::LensModelKind::kSplined;
  throw OptionError("--model '" + name + "' is not one of opencv5, opencv8, splined");
}

nlohmann::json PoseJson(const Eigen::Isometry3d& pose) {
  const QuaternionPose q = QuaternionPose::FromIsometry(pose);
  return {{"translation_mm", {q.translation_mm.x(), q.translation_mm.y(), q.translation_mm.z()}},
          {"rotation_wxyz", {q.rotation.w(), q.rotation.x(), q.rotation.y(), q.rotation.z()}}};
}

struct ImageEntry {
  std::string path;
  calib::TargetDetection detection;
  std::string rejection;  // before calibration (detection or size)
};

nlohmann::json ResultJson(const CalibrateCameraArgs& args, const calib::BoardSpec& board,
                          const std::vector<ImageEntry>& images, const std::vector<int>& view_image,
                          const calib::IntrinsicsResult& r, int width, int height) {
  nlohmann::json j;
  j["format"] = "lasercell.camera_calibration";
  j["version"] = 1;
  j["lensmodel"] = r.camera ? r.camera->lensmodel() : "";
  j["image_size"] = {width, height};
  j["board"] = board.ToString();
  j["options"] = {{"model", args.model},
                  {"fix_aspect", args.fix_aspect},
                  {"board_warp", args.warp},
                  {"outlier_threshold_sigma", args.outlier_sigma}};
  j["rms_px"] = r.rms_px;
  j["rms_definition"] = "sqrt(mean over inlier corners of |projected - observed|^2) (OpenCV's)";
  j["residual_sigma_px"] = r.residual_sigma_px;
  j["converged"] = r.converged;
  j["termination"] = r.termination;
  j["iterations"] = r.iterations;
  j["corners_used"] = r.num_corners;
  j["focal_length_observable"] = r.focal_observable;
  j["tilt_spread_deg"] = r.tilt_spread_deg;
  if (args.warp) j["board_warp_mm"] = {r.board_warp_mm.x(), r.board_warp_mm.y()};
  nlohmann::json intr = nlohmann::json::array();
  for (std::size_t i = 0; r.camera && i < r.camera->intrinsics().size(); ++i) {
    nlohmann::json e = {{"name", r.intrinsic_names[i]}, {"value", r.camera->intrinsics()[i]}};
    e["sigma"] = r.intrinsics_sigma.empty() ? nlohmann::json(nullptr)
                                            : nlohmann::json(r.intrinsics_sigma[i]);
    intr.push_back(e);
  }
  j["intrinsics"] = intr;
  nlohmann::json imgs = nlohmann::json::array();
  int used = 0, rejected = 0;
  std::vector<int> view_of_image(images.size(), -1);
  for (std::size_t v = 0; v < view_image.size(); ++v) view_of_image[view_image[v]] = static_cast<int>(v);
  for (std::size_t i = 0; i < images.size(); ++i) {
    nlohmann::json e = {{"file", images[i].path},
                        {"detection", calib::DetectionStatusName(images[i].detection.status)},
                        {"detection_message", images[i].detection.message}};
    const int v = view_of_image[i];
    const calib::ViewResult* vr = v >= 0 && v < static_cast<int>(r.views.size()) ? &r.views[v] : nullptr;
    if (vr != nullptr && vr->used) {
      e["used"] = true;
      e["rms_px"] = vr->rms_px;
      e["corners"] = vr->num_corners;
      e["outliers"] = vr->num_outliers;
      e["tilt_deg"] = vr->tilt_deg;
      e["camera_from_board"] = PoseJson(vr->camera_from_board);
      ++used;
    } else {
      e["used"] = false;
      e["rejection_reason"] = vr != nullptr ? vr->rejection_reason : images[i].rejection;
      ++rejected;
    }
    imgs.push_back(e);
  }
  j["images"] = imgs;
  j["images_used"] = used;
  j["images_rejected"] = rejected;
  nlohmann::json outliers = nlohmann::json::array();
  for (const calib::CornerResidual& c : r.corners) {
    if (!c.outlier) continue;
    outliers.push_back({{"file", images[view_image[c.view]].path},
                        {"corner_id", c.corner_id},
                        {"observed_px", {c.observed_px.x(), c.observed_px.y()}},
                        {"residual_px", {c.residual_px.x(), c.residual_px.y()}}});
  }
  j["outliers"] = outliers;
  nlohmann::json grid = nlohmann::json::array();
  double max_u = 0;
  for (int y = 0; y < r.uncertainty_px.rows(); ++y) {
    nlohmann::json row = nlohmann::json::array();
    for (int x = 0; x < r.uncertainty_px.cols(); ++x) {
      const double u = r.uncertainty_px(y, x);
      row.push_back(std::isfinite(u) ? nlohmann::json(u) : nlohmann::json(nullptr));
      if (std::isfinite(u)) max_u = std::max(max_u, u);
    }
    grid.push_back(row);
  }
  j["projection_uncertainty"] = {
      {"definition",
       "1-sigma worst-direction projection uncertainty (px) of the point at range_mm on each "
       "cell's centre ray, held fixed relative to the mean of the board frames (mrcal's "
       "mean-frames idea), from the joint intrinsics+poses covariance scaled by the residual "
       "variance; cells row by row over the image (calib/intrinsics.hpp)"},
      {"range_mm", r.uncertainty_range_mm},
      {"max_px", max_u},
      {"grid_px", grid}};
  j["warnings"] = r.warnings;
  j["summary"] = r.Summary();
  return j;
}

// mrcal's corners cache (vnl: "# filename x y level"), as mrgingham writes it, so that
// mrcal-calibrate-cameras --corners-cache can run on our detections: a complete chessboard per
// image in grid order, or "filename - - -" when the board was not found.
void WriteCornersCache(const std::string& path, const calib::BoardSpec& board,
                       const std::vector<ImageEntry>& images) {
  if (board.type != calib::BoardType::kChessboard) {
    throw OptionError("--corners-out: mrcal's corners cache holds complete chessboards only");
  }
  std::string text = "## lasercell calibrate camera detections, board " + board.ToString() +
                     "\n# filename x y level\n";
  char line[512];
  for (const ImageEntry& e : images) {
    if (!e.detection.found()) {
      text += e.path + " - - -\n";
      continue;
    }
    for (const Eigen::Vector2d& q : e.detection.corners_px) {
      std::snprintf(line, sizeof(line), " %.6f %.6f 0\n", q.x(), q.y());
      text += e.path + line;
    }
  }
  io::WriteFileAtomically(path, text);
}

void Run(const CalibrateCameraArgs& args) {
  const calib::BoardSpec board = calib::ParseBoardSpec(args.board);
  calib::IntrinsicsOptions options;
  options.model = Model(args.model);
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

  std::vector<ImageEntry> images;
  for (const std::string& path : Glob(args.images)) {
    ImageEntry e;
    e.path = path;
    try {
      e.detection = calib::DetectTargetInEncodedImage(io::ReadFileBytes(path), board);
    } catch (const FileError& err) {
      e.detection.status = calib::DetectionStatus::kUnreadable;
      e.detection.message = err.what();
    }
    if (!e.detection.found()) e.rejection = e.detection.message;
    if (!args.quiet) {
      std::fprintf(stderr, "%s: %s\n", path.c_str(), e.detection.message.c_str());
    }
    images.push_back(std::move(e));
  }
  // The image size: that of the first image with a board; others must match.
  int width = 0, height = 0;
  for (const ImageEntry& e : images) {
    if (e.detection.found()) {
      width = e.detection.width;
      height = e.detection.height;
      break;
    }
  }
  std::vector<calib::BoardView> views;
  std::vector<int> view_image;
  for (std::size_t i = 0; i < images.size(); ++i) {
    ImageEntry& e = images[i];
    if (!e.detection.found()) continue;
    if (e.detection.width != width || e.detection.height != height) {
      e.rejection = "image size " + std::to_string(e.detection.width) + "x" +
                    std::to_string(e.detection.height) + " differs from " + std::to_string(width) +
                    "x" + std::to_string(height);
      continue;
    }
    views.push_back({e.path, e.detection.corners_px, e.detection.corner_ids});
    view_image.push_back(static_cast<int>(i));
  }
  if (static_cast<int>(views.size()) < options.min_views) {
    std::string msg = "--images '" + args.images + "': the board " + board.ToString() +
                      " was found in " + std::to_string(views.size()) + " of " +
                      std::to_string(images.size()) + " images, need at least " +
                      std::to_string(options.min_views);
    for (std::size_t i = 0, shown = 0; i < images.size() && shown < 3; ++i) {
      if (!images[i].rejection.empty()) {
        msg += (shown == 0 ? " (" : "; ") + images[i].path + ": " + images[i].rejection;
        ++shown;
      }
    }
    throw InputError(msg + (views.size() < images.size() ? ")" : ""));
  }
  if (!args.corners_out.empty()) WriteCornersCache(args.corners_out, board, images);
  const calib::IntrinsicsResult result =
      calib::CalibrateIntrinsics(views, board, width, height, options);
  const nlohmann::json j = ResultJson(args, board, images, view_image, result, width, height);
  if (!args.json.empty()) io::WriteFileAtomically(args.json, j.dump(2) + "\n");
  if (!args.report.empty()) {
    report::WriteHtmlReport(
        args.report, calib::IntrinsicsReport(result, "lasercell camera calibration",
                                             "images " + args.images + ", board " +
                                                 board.ToString() + ", model " + args.model));
  }
  if (!result.focal_observable || !result.converged) {
    throw InputError("--images '" + args.images + "': calibration rejected, no camera model "
                     "written: " + (result.warnings.empty() ? result.Summary() : result.warnings.front()));
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
  cmd->add_option("--model", args->model, "opencv8 (default), opencv5 or splined");
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
  cmd->callback([args] { Run(*args); });
}

}  // namespace lasercell::tools
