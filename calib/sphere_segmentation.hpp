#pragma once
// Segmentation of calibration (half) spheres out of a sweep point cloud.
//
// Input: a sweep cloud in one frame (mm), e.g. the sensor frame at the start of a linear sweep,
// holding spheres on cylindrical stands over a floor or pallet. Output: one FitSphere result per
// sphere found, with the indices of its points. Stands, floor and clutter are ignored.
//
// Method (Hough voting, then RANSAC and region growing per candidate):
//  1. Spatial hash of the cloud; samples on a voxel grid of sample_spacing_mm.
//  2. Per sample, a normal from the PCA of its neighbours within normal_radius_mm; it votes for
//     centres p +- R n (both signs, no orientation needed) in a 3-D accumulator of vote_cell_mm
//     cells. A sphere's samples all vote for its centre; a plane's votes spread over a plane and
//     a cylinder's (a stand of the sphere's radius) over its axis line.
//  3. Candidates: accumulator peaks (27-cell sums, local maxima) with >= min_votes, strongest
//     first, none closer than R to a stronger one.
//  4. Per candidate: the cloud's points within R + search_margin_mm of it; RANSAC on 4-point
//     algebraic spheres whose radius is within radius_tolerance_mm of R (inliers: |residual| <
//     ransac_threshold_mm); FitSphere (robust loss, outlier flags) on the consensus; the inliers'
//     largest connected component (region growing over connectivity_mm) kept and refitted.
//  5. Accepted when it keeps >= min_points points, its residuals peak (RMS <= max_rms_fraction of
//     the inlier distance, itself min(ransac_threshold, 4 sigma of the fit)), nearly all
//     points near its shell inside its cap are inliers (min_shell_fraction: rejects surfaces that
//     only cross the shell), its cap's half-angle is >= min_cap_half_angle and it faces the sensor
//     (cap axis within max_cap_tilt_deg of towards_sensor): a stand's axis votes form a ring-shaped
//     consensus whose mean normal is sideways, so it fails. Points of accepted spheres are excluded
//     from later candidates.
//  6. For organized sweeps, the fit covariance is multiplied by LineCorrelationFactor: speckle
//     makes the noise of neighbouring columns correlated, and FitSphere's covariance assumes
//     independent points (it would be ~3x too small in sigma with 0.08 px speckle of 3-column
//     grain).
// Rejected candidates are listed with the reason, so "no sphere found" is explained.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "calib/sphere_fit.hpp"
#include "core/point_cloud.hpp"

namespace lasercell::calib {

/// Options of SegmentSpheres. Lengths in mm, angles in deg.
struct SphereSegmentationOptions {
  double radius_mm = 25.0;  ///< Nominal sphere radius (> 0); votes use it.
  /// Fit each sphere with the radius fixed to radius_mm (true) or free (false).
  bool fix_radius = true;
  /// Accepted |fitted - nominal| radius for RANSAC hypotheses and free-radius fits (> 0).
  double radius_tolerance_mm = 2.0;
  double sample_spacing_mm = 2.5;        ///< Voxel size of the voting samples (> 0).
  double normal_radius_mm = 5.0;         ///< Neighbourhood of the PCA normals (> 0).
  double vote_cell_mm = 2.0;             ///< Accumulator cell (> 0).
  int min_votes = 40;                    ///< Fewest votes (27-cell sum) of a candidate (> 0).
  int max_candidates = 60;               ///< Candidates examined, strongest first (> 0).
  double search_margin_mm = 3.0;         ///< Points within R + this of a candidate are examined.
  double ransac_threshold_mm = 0.5;      ///< RANSAC inlier distance (> 0).
  int ransac_iterations = 300;           ///< RANSAC draws per candidate (> 0).
  double connectivity_mm = 6.0;          ///< Region-growing neighbour distance (> 0); > the sweep's
                                         ///< profile spacing.
  std::size_t min_points = 100;          ///< Fewest points on an accepted sphere.
  double min_cap_half_angle_deg = 30.0;  ///< Smallest accepted cap (95 % cone), (0, 90].
  /// Unit direction from the spheres towards the sensor in the cloud's frame: (0, 0, -1) for
  /// the sensor frame (the camera looks along +z). Zero vector: no facing check.
  Eigen::Vector3d towards_sensor = Eigen::Vector3d(0, 0, -1);
  double max_cap_tilt_deg = 60.0;  ///< Largest angle between cap axis and towards_sensor.
  /// Shell test: of the points inside the cap's cone within 3x the inlier distance of the
  /// surface, at least this fraction must be inliers, (0, 1]. A real sphere holds nearly all of
  /// them; a surface that merely crosses the sphere's shell leaves a uniform residual band
  /// (about a third).
  double min_shell_fraction = 0.9;
  /// Peakedness test: the fit RMS over the inlier distance d must be <= this, (0, 1]. Sensor
  /// noise truncated at d = 4 sigma gives ~0.25; a surface crossing the shell fills the band
  /// +-d uniformly, ~0.58.
  double max_rms_fraction = 0.4;
  std::size_t max_spheres = 16;  ///< Stop after this many spheres.
  unsigned seed = 1;             ///< RANSAC random stream (results are deterministic).
  SphereFitOptions fit;          ///< Per-sphere fit (radius_mm set from fix_radius).

