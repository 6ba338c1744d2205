#pragma once
// Weighted rigid fit between corresponding 3-D points.
//
// Finds target_from_source minimising sum_i e_i^T S_i^-1 e_i, e_i = t_i - (R s_i + t), with
// S_i = C_target,i + R C_source,i R^T (the points' 3x3 covariances, mm^2).
// 1. Closed form (Horn 1987 / Umeyama 1991, no scale) with scalar weights w_i = 3 / trace(S_i).
// 2. Gauss-Newton on the full Mahalanobis cost over the left perturbation
//    target_from_source = Exp(xi) * T, xi = [rotation vector (rad); translation (mm)]
//    (core/frame_graph.hpp's covariance convention), S_i re-evaluated each iteration.
// The covariance of xi is (J^T S^-1 J)^-1, i.e. it trusts the stated point covariances; chi2 /
// dof says whether they were right (and `scale_covariance_by_residuals` rescales if wanted).
//
// Degenerate input throws InputError naming the degeneracy: fewer than 3 points, or points
// (source or target) on one line, where the rotation about the line is unobservable.
// Units mm, rad. Points named p_in_source / p_in_target.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "core/se3.hpp"

namespace lasercell::calib {

/// Options of FitRigidTransform.
struct RigidFitOptions {
  /// Points whose largest distance from their best-fit line is below this are collinear (mm,
  /// > 0): the rotation about that line is then unobservable and the fit throws.
  double min_off_line_mm = 1.0;
  /// Scale the covariance by chi2 / dof when dof > 0 (default off: trust the stated point
  /// covariances; with 4 points dof = 6 and the scale itself is very noisy).
  bool scale_covariance_by_residuals = false;
  int max_iterations = 20;  ///< Gauss-Newton iterations (> 0).
  /// Names of the points in error messages, e.g. "sphere" -> "sphere 2".
  std::string item_name = "point";

  /// Throws OptionError naming the field.
  void Check() const;
};

/// Outcome of FitRigidTransform.
struct RigidFitResult {
  Eigen::Isometry3d target_from_source = Eigen::Isometry3d::Identity();
  /// 6x6 covariance of xi = [rotvec (rad); translation (mm)], left perturbation.
  Matrix6d covariance = Matrix6d::Zero();
  /// Per point: t_i - T s_i (mm, target frame), its norm, and sqrt(e^T S^-1 e).
  std::vector<Eigen::Vector3d> residuals_mm;
  std::vector<double> residual_norms_mm;
  std::vector<double> mahalanobis;
  double rms_mm = 0;  ///< RMS of residual_norms_mm.
  double chi2 = 0;    ///< sum e^T S^-1 e.
  int dof = 0;        ///< 3n - 6.
  int iterations = 0;
  bool converged = false;
  /// Distance of the farthest source point from the source points' best-fit line, mm.
  double off_line_mm = 0;
  /// Closed-form (scalar-weight Horn/Umeyama) estimate before the refinement.
  Eigen::Isometry3d closed_form = Eigen::Isometry3d::Identity();

  /// 1-sigma of the rotation (deg, per axis of the rotation vector) and translation (mm).
  Eigen::Vector3d RotationSigmaDeg() const;
  Eigen::Vector3d TranslationSigmaMm() const;
  /// One line: rms, chi2/dof, 1-sigma.
  std::string Summary() const;
};

/// Weighted rigid fit. `source_covariances` and `target_covariances` are empty (identity,
/// i.e. 1 mm^2 isotropic) or one positive definite 3x3 (mm^2) per point. Throws InputError for
/// mismatched sizes, non-finite values, fewer than 3 points or collinear points.
RigidFitResult FitRigidTransform(const std::vector<Eigen::Vector3d>& p_in_source,
                                 const std::vector<Eigen::Vector3d>& p_in_target,
                                 const std::vector<Eigen::Matrix3d>& source_covariances = {},
                                 const std::vector<Eigen::Matrix3d>& target_covariances = {},
                                 const RigidFitOptions& options = {});

// The closed form (HornRigidTransform) is core's (core/se3.hpp): the correspondence search
// scores many assignments with it, and a rank-deficient cross-covariance there means a wrong
// assignment, not degenerate data; FitRigidTransform checks collinearity.

/// Largest distance of the points from their least-squares line, mm (0 for < 2 points).
double MaxDistanceFromLine(const std::vector<Eigen::Vector3d>& points);

}  // namespace lasercell::calib
