// Laser-plane calibration, method (b): a laser stripe on a chessboard of unknown pose (Zhou &
// Zhang 2005; see calib/laser_plane.hpp): per image the board pose from its corners, the stripe
// peaks' rays intersected with the board plane, one plane over all images, refined jointly with
// the board poses.

#include <ceres/ceres.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "calib/cost_functions/plane_board_joint.hpp"
#include "calib/cost_functions/plane_point_distance.hpp"
#include "calib/internal/laser_geometry.hpp"
#include "calib/internal/laser_plane_fit.hpp"
#include "calib/internal/stripe_detection.hpp"
#include "calib/laser_plane.hpp"
#include "core/error.hpp"
#include "core/ray_plane.hpp"
#include "core/stats.hpp"

namespace lasercell::calib {

using namespace internal;

StripeImage DecodeStripeImage(const std::string& bytes, const std::string& name) {
  const cv::Mat raw(1, static_cast<int>(bytes.size()), CV_8UC1, const_cast<char*>(bytes.data()));
  cv::Mat image;
  if (!bytes.empty()) image = cv::imdecode(raw, cv::IMREAD_UNCHANGED);
  if (image.empty()) {
    throw FileError(name, "cannot decode the image (not a readable JPEG/PNG/... file)");
  }
  if (image.depth() != CV_8U) {
    cv::Mat converted;
    image.convertTo(converted, CV_8U, image.depth() == CV_16U ? 1.0 / 256.0 : 1.0);
    image = converted;
  }
  if (image.channels() == 4) cv::cvtColor(image, image, cv::COLOR_BGRA2BGR);
  if (image.channels() != 1 && image.channels() != 3) {
    throw FileError(name, "has " + std::to_string(image.channels()) + " channels; expected 1 or 3");
  }
  StripeImage out;
  out.name = name;
  out.image.width = image.cols;
  out.image.height = image.rows;
  out.image.channels = image.channels();
  const cv::Mat cont = image.isContinuous() ? image : image.clone();
  out.image.pixels.assign(cont.data, cont.data + cont.total() * cont.elemSize());
  return out;
}

namespace {

/// The stripe method's board: a chessboard (the search region and the joint fit use its grid of
/// inner corners); OptionError naming the board otherwise.
void CheckStripeBoard(const BoardSpec& board) {
  board.Check();
  if (board.type != BoardType::kChessboard) {
    throw OptionError(
        "the stripe method needs a chessboard (chessboard:COLSxROWS:SQUARE_MM), not '" +
        board.ToString() + "'");
  }
}

/// Stripe points of one image: board pose, rays of the stripe pixels ∩ board plane.
struct ImagePoints {
  std::vector<Eigen::Vector2d> pixels;
  std::vector<Eigen::Vector3d> rays;
  std::vector<Eigen::Vector3d> points;
  Eigen::Isometry3d camera_from_board = Eigen::Isometry3d::Identity();
  std::vector<Eigen::Vector2d> corners_normalized;  // x/z, y/z of the corners' rays
};

ImagePoints StripePoints(const CameraModel& camera, const StripeObservation& observation,
                         const BoardSpec& board, LaserPlaneItem& item) {
  ImagePoints out;
  const Eigen::Isometry3d camera_from_board =
      BoardPose(camera, observation.corners_px, board, &item.reprojection_rms_px);
  out.camera_from_board = camera_from_board;
  for (const auto& r : camera.UnprojectMany(observation.corners_px)) {
    out.corners_normalized.emplace_back(r.x() / r.z(), r.y() / r.z());
  }
  const Eigen::Vector3d board_normal = camera_from_board.linear().col(2);
  const double board_offset = -board_normal.dot(camera_from_board.translation());
  const std::vector<Eigen::Vector3d> rays = camera.UnprojectMany(observation.stripe_px);
  for (std::size_t k = 0; k < rays.size(); ++k) {
    const auto p = IntersectRayPlane(rays[k], board_normal, board_offset);
    if (!p) continue;
    out.pixels.push_back(observation.stripe_px[k]);
    out.rays.push_back(rays[k]);
    out.points.push_back(*p);
  }
  return out;
}

/// Zhou & Zhang's joint refinement: laser plane and board poses from the corners (normalized
/// reprojection, scaled to px / corner sigma) and the stripe rays (distance of ray ∩ board from
/// the laser plane / stripe sigma). The sigmas are estimated from the separate fits and then
/// from this fit's own residuals (two passes), so the covariance is in units of the data.
PlaneFit JointStripeFit(const std::map<int, ImagePoints>& views, const BoardSpec& board,
                        const Eigen::Vector2d& focal_px, const Eigen::Vector3d& n0, double d0,
                        double corner_sigma_px, double stripe_sigma_mm,
                        std::map<int, Eigen::Isometry3d>* refined_poses) {
  PlaneFit fit;
  Eigen::Vector3d n_start = n0;
  double d_start = d0;
  std::map<int, std::array<double, 6>> start;
  for (const auto& [i, v] : views) {
    Eigen::AngleAxisd aa(v.camera_from_board.linear());
    const Eigen::Vector3d w = aa.angle() * aa.axis();
    const Eigen::Vector3d t = v.camera_from_board.translation();
    start[i] = {w.x(), w.y(), w.z(), t.x(), t.y(), t.z()};
  }
  for (int pass = 0; pass < 2; ++pass) {
    double n[3] = {n_start.x(), n_start.y(), n_start.z()};
    double d = d_start;
    std::map<int, std::array<double, 6>> poses = start;
    ceres::Problem problem;
    int count = 0;
    std::vector<ceres::ResidualBlockId> corner_blocks, stripe_blocks;
    for (const auto& [i, v] : views) {
      double* pose = poses[i].data();
      for (int j = 0; j < board.rows; ++j) {
        for (int c = 0; c < board.cols; ++c) {
          const std::size_t k = static_cast<std::size_t>(j * board.cols + c);
          corner_blocks.push_back(problem.AddResidualBlock(
              BoardCornerCost::Create(
                  Eigen::Vector3d(c * board.square_mm, j * board.square_mm, 0.0),
                  v.corners_normalized[k], focal_px / corner_sigma_px),
              nullptr, pose));
          count += 2;
        }
      }
      for (const auto& ray : v.rays) {
        stripe_blocks.push_back(problem.AddResidualBlock(
            StripeOnBoardCost::Create(ray, 1.0 / stripe_sigma_mm), nullptr, n, &d, pose));
        ++count;
      }
    }
    problem.SetManifold(n, new ceres::SphereManifold<3>());
    SolvePlaneProblem(PlaneSolverOptions(ceres::DENSE_SCHUR), problem, n, &d, &fit);
    // Re-estimate each group's sigma from its residuals (unit-weight residuals ~ N(0, 1) when
    // the sigma is right); the second pass uses them.
    const auto group_rms = [&](const std::vector<ceres::ResidualBlockId>& blocks, int per_block) {
      ceres::Problem::EvaluateOptions eval;
      eval.residual_blocks = blocks;
      double cost = 0;
      problem.Evaluate(eval, &cost, nullptr, nullptr, nullptr);
      return std::sqrt(2.0 * cost / (static_cast<double>(blocks.size()) * per_block));
    };
    const double corner_scale = group_rms(corner_blocks, 2);
    const double stripe_scale = group_rms(stripe_blocks, 1);
    ceres::Covariance covariance(PlaneCovarianceOptions());
    fit.covariance_ok = false;
    if (covariance.Compute(PlaneCovarianceBlocks(n, &d), &problem)) {
      // Unit-weight residuals (both groups' sigmas re-estimated above): no further scaling.
      fit.covariance = PlaneCovariance(covariance, n, &d, 1.0);
      fit.covariance_ok = fit.covariance.allFinite();
    }
    if (refined_poses != nullptr) {
      refined_poses->clear();
      for (const auto& [i, p] : poses) {
        const Eigen::Vector3d w(p[0], p[1], p[2]);
        Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
        if (w.norm() > 0)
          pose.linear() = Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix();
        pose.translation() = Eigen::Vector3d(p[3], p[4], p[5]);
        (*refined_poses)[i] = pose;
      }
    }
    corner_sigma_px *= corner_scale;
    stripe_sigma_mm *= stripe_scale;
    n_start = fit.normal;
    d_start = fit.offset;
    (void)count;
  }
  OrientPlane(fit.normal, fit.offset);
  return fit;
}

PlaneFit FitPoints(const std::vector<Eigen::Vector3d>& points, const std::vector<int>& owner,
                   const Eigen::Vector3d& n0, double d0, int skip_item) {
  return Solve(n0, d0, 0.0, false, 0.0, false,
               [&](ceres::Problem& problem, double* pn, double* pd, double*, double*) {
                 int count = 0;
                 for (std::size_t k = 0; k < points.size(); ++k) {
                   if (owner[k] == skip_item) continue;
                   problem.AddResidualBlock(PlanePointDistanceCost::Create(points[k]), nullptr, pn,
                                            pd);
                   ++count;
                 }
                 return count;
               });
}

}  // namespace

StripeObservation DetectStripe(const CameraModel& camera, const StripeImage& image,
                               const BoardSpec& board, const StripeOptions& options) {
  options.Check();
  CheckStripeBoard(board);
  const Image8& raster = image.image;
  if (raster.width != camera.width_px() || raster.height != camera.height_px()) {
    throw InputError("image '" + image.name + "' is " + std::to_string(raster.width) + "x" +
                     std::to_string(raster.height) + " but the camera model is " +
                     std::to_string(camera.width_px()) + "x" + std::to_string(camera.height_px()) +
                     "; use the camera that took the images");
  }
  LASERCELL_CHECK(raster.pixels.size() == static_cast<std::size_t>(raster.width) * raster.height *
                                              raster.channels &&
                      (raster.channels == 1 || raster.channels == 3),
                  "StripeImage buffer size");
  StripeObservation out;
  out.name = image.name;
  const TargetDetection detection = DetectTarget(Gray8Of(raster), board, options.board_detection);
  if (!detection.found()) {
    out.note = "board: " + detection.message;
    return out;
  }
  out.corners_px = detection.corners_px;
  const Eigen::Isometry3d camera_from_board = BoardPose(camera, out.corners_px, board, nullptr);
  // The board region: the inner-corner grid grown by the margin, sampled along its edges
  // (straight on the board, curved in a distorted image).
  const double s = board.square_mm, g = options.board_margin_squares;
  const double x0 = -g * s, y0 = -g * s, x1 = (board.cols - 1 + g) * s,
               y1 = (board.rows - 1 + g) * s;
  std::vector<cv::Point2f> region;
  const int kSteps = 16;
  const Eigen::Vector2d outline[4] = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
  for (int e = 0; e < 4; ++e) {
    for (int k = 0; k < kSteps; ++k) {
      const Eigen::Vector2d b =
          outline[e] + (outline[(e + 1) % 4] - outline[e]) * (static_cast<double>(k) / kSteps);
      const Eigen::Vector2d q =
          camera.Project(camera_from_board * Eigen::Vector3d(b.x(), b.y(), 0.0));
      region.emplace_back(static_cast<float>(q.x()), static_cast<float>(q.y()));
    }
  }
  std::vector<cv::Point2f> hull;
  cv::convexHull(region, hull);
  const cv::Mat laser = LaserChannel(raster, options.laser_color);
  auto by_columns = StripePeaks(laser, hull, false, options);
  auto by_rows = StripePeaks(laser, hull, true, options);
  out.scan_along_rows = by_rows.size() > by_columns.size();
  out.stripe_px = out.scan_along_rows ? std::move(by_rows) : std::move(by_columns);
  if (static_cast<int>(out.stripe_px.size()) < options.min_peaks_per_image) {
    out.note = "laser stripe not found on the board (" + std::to_string(out.stripe_px.size()) +
               " peaks, need " + std::to_string(options.min_peaks_per_image) + ")";
    out.stripe_px.clear();
    return out;
  }
  out.note = std::string("stripe: one peak per image ") + (out.scan_along_rows ? "row" : "column");
  return out;
}

LaserPlaneResult CalibrateLaserPlaneFromStripes(const CameraModel& camera,
                                                const std::vector<StripeImage>& images,
                                                const BoardSpec& board,
                                                const StripeOptions& options) {
  std::vector<StripeObservation> observations;
  for (const StripeImage& image : images)
    observations.push_back(DetectStripe(camera, image, board, options));
  return CalibrateLaserPlaneFromStripeObservations(camera, observations, board, options);
}

namespace {

/// The stripe points of all used images, with their rays, pixels and image index.
struct StripePointSet {
  std::vector<Eigen::Vector3d> points, rays;
  std::vector<Eigen::Vector2d> pixels;
  std::vector<int> owner;
};

/// Board pose and stripe points per observation (the items of `result`); InputError when fewer
/// than 2 images are usable, listing why each failed.
int CollectStripeViews(const CameraModel& camera,
                       const std::vector<StripeObservation>& observations, const BoardSpec& board,
                       const StripeOptions& options, LaserPlaneResult& result,
                       std::map<int, ImagePoints>& views, StripePointSet& all) {
  int usable = 0;
  for (std::size_t i = 0; i < observations.size(); ++i) {
    const StripeObservation& observation = observations[i];
    LaserPlaneItem item;
    item.name = observation.name;
    item.note = observation.note;
    item.scan_along_rows = observation.scan_along_rows;
    ImagePoints found;
    const bool complete =
        observation.corners_px.size() == static_cast<std::size_t>(board.NumCorners());
    if (!observation.corners_px.empty() && !complete) {
      item.note = "has " + std::to_string(observation.corners_px.size()) + " corners, the board " +
                  std::to_string(board.NumCorners());
    }
    if (complete && static_cast<int>(observation.stripe_px.size()) >= options.min_peaks_per_image) {
      found = StripePoints(camera, observation, board, item);
    } else if (complete && item.note.empty()) {
      item.note = "too few stripe peaks (" + std::to_string(observation.stripe_px.size()) + ")";
    }
    if (!found.points.empty()) {
      views[static_cast<int>(i)] = found;
      item.used = true;
      item.points = static_cast<int>(found.points.size());
      ++usable;
      for (std::size_t k = 0; k < found.points.size(); ++k) {
        all.points.push_back(found.points[k]);
        all.rays.push_back(found.rays[k]);
        all.pixels.push_back(found.pixels[k]);
        all.owner.push_back(static_cast<int>(i));
      }
    }
    result.items.push_back(item);
  }
  if (usable < 2) {
    std::string why;
    for (const auto& item : result.items) {
      if (!item.used) why += "; " + item.name + ": " + item.note;
    }
    throw InputError("fewer than 2 usable stripe images (" + std::to_string(usable) + " of " +
                     std::to_string(observations.size()) +
                     "): the plane needs the stripe on the board in >= 2 board poses" + why);
  }
  return usable;
}

/// Start by total least squares, then Ceres; drop gross outliers once (robust sigma). `kept`
/// gets the remaining points; returns the point fit over them.
PlaneFit FitWithoutOutliers(const StripePointSet& all, const StripeOptions& options,
                            LaserPlaneResult& result, StripePointSet& kept) {
  const TlsPlane start = FitPlaneTls(all.points);
  PlaneFit fit = FitPoints(all.points, all.owner, start.normal, start.offset_mm, -1);
  std::vector<double> abs_res;
  for (const auto& p : all.points) abs_res.push_back(std::abs(fit.normal.dot(p) + fit.offset));
  const double robust_sigma = 1.4826 * Median(abs_res);
  for (std::size_t k = 0; k < all.points.size(); ++k) {
    if (abs_res[k] <= options.outlier_sigmas * robust_sigma || robust_sigma == 0) {
      kept.points.push_back(all.points[k]);
      kept.rays.push_back(all.rays[k]);
      kept.pixels.push_back(all.pixels[k]);
      kept.owner.push_back(all.owner[k]);
    }
  }
  if (kept.points.size() < all.points.size()) {
    result.warnings.push_back(std::to_string(all.points.size() - kept.points.size()) +
                              " stripe points farther than " + Num(options.outlier_sigmas) +
                              " robust sigmas from the plane were dropped");
    fit = FitPoints(kept.points, kept.owner, fit.normal, fit.offset, -1);
  }
  return fit;
}

/// Points of one view share its board-pose error, so the covariance of the point fit is
/// optimistic. Refine plane and board poses jointly (Zhou & Zhang 2005): its covariance carries
/// the pose uncertainty, and the points are re-intersected with the refined boards. Keeps `fit`
/// (with a warning) when the joint refinement fails.
void RefineJointly(const CameraModel& camera, const std::map<int, ImagePoints>& views,
                   const BoardSpec& board, int usable, LaserPlaneResult& result, PlaneFit& fit,
                   StripePointSet& kept) {
  std::map<int, ImagePoints> kept_views;
  for (auto& [i, v] : views) {
    ImagePoints kv = v;
    kv.rays.clear();
    kv.pixels.clear();
    kv.points.clear();
    kept_views[i] = kv;
  }
  for (std::size_t k = 0; k < kept.points.size(); ++k) {
    ImagePoints& kv = kept_views[kept.owner[k]];
    kv.rays.push_back(kept.rays[k]);
    kv.pixels.push_back(kept.pixels[k]);
  }
  double corner_rms = 0;
  for (const auto& item : result.items)
    corner_rms += item.used ? item.reprojection_rms_px / usable : 0.0;
  const Eigen::Vector2d focal(camera.intrinsics()[0], camera.intrinsics()[1]);
  std::map<int, Eigen::Isometry3d> refined;
  double stripe_rms = 0;
  for (const auto& p : kept.points) stripe_rms += std::pow(fit.normal.dot(p) + fit.offset, 2);
  stripe_rms = std::sqrt(stripe_rms / static_cast<double>(kept.points.size()));
  const PlaneFit joint =
      JointStripeFit(kept_views, board, focal, fit.normal, fit.offset, std::max(corner_rms, 0.01),
                     std::max(stripe_rms, 1e-3), &refined);
  if (joint.converged && joint.covariance_ok) {
    fit = joint;
    for (std::size_t k = 0; k < kept.points.size(); ++k) {
      const Eigen::Isometry3d& pose = refined[kept.owner[k]];
      const Eigen::Vector3d m = pose.linear().col(2);
      const auto p = IntersectRayPlane(kept.rays[k], m, -m.dot(pose.translation()));
      if (p) kept.points[k] = *p;
    }
  } else {
    result.warnings.push_back(
        "the joint refinement of plane and board poses failed (" + joint.termination +
        "); the plane and its covariance come from the point fit and are optimistic");
  }
}

/// Residuals, per-image RMS and leave-one-image-out on point fits over the final points.
void StripeResiduals(const PlaneFit& fit, const StripePointSet& kept, std::size_t images,
                     int usable, LaserPlaneResult& result) {
  std::vector<double> item_sum(images, 0);
  std::vector<int> item_count(images, 0);
  double sum = 0;
  for (std::size_t k = 0; k < kept.points.size(); ++k) {
    const double r = fit.normal.dot(kept.points[k]) + fit.offset;
    result.residuals.push_back({kept.owner[k], kept.pixels[k], kept.points[k], r});
    sum += r * r;
    item_sum[static_cast<std::size_t>(kept.owner[k])] += r * r;
    ++item_count[static_cast<std::size_t>(kept.owner[k])];
  }
  result.points = static_cast<int>(kept.points.size());
  result.rms_mm = std::sqrt(sum / std::max<std::size_t>(1, kept.points.size()));
  const PlaneFit loo_reference =
      usable >= 3 ? FitPoints(kept.points, kept.owner, fit.normal, fit.offset, -1) : fit;
  for (std::size_t i = 0; i < result.items.size(); ++i) {
    LaserPlaneItem& item = result.items[i];
    if (!item.used) continue;
    item.points = item_count[i];
    item.rms_mm = item_count[i] > 0 ? std::sqrt(item_sum[i] / item_count[i]) : 0.0;
    if (usable < 3) {
      item.loo_normal_change_deg = item.loo_offset_change_mm = item.loo_max_displacement_mm = kNaN;
      continue;
    }
    // Leave-one-out on point fits (cheap) over the final points: the change without this view.
    const PlaneFit loo = FitPoints(kept.points, kept.owner, loo_reference.normal,
                                   loo_reference.offset, static_cast<int>(i));
    LooChange(loo_reference.normal, loo_reference.offset, loo.normal, loo.offset, kept.points,
              item);
  }
  SummarizeLoo(result);
}

}  // namespace

LaserPlaneResult CalibrateLaserPlaneFromStripeObservations(
    const CameraModel& camera, const std::vector<StripeObservation>& observations,
    const BoardSpec& board, const StripeOptions& options) {
  options.Check();
  CheckStripeBoard(board);
  LaserPlaneResult result;
  result.method = "stripe_chessboard";
  std::map<int, ImagePoints> views;
  StripePointSet all, kept;
  const int usable = CollectStripeViews(camera, observations, board, options, result, views, all);
  PlaneFit fit = FitWithoutOutliers(all, options, result, kept);
  if (options.joint_refinement) RefineJointly(camera, views, board, usable, result, fit, kept);
  FillPlane(fit, result);
  StripeResiduals(fit, kept, observations.size(), usable, result);
  // Rays of every image in one plane through the camera centre: the points are on the laser
  // plane (the board planes place them) but the plane passes through the camera.
  FlagConditioning(result, kept.rays, options.min_triangulation_angle_deg);
  // The camera's own uncertainty: the whole method (board poses, stripe points, joint
  // refinement) again through perturbed cameras.
  StripeOptions refit_options = options;
  refit_options.include_camera_uncertainty = false;
  AddCameraUncertainty(
      camera, options.include_camera_uncertainty,
      [&](const CameraModel& perturbed) {
        const LaserPlaneResult refit = CalibrateLaserPlaneFromStripeObservations(
            perturbed, observations, board, refit_options);
        return std::make_pair(refit.normal, refit.offset_mm);
      },
      result);
  if (!result.converged)
    result.warnings.push_back("the solver did not converge: " + result.termination);
  return result;
}

}  // namespace lasercell::calib