  /// Throws OptionError naming the field.
  void Check() const;
};

/// One sphere found in the cloud.
struct SegmentedSphere {
  SphereFitResult fit;               ///< Fit over `indices` (residuals/outliers in that order).
  std::vector<std::size_t> indices;  ///< Cloud indices of the sphere's points.
  int votes = 0;                     ///< Accumulator votes of its candidate.
  double shell_fraction = 0;         ///< Inliers / points near the shell inside the cap.
  double inlier_distance_mm = 0;     ///< Inlier distance used for this sphere.
  /// Factor applied to fit.covariance for noise correlated along the laser line (1 = none, or
  /// the cloud has no profile/column fields): see LineCorrelationFactor.
  double correlation_factor = 1.0;
};

/// A candidate that was not accepted.
struct RejectedSphereCandidate {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  ///< Candidate centre, mm.
  int votes = 0;
  std::string reason;  ///< e.g. "cap faces away from the sensor (78 deg)".
};

/// Outcome of SegmentSpheres.
struct SphereSegmentationResult {
  std::vector<SegmentedSphere> spheres;  ///< Strongest first.
  std::vector<RejectedSphereCandidate> rejected;
  std::size_t samples = 0;     ///< Voting samples.
  std::size_t candidates = 0;  ///< Candidates examined.
  /// One line, e.g. "4 spheres (3120, 2980, ... points), 7 candidates rejected".
  std::string Summary() const;
};

/// Variance inflation for residuals correlated along the laser line (laser speckle): for the
/// points `indices` of an organized sweep (profile and column fields) with fit residuals
/// `residuals` (same order; `outlier` flags skipped), the lag-k autocorrelation rho_k of the
/// residuals of neighbouring columns in one profile, and kappa = 1 + 2 sum rho_k over the initial
/// positive run of lags (k <= max_lag) -- the effective-sample-size factor of a correlated series
/// (Geyer 1992's initial positive sequence). 1 when the cloud has no profile/column fields.
double LineCorrelationFactor(const PointCloud& cloud, const std::vector<std::size_t>& indices,
                             const std::vector<double>& residuals,
                             const std::vector<std::uint8_t>& outlier, int max_lag = 40);

/// Finds spheres of about options.radius_mm in `cloud` (positions only). Throws OptionError for
/// bad options; an empty or sphere-free cloud gives an empty `spheres` list (not an error).
SphereSegmentationResult SegmentSpheres(const PointCloud& cloud,
                                        const SphereSegmentationOptions& options = {});

}  // namespace lasercell::calib
