#include "calib/camera_calibration.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/error.hpp"
#include "core/format.hpp"
#include "core/io/file_util.hpp"
#include "core/json_io.hpp"

namespace lasercell::calib {

CalibrationImages DetectCalibrationImages(const std::vector<std::string>& paths,
                                          const BoardSpec& board,
                                          const std::function<void(const std::string&)>& log,
                                          const ProgressCallback& progress) {
  CalibrationImages out;
  for (const std::string& path : paths) {
    CalibrationImage e;
    e.path = path;
    try {
      e.detection = DetectTargetInEncodedImage(io::ReadFileBytes(path), board);
    } catch (const FileError& err) {
      e.detection.status = DetectionStatus::kUnreadable;
      e.detection.message = err.what();
    }
    if (!e.detection.found()) e.rejection = e.detection.message;
    if (log) log(path + ": " + e.detection.message);
    out.images.push_back(std::move(e));
    ReportProgress(progress, "detect", static_cast<double>(out.images.size()) / paths.size());
  }
  for (const CalibrationImage& e : out.images) {
    if (e.detection.found()) {
      out.width = e.detection.width;
      out.height = e.detection.height;
      break;
    }
  }
  for (std::size_t i = 0; i < out.images.size(); ++i) {
    CalibrationImage& e = out.images[i];
    if (!e.detection.found()) continue;
    if (e.detection.width != out.width || e.detection.height != out.height) {
      e.rejection = "image size " + std::to_string(e.detection.width) + "x" +
                    std::to_string(e.detection.height) + " differs from " +
                    std::to_string(out.width) + "x" + std::to_string(out.height);
      continue;
    }
    out.views.push_back({e.path, e.detection.corners_px, e.detection.corner_ids});
    out.view_image.push_back(static_cast<int>(i));
  }
  return out;
}

void CheckEnoughViews(const CalibrationImages& in, const BoardSpec& board, int min_views,
                      const std::string& images_glob) {
  if (static_cast<int>(in.views.size()) >= min_views) return;
  std::string msg = "--images '" + images_glob + "': the board " + board.ToString() +
                    " was found in " + std::to_string(in.views.size()) + " of " +
                    std::to_string(in.images.size()) + " images, need at least " +
                    std::to_string(min_views);
  for (std::size_t i = 0, shown = 0; i < in.images.size() && shown < 3; ++i) {
    if (!in.images[i].rejection.empty()) {
      msg += (shown == 0 ? " (" : "; ") + in.images[i].path + ": " + in.images[i].rejection;
      ++shown;
    }
  }
  throw InputError(msg + (in.views.size() < in.images.size() ? ")" : ""));
}

std::string CornersCacheText(const BoardSpec& board, const std::vector<CalibrationImage>& images) {
  if (board.type != BoardType::kChessboard) {
    throw OptionError("--corners-out: mrcal's corners cache holds complete chessboards only");
  }
  std::string text = "## lasercell calibrate camera detections, board " + board.ToString() +
                     "\n# filename x y level\n";
  char line[512];
  for (const CalibrationImage& e : images) {
    if (!e.detection.found()) {
      text += e.path + " - - -\n";
      continue;
    }
    for (const Eigen::Vector2d& q : e.detection.corners_px) {
      std::snprintf(line, sizeof(line), " %.6f %.6f 0\n", q.x(), q.y());
      text += e.path + line;
    }
  }
  return text;
}

namespace {

// Per image: detection, and the view's result when it was used, else why not.
nlohmann::json ImagesJson(const IntrinsicsResult& r, const CalibrationImages& in, int* used,
                          int* rejected) {
  nlohmann::json imgs = nlohmann::json::array();
  std::vector<int> view_of_image(in.images.size(), -1);
  for (std::size_t v = 0; v < in.view_image.size(); ++v) {
    view_of_image[static_cast<std::size_t>(in.view_image[v])] = static_cast<int>(v);
  }
  for (std::size_t i = 0; i < in.images.size(); ++i) {
    const CalibrationImage& image = in.images[i];
    nlohmann::json e = {{"file", image.path},
                        {"detection", DetectionStatusName(image.detection.status)},
                        {"detection_message", image.detection.message}};
    const int v = view_of_image[i];
    const ViewResult* vr = v >= 0 && v < static_cast<int>(r.views.size())
                               ? &r.views[static_cast<std::size_t>(v)]
                               : nullptr;
    if (vr != nullptr && vr->used) {
      e["used"] = true;
      e["rms_px"] = vr->rms_px;
      e["corners"] = vr->num_corners;
      e["outliers"] = vr->num_outliers;
      e["tilt_deg"] = vr->tilt_deg;
      e["camera_from_board"] = json::Pose(vr->camera_from_board);
      ++*used;
    } else {
      e["used"] = false;
      e["rejection_reason"] = vr != nullptr ? vr->rejection_reason : image.rejection;
      ++*rejected;
    }
    imgs.push_back(e);
  }
  return imgs;
}

nlohmann::json UncertaintyJson(const IntrinsicsResult& r) {
  nlohmann::json grid = nlohmann::json::array();
  double max_u = 0;
  for (int y = 0; y < r.uncertainty_px.rows(); ++y) {
    nlohmann::json row = nlohmann::json::array();
    for (int x = 0; x < r.uncertainty_px.cols(); ++x) {
      const double u = r.uncertainty_px(y, x);
      row.push_back(json::FiniteOrNull(u));
      if (std::isfinite(u)) max_u = std::max(max_u, u);
    }
    grid.push_back(row);
  }
  return {{"definition",
           "1-sigma worst-direction projection uncertainty (px) of the point at range_mm on "
           "each cell's centre ray, held fixed relative to the mean of the board frames "
           "(mrcal's mean-frames idea), from the joint intrinsics+poses covariance scaled by "
           "the residual variance; cells row by row over the image (calib/intrinsics.hpp)"},
          {"range_mm", r.uncertainty_range_mm},
          {"max_px", max_u},
          {"grid_px", grid}};
}

}  // namespace

nlohmann::json CameraCalibrationJson(const IntrinsicsResult& r, const BoardSpec& board,
                                     const CalibrationImages& in, const CameraCalibrationRun& run) {
  nlohmann::json j;
  j["format"] = "lasercell.camera_calibration";
  j["version"] = 1;
  j["lensmodel"] = r.camera ? r.camera->lensmodel() : "";
  j["image_size"] = {in.width, in.height};
  j["board"] = board.ToString();
  j["options"] = {{"model", run.model},
                  {"fix_aspect", run.fix_aspect},
                  {"board_warp", run.board_warp},
                  {"outlier_threshold_sigma", run.outlier_threshold_sigma}};
  j["rms_px"] = r.rms_px;
  j["rms_definition"] = "sqrt(mean over inlier corners of |projected - observed|^2) (OpenCV's)";
  j["residual_sigma_px"] = r.residual_sigma_px;
  j["converged"] = r.converged;
  j["termination"] = r.termination;
  j["iterations"] = r.iterations;
  j["corners_used"] = r.num_corners;
  j["focal_length_observable"] = r.focal_observable;
  j["tilt_spread_deg"] = r.tilt_spread_deg;
  if (run.board_warp) j["board_warp_mm"] = {r.board_warp_mm.x(), r.board_warp_mm.y()};
  nlohmann::json intr = nlohmann::json::array();
  for (std::size_t i = 0; r.camera && i < r.camera->intrinsics().size(); ++i) {
    nlohmann::json e = {{"name", r.intrinsic_names[i]}, {"value", r.camera->intrinsics()[i]}};
    e["sigma"] = r.intrinsics_sigma.empty() ? nlohmann::json(nullptr)
                                            : nlohmann::json(r.intrinsics_sigma[i]);
    intr.push_back(e);
  }
  j["intrinsics"] = intr;
  int used = 0, rejected = 0;
  j["images"] = ImagesJson(r, in, &used, &rejected);
  j["images_used"] = used;
  j["images_rejected"] = rejected;
  nlohmann::json outliers = nlohmann::json::array();
  for (const CornerResidual& c : r.corners) {
    if (!c.outlier) continue;
    outliers.push_back(
        {{"file",
          in.images[static_cast<std::size_t>(in.view_image[static_cast<std::size_t>(c.view)])]
              .path},
         {"corner_id", c.corner_id},
         {"observed_px", {c.observed_px.x(), c.observed_px.y()}},
         {"residual_px", {c.residual_px.x(), c.residual_px.y()}}});
  }
  j["outliers"] = outliers;
  j["projection_uncertainty"] = UncertaintyJson(r);
  j["warnings"] = r.warnings;
  j["summary"] = r.Summary();
  return j;
}

IntrinsicsResult CalibrateIntrinsicsFallingBackToOpencv5(const std::vector<BoardView>& views,
                                                         const BoardSpec& board, int width_px,
                                                         int height_px,
                                                         const IntrinsicsOptions& options) {
  IntrinsicsResult result = CalibrateIntrinsics(views, board, width_px, height_px, options);
  const bool folds = !result.invertible || result.imager_folds;
  if (options.model != LensModelKind::kOpenCV8 || !folds || !result.camera || !result.converged ||
      !result.focal_observable) {
    return result;
  }
  const std::string why = !result.inversion_problem.empty()
                              ? result.inversion_problem
                              : "it folds over beyond the observed corners (no ray at " +
                                    FormatFixed(100.0 * result.imager_fraction_without_ray, 1) +
                                    " % of the imager)";
  IntrinsicsOptions opencv5 = options;
  opencv5.model = LensModelKind::kOpenCV5;
  IntrinsicsResult refit = CalibrateIntrinsics(views, board, width_px, height_px, opencv5);
  // Keep OPENCV8 unless OPENCV5 is usable and does not fold, or leaves fewer of the imager's
  // pixels without a ray.
  const bool better = refit.RejectionReason().empty() &&
                      (!result.invertible || !refit.imager_folds ||
                       refit.imager_fraction_without_ray < result.imager_fraction_without_ray);
  if (!better) return result;
  refit.refitted_because = "OPENCV8 was refitted as OPENCV5: " + why.substr(0, why.find(';'));
  refit.warnings.insert(refit.warnings.begin(), refit.refitted_because);
  return refit;
}

}  // namespace lasercell::calib
