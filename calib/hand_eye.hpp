#pragma once
// Eye-in-hand calibration with a camera on the robot flange observing a fixed chessboard
// (Tsai-Lenz, Park-Martin, Daniilidis closed forms, refined over the reprojection error).
//
// Conventions: per view i the robot reports base_from_flange A_i (mm); the camera sees the board
// at camera_from_board C_i (from PnP through the camera model). Unknowns: X = flange_from_camera
// and Y = base_from_board, linked by A_i * X * C_i = Y for every view. The closed forms use the
// relative motions of view pairs (i, j): A_ij = A_i^-1 A_j (flange_i_from_flange_j) and
// B_ij = C_i C_j^-1 (camera_i_from_camera_j), with A_ij X = X B_ij (AX = XB). The refinement
// minimises the reprojection error of every corner over X and Y jointly (robot-world-hand-eye),
// camera intrinsics held fixed.
//
// Covariances are 6x6 over [rotation vector rad; translation mm] of a perturbation
// (R = Exp(dr) * R_est, t = t_est + dt), i.e. the rotation part is a LEFT perturbation expressed
// in the parent frame (flange for X, base for Y), as FrameGraph's StaticEdge::covariance. They
// are (J^T J)^-1 scaled by the residual variance sigma^2 = sum r^2 / (2 N - 12), plus (when the
// camera model carries its intrinsics covariance) what the camera's own uncertainty does to X and
// Y, propagated by refining again through perturbed cameras (calib/camera_uncertainty.hpp): a
// focal length error scales every board distance, which no number of views averages away. They
// do not include the uncertainty of the robot poses.
//
// Units: mm, rad (deg only where a name says _deg), px for pixels.

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "calib/camera_model.hpp"
#include "core/se3.hpp"

namespace lasercell::calib {

/// Closed-form AX = XB solvers (our own implementations).
enum class HandEyeMethod {
  kTsaiLenz,    ///< Tsai & Lenz 1989: modified Rodrigues vectors, rotation then translation.
  kParkMartin,  ///< Park & Martin 1994: rotation from log maps, (M^T M)^-1/2 M^T.
  kDaniilidis,  ///< Daniilidis 1999: dual quaternions, SVD of the stacked 6x8 system.
};
/// "tsai-lenz", "park-martin", "daniilidis".
std::string HandEyeMethodName(HandEyeMethod method);

/// One robot pose and the chessboard seen from it.
struct HandEyeView {
  Eigen::Isometry3d base_from_flange = Eigen::Isometry3d::Identity();  ///< Robot pose, mm.
  std::vector<Eigen::Vector2d> corners_px;                             ///< Detected corners, px.
  std::vector<Eigen::Vector3d> corners_in_board;  ///< The same corners on the board, mm.
};

/// Thresholds of the motion degeneracy checks (CheckHandEyeMotions).
struct HandEyeMotionOptions {
  /// The largest relative rotation between two poses must reach this, deg; below it the robot
  /// only translated and the rotation of X is unobservable.
  double min_rotation_deg = 5.0;
  /// The rotation axes of the relative motions (those rotating >= min_rotation_deg) must spread
  /// by at least this angle, deg; otherwise the translation of X along the common axis is
  /// unobservable.
  double min_axis_spread_deg = 5.0;

  /// Throws OptionError naming the field.
  void Check() const;
};

/// Throws InputError naming the degeneracy when the robot poses cannot determine X: fewer than
/// 3 poses, a pose that is not a rigid transform, pure-translation motions (rotation
/// unobservable), all rotations about one axis (translation along it unobservable).
void CheckHandEyeMotions(const std::vector<Eigen::Isometry3d>& base_from_flange,
                         const HandEyeMotionOptions& options = {});

/// Closed-form flange_from_camera from poses and per-view camera_from_board (same count >= 3),
/// using the motions of every pair (i, j), i < j, whose robot rotation exceeds 1 deg.
/// Throws InputError when too few motions rotate.
Eigen::Isometry3d SolveHandEyeClosedForm(const std::vector<Eigen::Isometry3d>& base_from_flange,
                                         const std::vector<Eigen::Isometry3d>& camera_from_board,
                                         HandEyeMethod method);

/// base_from_board given X: the chordal average of A_i X C_i.
Eigen::Isometry3d BaseFromBoard(const std::vector<Eigen::Isometry3d>& base_from_flange,
                                const std::vector<Eigen::Isometry3d>& camera_from_board,
                                const Eigen::Isometry3d& flange_from_camera);

/// camera_from_board of one view: PnP on the unprojected corners (OpenCV solvePnP on
/// normalised coordinates), refined over the reprojection error through `camera`.
Eigen::Isometry3d EstimateCameraFromBoard(const HandEyeView& view, const CameraModel& camera);

/// AX - XB consistency of one motion: rotation angle (deg) and translation norm (mm) of
/// (A X)^-1 (X B).
struct AxXbError {
  double rotation_deg = 0;
  double translation_mm = 0;
};
AxXbError AxXbResidual(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b,
                       const Eigen::Isometry3d& x);

/// Options of CalibrateHandEye.
struct HandEyeOptions {
  HandEyeMethod initialisation = HandEyeMethod::kParkMartin;  ///< Closed form that starts Ceres.
  HandEyeMotionOptions motion;                                ///< Degeneracy thresholds.
  bool refine = true;        ///< Ceres refinement over reprojection error (else closed form).
  int max_iterations = 100;  ///< Ceres iterations (>= 1).
  double function_tolerance = 1e-12;  ///< Ceres relative cost change to stop (> 0).
  bool estimate_covariance = true;    ///< Compute the 6x6 covariances.
  /// Add the camera's uncertainty to them (file comment; 2 refinements per intrinsic). Default
  /// true; needs the refinement and a camera model that carries its covariance.
  bool include_camera_uncertainty = true;
  int threads = 1;  ///< Ceres threads (>= 1).
  /// For boards symmetric under a 180-degree turn (odd x odd inner corners), renumber the corners
  /// of views whose numbering runs from the other end than view 1's (see CalibrateHandEye).
  bool fix_symmetric_board_order = true;

