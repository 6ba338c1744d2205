#pragma once
// Sphere fitting to measured surface points.
//
// Conventions: points and the centre are in one frame, whatever the caller's (`p_in_frame`);
// units mm. Residuals are signed point-to-surface distances |p - c| - R (positive outside).
//
// Method: algebraic initialisation (Kasa: |p|^2 + D.p + G = 0 is linear in D, G; solved in
// centred, scaled coordinates), then geometric least squares in Ceres (SphereDistanceCost) with a
// Cauchy robust loss; points whose residual exceeds outlier_threshold_sigma robust sigmas
// (1.4826 * MAD) are flagged as outliers, and a final plain least-squares pass over the inliers
// gives the estimate and its covariance: sigma^2 (J^T J)^-1 with sigma^2 = SSR / (n - p), the
// residual variance (Gauss-Markov; the covariance is scaled by the residual variance, so it needs
// no noise model from the caller).
//
// Half and partial spheres: with the radius known (options.radius_mm) any cap fixes the centre.
// With a free radius, centre-along-the-cap-axis and radius trade off as the cap shrinks; the fit
// reports the cap's half-angle and sets radius_determined = false (with a warning) when it is
// below options.min_cap_half_angle_deg.
//
// Usage: SphereFitResult r = FitSphere(points, {.radius_mm = 25.0});

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace lasercell::calib {

/// Options of FitSphere.
struct SphereFitOptions {
  /// Known sphere radius, mm (> 0). Unset: the radius is estimated with the centre.
  std::optional<double> radius_mm;
  /// Scale of the Cauchy robust loss of the robust pass, mm (> 0). Residuals well below it
  /// count fully; far beyond it they hardly pull. ~3-6x the point noise.
  double robust_loss_scale_mm = 0.3;
  /// Points with |residual| > this many robust sigmas (1.4826 * median |residual|) after the
  /// robust pass are flagged as outliers and left out of the final pass (> 0).
  double outlier_threshold_sigma = 4.0;
  /// Outliers are only flagged beyond this absolute residual too, mm (>= 0): keeps near-perfect
  /// synthetic data from being cut at a sub-micrometre MAD.
  double min_outlier_threshold_mm = 1e-3;
  /// Free radius: a cap narrower than this half-angle (deg, in (0, 90]) does not fix the
  /// radius; the result says so (radius_determined = false).
  double min_cap_half_angle_deg = 25.0;
  /// Ceres iterations per pass (> 0).
  int max_iterations = 100;

  /// Throws OptionError naming the field.
  void Check() const;
};

/// Outcome of FitSphere. Covariances are 1-sigma^2, scaled by the residual variance.
struct SphereFitResult {
  /// False: too few of the points agree with one sphere, or they do not fix it (see failure).
  bool success = false;
  std::string failure;                               ///< Why not, when !success.
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  ///< Centre, mm (caller's frame).
  double radius_mm = 0;                              ///< Fitted or given radius.
  bool radius_fixed = false;                         ///< True when options.radius_mm was given.
  /// Covariance of [centre; radius] (4x4, mm^2); the radius row/column is zero when fixed.
  Eigen::Matrix4d covariance = Eigen::Matrix4d::Zero();
  /// The centre block of `covariance`, mm^2.
  Eigen::Matrix3d CenterCovariance() const { return covariance.topLeftCorner<3, 3>(); }
  double radius_sigma_mm = 0;    ///< 1-sigma of the radius (0 when fixed).
  double residual_sigma_mm = 0;  ///< sqrt(SSR / (n - p)) over the inliers.
  double rms_mm = 0;             ///< RMS residual over the inliers.
  /// Signed residual of every input point (same order), mm, at the final estimate.
  std::vector<double> residuals_mm;
  /// 1 for points flagged as outliers (same order as the input).
  std::vector<std::uint8_t> outlier;
  std::size_t num_inliers = 0;
  std::size_t num_outliers = 0;
  int iterations = 0;       ///< Ceres iterations over both passes.
  bool converged = false;   ///< Both Ceres passes converged.
  std::string termination;  ///< Ceres termination of the final pass.
  /// Unit direction from the centre to the middle of the measured cap (mean of the inliers'
  /// directions), and the half-angle (deg) of the cone about it holding 95 % of them.
  Eigen::Vector3d cap_axis = Eigen::Vector3d::Zero();
  double cap_half_angle_deg = 0;
  /// False when the radius is free and the cap is too small to fix it (see warnings).
  bool radius_determined = true;
  std::vector<std::string> warnings;  ///< Human-readable, e.g. the small-cap warning.

  /// One line: centre, radius, 1-sigma, rms, inliers/outliers, cap angle.
  std::string Summary() const;
};

/// Fits a sphere to `points` (mm, any frame). Throws OptionError for bad options and
/// InputError naming the degeneracy for points that cannot determine a sphere: non-finite
/// points, fewer than 5 points (4 with the radius known), all points on a plane with a free
/// radius. An outcome on such valid points -- too few of them agree with one sphere, a singular
/// information matrix -- is reported in the result (success = false, `failure`), never thrown.
SphereFitResult FitSphere(std::span<const Eigen::Vector3d> points,
                          const SphereFitOptions& options = {});

/// Algebraic (Kasa) sphere through the points: centre and radius, or nullopt when the points are
/// coplanar or fewer than 4. Biased for small caps (use FitSphere for the estimate).
std::optional<std::pair<Eigen::Vector3d, double>> AlgebraicSphere(
    std::span<const Eigen::Vector3d> points);

}  // namespace lasercell::calib
