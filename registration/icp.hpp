#pragma once
// Iterative closest point (Besl & McKay 1992; point-to-plane: Chen & Medioni 1992) with a robust
// kernel whose scale follows the residuals (MAD), composed like small_gicp / KISS-ICP: nearest
// neighbours -> residuals -> robust weights -> one linear solve -> pose update, until the update
// is below tolerance. As in the seed (Skotheim IV-G) the scene is the source and the model the
// target: the result is target_from_source (= model_from_scene). Units: mm, rad.
// Deterministic for any thread count: partial sums are per fixed chunk, merged in chunk order.
//
// Pose covariance (IcpResult::covariance), evaluated once at the returned pose over the
// correspondences with a positive kernel weight, with the final kernel scale. J_i is the
// residual's Jacobian w.r.t. a left perturbation xi = [w (rad); u (mm)] of target_from_source
// (core/pose_covariance.hpp); r_i the residual (point-to-plane: n.(T s - q); point-to-point: the
// vector T s - q, the kernel acting on its length); psi(r) = w(r) r the kernel's influence and
// psi'(r) its slope. The M-estimator's sandwich (Huber 1967; Huber 1981, sec. 7.6):
//   cov = m / (m - 6) * A^-1 B A^-1,  A = sum_i J_i^T psi'(r_i) J_i,  B = sum_i J_i^T psi_i psi_i^T
//   J_i
// with m the number of scalar residuals (HC1 factor, MacKinnon & White 1985). For least squares
// this is White's (1980) heteroscedasticity-consistent covariance; it reduces to
// s^2 (J^T W J)^-1, s^2 = sum w r^2 / (m - 6), when every residual has the same variance and
// w = 1. That plain form is not used because a laser scanner's noise lies along the line of
// sight: projected on the surface normal it scales with cos(incidence), so faces seen at
// different angles have different residual variances, and one pooled s^2 gave some directions
// a sigma 1.5x too small and others one 2x too large (tests/registration/icp_covariance_test.cpp).
// Assumptions: first order in xi; independent residuals of zero mean at the true pose.
// Point-to-point is far more optimistic than point-to-plane: its tangential residuals come from
// the model's sampling, not from noise, and its slow convergence stops short; in the
// point-to-plane coverage test's setting its sigmas were 2-6x too small. Use point-to-plane
// where the covariance matters.
// Spatially correlated errors (a model's facets against the real surface, a scan's ripple, the
// bias of point-to-plane against a point-sampled curved model: curvature x spacing^2 / 2 per
// residual) break the independence and make the estimate optimistic: neighbouring residuals
// push the pose the same way. With covariance_block_mm > 0 the source points are grouped into
// cubes of that side and B sums each group's gradient before the outer product (the
// cluster-robust sandwich, Liang & Zeger 1986):
//   B = (G - 1) / G x sum_g gt_g gt_g^T,  gt_g = (I - A_g A^+)^-1 sum_{i in g} J_i^T psi_i,
// for G groups, A_g the group's share of A: each group's gradient as if the group had been
// left out of the fit (CR3, the cluster jackknife; Bell & McCaffrey 2002), since the fit
// absorbs part of a group's shared error into the pose and its residuals understate it.
// Errors correlated over less than a block are then counted at their real weight; errors
// shared by the whole part (a calibration's) still are not: they are other terms of a pose's
// covariance. At least 7 groups are needed, else covariance_valid is false.
// Unobservable directions (a plane, a cylinder, a sphere: eigenvalues of A below 1e-9 of the
// largest) get the variance kIcpUnobservableVariance instead of an inverse, and
// covariance_valid is false; so do fits with m <= 6 scalar residuals. The matrix stays finite.
// IcpResult::residual_sigma_mm reports s above (the pooled residual scale) for information.
// A declared model error (IcpOptions::model_error_sigma_mm > 0): the part is not its CAD (form
// tolerance, warp, a tessellated model's chords), an error the residuals cannot show where the
// fit absorbs it. It is modelled as an offset delta_g of the target surface along its normal,
// the same within each cube g of side model_error_length_mm, independent between cubes, of
// standard deviation sigma_f. The estimating equation sum_i J_i^T psi(r_i) = 0 moves by
// -sum_{i in g} J_i^T psi'(r_i) (dr_i / d delta_g) delta_g, so the pose moves by
// A^-1 sum_g s_g delta_g with s_g = sum_{i in g} psi'(r_i) J_i^T (point-to-plane) and
// J_i^T dpsi_i n_q (point-to-point), and the covariance gains
//   A^+ (sigma_f^2 sum_g s_g s_g^T) A^+
// (first order; added to the sandwich above, which keeps the residuals' own scatter).

#include <Eigen/Geometry>
#include <cstddef>
#include <span>
#include <string>

#include "core/se3.hpp"
#include "registration/kdtree.hpp"