  /// Throws OptionError naming the field.
  void Check() const;
};

/// Result of CalibrateHandEye.
struct HandEyeResult {
  Eigen::Isometry3d flange_from_camera = Eigen::Isometry3d::Identity();  ///< X.
  Eigen::Isometry3d base_from_board = Eigen::Isometry3d::Identity();     ///< Y.
  Matrix6d flange_from_camera_covariance = Matrix6d::Zero();             ///< See the file comment.
  Matrix6d base_from_board_covariance = Matrix6d::Zero();                ///< See the file comment.
  bool covariance_valid = false;  ///< False when not asked for or Ceres could not invert.
  /// The camera's part of flange_from_camera_covariance (zero when not included).
  Matrix6d flange_from_camera_camera_covariance = Matrix6d::Zero();
  bool camera_uncertainty_included = false;
  std::string camera_uncertainty_note;  ///< Why not, when not included.

  Eigen::Isometry3d initial_flange_from_camera = Eigen::Isometry3d::Identity();  ///< Closed form.
  std::vector<Eigen::Isometry3d> camera_from_board;  ///< Per-view PnP poses (closed-form input).

  bool converged = false;   ///< Ceres reported convergence (true without refinement).
  int iterations = 0;       ///< Ceres iterations.
  std::string termination;  ///< Ceres termination message.

  int observations = 0;             ///< Corners used.
  double reprojection_rms_px = 0;   ///< RMS of corner residuals (per coordinate pair norm).
  double residual_sigma_px = 0;     ///< sqrt(sum r^2 / (2N - 12)): scales the covariance.
  std::vector<double> view_rms_px;  ///< Per view RMS reprojection error.
  std::vector<Eigen::Vector2d> residuals_px;  ///< Every corner residual (predicted - detected).
  /// Per view: A_i X C_i against Y (view closure), rotation deg / translation mm.
  std::vector<AxXbError> view_closure;
  /// Per consecutive motion (i, i+1): AX - XB with the final X and PnP camera poses.
  std::vector<AxXbError> axxb;
  double axxb_rms_rotation_deg = 0;    ///< RMS over `axxb`.
  double axxb_rms_translation_mm = 0;  ///< RMS over `axxb`.
  std::vector<int> reversed_views;     ///< 0-based views whose corner numbering was reversed.
  std::vector<std::string> warnings;   ///< e.g. a view with a large residual.

  /// 1 sigma of X: rotation deg per axis (x, y, z) and translation mm per axis.
  Eigen::Vector3d SigmaRotationDeg() const;
  Eigen::Vector3d SigmaTranslationMm() const;
  /// One line: converged, RMS, AX-XB, 1 sigma.
  std::string Summary() const;
};

/// Eye-in-hand calibration: per-view PnP, motion checks, closed form, then the joint Ceres
/// refinement of X and Y over every corner's reprojection error. When every view has the same
/// board points and listing them backwards is the board turned by 180 degrees, a view whose
/// camera motion from view 1 rotates by an angle that matches the robot's only after reversing
/// its corners is reversed (reported in reversed_views and warnings). Throws InputError for fewer
/// than 3 views, views with < 4 corners or mismatched corner/board counts, and the motion
/// degeneracies of CheckHandEyeMotions.
HandEyeResult CalibrateHandEye(const std::vector<HandEyeView>& views, const CameraModel& camera,
                               const HandEyeOptions& options = {});

}  // namespace lasercell::calib
