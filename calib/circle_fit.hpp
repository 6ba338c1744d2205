#pragma once
// Circle fitting to 2D points: one laser profile across a sphere or a cylinder is a circle arc
// in the laser plane (calib/sphere_section_hand_eye.hpp), often with other surfaces beside it.
//
// Conventions: points and the centre in one 2D frame, whatever the caller's (for a profile the
// laser plane's (x, z)); units mm. Residuals are signed point-to-circle distances |p - c| - r.
//
// Method: RANSAC over circles through three points (radius within the options' range), the
// largest consensus within inlier_gate_mm; then geometric least squares (Gauss-Newton with
// Levenberg damping) over the consensus, alternated with trimming: points farther than
// trim_sigmas robust sigmas (1.4826 * median |residual|) are left out and the fit repeated until
// the inlier set is stable. Covariance sigma^2 (J^T J)^-1 with sigma^2 = SSR / (n - 3) over the
// inliers (Gauss-Markov, scaled by the residual variance: no noise model needed).

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace lasercell::calib {

/// Options of FitCircle. Units mm.
struct CircleFitOptions {
  double min_radius_mm = 1.0;     ///< Smallest circle accepted (> 0).
  double max_radius_mm = 1000.0;  ///< Largest circle accepted (> min_radius_mm).
  /// RANSAC consensus gate: a point within this distance of a candidate circle supports it
  /// (> 0). A few times the point noise plus the candidate's own error; 0.2 mm suits profilers
  /// with ~0.01-0.05 mm noise.
  double inlier_gate_mm = 0.2;
  double trim_sigmas = 3.0;     ///< Trimming threshold in robust sigmas (> 0).
  double min_trim_mm = 1e-3;    ///< The trimming threshold is at least this (>= 0).
  int ransac_iterations = 400;  ///< Three-point candidates drawn (> 0).
  std::uint64_t seed = 1;       ///< RANSAC draws (deterministic for a seed).
  std::size_t min_points = 10;  ///< Fewer inliers: no circle (>= 3).
  /// Throws OptionError naming the field.
  void Check() const;
};

/// Outcome of FitCircle.
struct CircleFitResult {
  bool success = false;
  std::string failure;  ///< Why not, when !success.
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  double radius_mm = 0;
  /// Covariance of [centre x, centre y, radius], mm^2, scaled by the residual variance.
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  double rms_mm = 0;  ///< RMS residual over the inliers.
  std::size_t inliers = 0, outliers = 0;
  /// Angle the inliers span about the centre (360 minus the largest empty gap), deg.
  double arc_deg = 0;
  std::vector<std::uint8_t> inlier;  ///< Per input point.
  /// One line: centre, radius, 1-sigma, rms, inliers, arc.
  std::string Summary() const;
};

/// Fits a circle to `points` (see the file comment). Throws InputError for non-finite points
/// or fewer than options.min_points points; a circle that cannot be found among valid points
/// (no three-point candidate within the radius range gathers min_points) is reported as
/// success = false with the reason.
CircleFitResult FitCircle(std::span<const Eigen::Vector2d> points,
                          const CircleFitOptions& options = {});

}  // namespace lasercell::calib
