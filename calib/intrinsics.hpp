#pragma once
// Camera intrinsics from views of a planar board (calib/board.hpp), with mrcal lens models,
// solved with Ceres (calib/cost_functions/reprojection.hpp).
//
// Pipeline: (1) focal length from the views' homographies (Zhang 2000, sec. 3.1, principal
// point at the image centre, square pixels) and board poses by planar PnP; (2) Ceres
// Levenberg-Marquardt over intrinsics, all camera_from_board poses and, optionally, the
// board's bow (warp); (3) outlier rejection: corners whose residual exceeds
// outlier_threshold_sigma x the residual sigma are dropped and the problem re-solved, until no
// new outlier; (4) splined models start from an OPENCV8 solution (core fx fy cx cy from it, knots
// fitted with the poses held, then everything freed) and carry regularisation residuals like
// mrcal's (knot values pulled to zero, plus a smoothness term on second differences);
// (5) covariance of the intrinsics, marginal over poses and warp, scaled by the observed
// residual variance sigma^2 = SSR / (2 N - P); (6) projection uncertainty over a grid.
//
// Projection uncertainty, and how it differs from mrcal's: for each grid cell the ray of its
// centre pixel is unprojected and the point p at `uncertainty_range_mm` on it is expressed in
// every board frame (p_i = board_i_from_camera * p); perturbing the parameters moves the point
// to mean_i(camera_from_board_i * p_i) and its projection q. The 2x2 covariance of q is
// G Sigma G^T with G = dq/d(intrinsics, all poses) (mrcal's gradients for the lens, exact
// rotation derivatives for the poses) and Sigma the joint covariance of intrinsics and poses
// (marginal over the warp) scaled by sigma^2; the figure is its worst-direction standard
// deviation sqrt(max eigenvalue), px. This follows mrcal's "mean-frames" construction;
// differences: sigma comes from the observed residuals of this solve (mrcal from its
// observed-pixel-uncertainty setting), the warp is marginalised out here, and newer mrcal
// versions also offer a cross-reprojection method. Like every linearised figure it is unreliable
// where no board was seen (tests: it matches the Monte-Carlo spread where boards were and
// overestimates it 2-3x in uncovered image corners).
//
// RMS: rms_px = sqrt(mean over corners of |residual|^2) (OpenCV's definition, the 2-D error per
// corner). mrcal's "RMS reprojection error" divides by the number of coordinates (2N): it is
// rms_px / sqrt(2).
//
// Units: mm, rad, px. Pixel convention of camera_model.hpp.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

#include "calib/board.hpp"
#include "calib/camera_model.hpp"

namespace lasercell::calib {

/// The corners of a board seen in one image.
struct BoardView {
  std::string name;                         ///< Image name, for messages and reports.
  std::vector<Eigen::Vector2d> corners_px;  ///< Detected corners.
  std::vector<int> corner_ids;              ///< BoardSpec corner ids (same length).
};

enum class LensModelKind { kOpenCV5, kOpenCV8, kSplined };

struct IntrinsicsOptions {
  LensModelKind model = LensModelKind::kOpenCV8;  ///< Lens model family.
  /// Splined model (mrcal LENSMODEL_SPLINED_STEREOGRAPHIC): B-spline order (2 or 3), knots
  /// along x and y, horizontal field of view covered by the knots in degrees (0: from the image
  /// width and the OPENCV8 focal length, +20 %).
  int spline_order = 3;
  int spline_nx = 10;
  int spline_ny = 8;
  double spline_fov_x_deg = 0;
  /// Regularisation of the splined model, in px per unit of the knot values (normalised
  /// stereographic units) scaled by the focal length: value term (mrcal-like, pulls the knots to
  /// zero where nothing is observed) and second-difference (smoothness) term.
  double spline_value_weight = 0.02;
  double spline_smoothness_weight = 0.2;
  bool fix_aspect_ratio = false;     ///< Hold fy / fx at 1 (OpenCV's CALIB_FIX_ASPECT_RATIO).
  bool estimate_board_warp = false;  ///< Estimate the board's bow (2 coefficients, mm).
  /// A corner is an outlier when its residual norm exceeds this times the per-coordinate
  /// residual sigma (4 => chi^2 with 2 dof at p ~ 3e-4).
  double outlier_threshold_sigma = 4.0;
  int max_outlier_rounds = 5;    ///< Re-solves after dropping outliers (0: no rejection).
  int min_views = 3;             ///< Fewer usable views: InputError.
  int min_corners_per_view = 6;  ///< Views with fewer corners are not used.
  int max_iterations = 200;      ///< Ceres iterations per solve.
  /// Projection-uncertainty grid (cells along x and y) and the range of the fixed point, mm
  /// (0: the median board distance).
  int uncertainty_grid_x = 16;
  int uncertainty_grid_y = 12;
  double uncertainty_range_mm = 0;
  /// Focal length flagged unobservable when its relative 1-sigma exceeds this.
  double max_focal_relative_sigma = 0.01;
  /// Views are "nearly parallel" when every board normal lies within this angle of their mean.
  double min_tilt_spread_deg = 5.0;
  int threads = 1;  ///< Ceres threads (results identical for any count).