namespace lasercell::registration {

/// Variance given to unobservable directions of the ICP covariance: rad^2 / mm^2 along the
/// free eigenvectors (sigma 1e5), large against any real pose uncertainty, yet finite so that
/// propagating it (InverseCovariance, ComposeCovariance) keeps the matrix free of NaN.
inline constexpr double kIcpUnobservableVariance = 1e10;

/// Error metric.
enum class IcpMetric {
  kPointToPlane,  ///< r = n_target . (T s - q); needs target normals. 6x6 Gauss-Newton step.
  kPointToPoint,  ///< r = |T s - q|; closed-form weighted Horn/Umeyama step (no scale).
};

/// Robust kernel on the residual r with scale sigma.
enum class RobustKernel {
  kNone,          ///< Least squares.
  kHuber,         ///< w = 1 for |r| <= 1.345 sigma, else 1.345 sigma / |r|.
  kTukey,         ///< w = (1 - (r/c)^2)^2 for |r| < c = 4.685 sigma, else 0.
  kGemanMcClure,  ///< w = (sigma^2 / (sigma^2 + r^2))^2.
};

/// Options for AlignIcp.
struct IcpOptions {
  IcpMetric metric = IcpMetric::kPointToPlane;
  RobustKernel kernel = RobustKernel::kTukey;
  /// Fixed kernel scale sigma, mm; 0 = re-estimated each iteration as 1.4826 x median |r|.
  double kernel_scale_mm = 0.0;
  /// Floor for the estimated scale, mm (about the sensor noise), > 0.
  double min_kernel_scale_mm = 0.25;
  /// Pairs farther apart than this are not correspondences, mm (> 0).
  double max_correspondence_distance_mm = 10.0;
  int max_iterations = 30;                 ///< >= 1.
  double translation_tolerance_mm = 1e-3;  ///< Converged when the update moves less than this...
  double rotation_tolerance_rad = 1e-5;    ///< ... and turns less than this.
  std::size_t min_correspondences = 6;     ///< Fewer: terminate (>= 3).
  /// Side of the cubes (source frame) whose residuals the covariance treats as one correlated
  /// group, mm; 0 = every residual independent. >= 0. See the file comment.
  double covariance_block_mm = 0.0;
  /// Normal compatibility (Rusinkiewicz & Levoy 2001): when AlignIcp is given source normals, a
  /// pair whose source and target normals differ by more than this angle (either orientation)
  /// is not a correspondence. Near a sharp edge the nearest model point may lie on the other
  /// face; its normal then measures a top-face point's distance to a wall's plane, a constraint
  /// across the surface that the scan does not hold (and an edge's mixed-pixel range biases).
  /// 0 (default) = no test; 45 deg is the usual choice. In [0, pi/2] rad. Only callers that
  /// pass normals can use it: the grasp's local fit (localize/localize_parts.cpp) does;
  /// LocalizeInCloud's ICP does not yet. Off by default: on the realistic Table I it made the
  /// reported covariance hold the hole's error better but the worst errors larger
  /// (BENCHMARKS.md, "The hole's sideways position").
  double max_normal_angle_rad = 0.0;
  /// Declared standard deviation of the target (model) surface against the real part along its
  /// normal, mm (a form tolerance t spread uniformly: t / sqrt(3)); it adds the model-error term
  /// of the file comment to the covariance (not to the fit). 0 (default) = the model is exact.
  /// >= 0; point-to-point needs target normals for it.
  double model_error_sigma_mm = 0.0;
  /// Side of the cubes (source frame) over which the model error is one offset, mm: about the
  /// length over which the part's deviation from its CAD keeps its sign. > 0.
  double model_error_length_mm = 20.0;
  int threads = 1;  ///< 0 = all cores, 1 = calling thread.
  /// Throws OptionError naming the field when a value is out of range.
  void Check() const;
};

/// Why ICP stopped.
enum class IcpTermination { kConverged, kMaxIterations, kTooFewCorrespondences };

/// Outcome of AlignIcp. Statistics are evaluated at the returned pose.
struct IcpResult {
  Eigen::Isometry3d target_from_source = Eigen::Isometry3d::Identity();
  bool converged = false;
  IcpTermination termination = IcpTermination::kMaxIterations;
  int iterations = 0;               ///< Pose updates applied.
  std::size_t correspondences = 0;  ///< Source points with a target point within max distance.
  std::size_t inliers = 0;          ///< Correspondences with |r| <= 3 sigma.
  double inlier_fraction = 0.0;     ///< inliers / source points.
  double rmse_mm = 0.0;             ///< RMS of the metric's residual over inliers.
  double point_rmse_mm = 0.0;       ///< RMS nearest-neighbour distance over inliers.
  double kernel_scale_mm = 0.0;     ///< Final sigma.
  bool degenerate = false;          ///< The last step was rank-deficient (e.g. a plane).
  /// Covariance of target_from_source over [rotation vector (rad); translation (mm)], left
  /// perturbation in the target frame (target_from_source_true = Exp(xi) * target_from_source);
  /// see the file comment for the estimator. Finite; meaningful only when covariance_valid.
  Matrix6d covariance = Matrix6d::Identity() * kIcpUnobservableVariance;
  /// False when the covariance could not be estimated: unobservable directions at the final
  /// pose (they carry kIcpUnobservableVariance), at most 6 scalar residuals or groups, or too
  /// few correspondences.
  bool covariance_valid = false;
  /// Pooled residual scale s = sqrt(sum w r^2 / (m - 6)), mm (for information; the covariance
  /// uses each residual's own scatter, see the file comment).
  double residual_sigma_mm = 0.0;
  /// One line, e.g. "converged after 7 iterations: rmse 0.41 mm, 812/903 inliers".
  std::string Summary() const;
};

/// Name of a termination reason ("converged", "max_iterations", "too_few_correspondences").
const char* ToString(IcpTermination termination);

/// Aligns `source` to the target cloud held by `target` (kd-tree; `target_normals` unit, same
/// order, required for point-to-plane) starting from `initial_target_from_source`.
/// `source_normals` (unit, one per source point, or empty) enable the normal compatibility test
/// of IcpOptions::max_normal_angle_rad; InputError when their count is wrong.
IcpResult AlignIcp(std::span<const Eigen::Vector3d> source, const KdTree& target,
                   std::span<const Eigen::Vector3d> target_normals,
                   const Eigen::Isometry3d& initial_target_from_source,
                   const IcpOptions& options = {},
                   std::span<const Eigen::Vector3d> source_normals = {});

}  // namespace lasercell::registration