  /// Throws OptionError naming the field.
  void Check() const;
};

/// One corner's fit.
struct CornerResidual {
  int view = 0;  ///< Index into IntrinsicsResult::views.
  int corner_id = 0;
  Eigen::Vector2d observed_px = Eigen::Vector2d::Zero();
  Eigen::Vector2d residual_px = Eigen::Vector2d::Zero();  ///< projected - observed.
  bool outlier = false;
};

/// One image's fate and fit.
struct ViewResult {
  std::string name;
  bool used = false;
  std::string rejection_reason;  ///< Why it was not used (empty when used).
  int num_corners = 0;           ///< Corners used (after outlier rejection).
  int num_outliers = 0;
  double rms_px = 0;  ///< RMS of its inlier corners (OpenCV definition).
  Eigen::Isometry3d camera_from_board = Eigen::Isometry3d::Identity();
  double tilt_deg = 0;  ///< Angle between the board normal and the optical axis.
};

struct IntrinsicsResult {
  std::optional<CameraModel> camera;  ///< Set whenever a solve ran.
  bool converged = false;             ///< The last solve converged.
  std::string termination;            ///< Ceres's message of the last solve.
  int iterations = 0;                 ///< Over all solves.
  int outlier_rounds = 0;
  double rms_px = 0;             ///< Inliers, OpenCV definition (see header).
  double residual_sigma_px = 0;  ///< Per-coordinate sigma, sqrt(SSR / (2N - P)).
  int num_corners = 0;           ///< Inlier corners.
  int num_outliers = 0;          ///< Corners rejected as outliers.
  int num_parameters = 0;        ///< Optimised (intrinsics + poses + warp).
  std::vector<ViewResult> views;
  std::vector<CornerResidual> corners;       ///< Every corner of the used views.
  std::vector<std::string> intrinsic_names;  ///< fx fy cx cy k1 ... (mrcal order).
  /// Covariance of mrcal's full intrinsics vector (fy follows fx when the aspect is fixed),
  /// marginal over poses and warp, scaled by residual_sigma_px^2. Empty when not computable.
  Eigen::MatrixXd intrinsics_covariance;
  std::vector<double> intrinsics_sigma;  ///< sqrt of its diagonal (empty when not computable).
  Eigen::Vector2d board_warp_mm = Eigen::Vector2d::Zero();  ///< When estimated.
  double tilt_spread_deg = 0;    ///< Largest angle of a board normal from their mean.
  bool focal_observable = true;  ///< False: views do not constrain the focal length.
  std::string focal_problem;     ///< Why not (the first reason found), "" when observable.
  /// False: the lens model folds over (CheckLensInversion) within the bounding box of the
  /// observed corners, where the boards should have pinned it down; such a model must not be
  /// used for measuring (RejectionReason).
  bool invertible = true;
  std::string inversion_problem;  ///< Where and how it folds inside them, "" when invertible.
  /// Fraction of a grid over the whole imager without a ray (the model folds over beyond the
  /// observed corners: extrapolation, warned about, not refused).
  double imager_fraction_without_ray = 0;
  /// The model folds over somewhere on the imager (pixels without a ray or rays in reversed
  /// order: CheckLensInversion over the whole imager fails).
  bool imager_folds = false;
  /// 1-sigma projection uncertainty (worst direction, px) over the image, rows = grid y.
  Eigen::MatrixXd uncertainty_px;
  double uncertainty_range_mm = 0;
  std::vector<std::string> warnings;  ///< Weak views, focal length, lens inversion, ...
  /// Set by CalibrateIntrinsicsFallingBackToOpencv5 when this is its OPENCV5 refit: why the
  /// OPENCV8 fit was not kept ("" otherwise).
  std::string refitted_because;

  std::string Summary() const;  ///< One line: model, RMS, views, outliers, fx +- sigma, problems.
  /// Why this calibration must not be used as a measuring camera ("" when it may): no model,
  /// not converged, focal length unobservable or a lens model that is not invertible; every
  /// reason that holds, joined by "; ".
  std::string RejectionReason() const;
};

/// Sets result->invertible, imager_fraction_without_ray, imager_folds and their warnings from the
/// solved camera and the inlier corners (nothing when no camera was solved). CalibrateIntrinsics
/// calls it.
void AssessLensInversion(IntrinsicsResult* result);

/// The lens model family named `name` ("opencv5", "opencv8", "splined"); OptionError starting
/// with `field` otherwise.
LensModelKind ParseLensModelKind(const std::string& name, const std::string& field);

/// The name mrcal uses for the lens model of `options` ("LENSMODEL_OPENCV8",
/// "LENSMODEL_SPLINED_STEREOGRAPHIC_order=3_Nx=10_Ny=8_fov_x_deg=75", ...); `fov_x_deg` is used
/// for splined models.
std::string MrcalLensModelName(const IntrinsicsOptions& options, double fov_x_deg);

/// Calibrates a camera of width x height px from board views. Throws InputError when fewer than
/// options.min_views views are usable (the message lists every view's problem) or the inputs are
/// inconsistent (corner ids out of range, corners outside the image). Unobservable focal length,
/// nearly parallel views and non-convergence are reported in the result (warnings,
/// focal_observable, converged), never silently; so is a lens model that cannot be inverted over
/// the whole imager (invertible, with a warning).
IntrinsicsResult CalibrateIntrinsics(const std::vector<BoardView>& views, const BoardSpec& board,
                                     int width_px, int height_px,
                                     const IntrinsicsOptions& options = {});

}  // namespace lasercell::calib
