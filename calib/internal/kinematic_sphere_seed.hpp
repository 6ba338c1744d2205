#pragma once
// Private seed for the robot-sphere solvers: a small algebraic sphere fit and a local RANSAC that
// finds the sphere in one short sweep (points in the robot base, posed by the initial model).
// The "spheres" module (calib/sphere_fit.*) has the full geometric fit; this is only a seed.

#include <Eigen/Core>
#include <optional>
#include <vector>

namespace lasercell::calib::internal {

struct SeedSphere {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double radius_mm = 0;
  std::vector<int> inliers;  ///< Indices into the input points.
};

/// Algebraic least-squares sphere |p|^2 = 2 c.p + k through >= 4 points (Pratt-free, plain);
/// nullopt when the points are (nearly) coplanar or fewer than 4.
std::optional<SeedSphere> AlgebraicSphere(const std::vector<Eigen::Vector3d>& points,
                                          const std::vector<int>& indices);

/// Options of FindSphere.
struct FindSphereOptions {
  double min_radius_mm = 5;      ///< Smallest plausible radius.
  double max_radius_mm = 150;    ///< Largest plausible radius (rejects planes).
  double neighbourhood_mm = 80;  ///< Samples are drawn within this distance of a seed point.
  double inlier_gate_mm = 1.0;   ///< |distance - radius| for an inlier.
  int hypotheses = 400;          ///< RANSAC hypotheses.
  unsigned seed = 1;             ///< Random seed (std::mt19937 raw draws: deterministic).
  /// When set, only points within this distance of `near_centre` are considered.
  std::optional<Eigen::Vector3d> near_centre;
  double near_distance_mm = 0;
};

/// The sphere with the most inliers (refined algebraically on them, twice); nullopt when none
/// has at least 10 inliers. Inlier sets a plane fits about as well as the sphere (thickness
/// across the best plane below 3x the sphere's RMS residual: a patch of floor fitted by a large
/// sphere) are skipped.
std::optional<SeedSphere> FindSphere(const std::vector<Eigen::Vector3d>& points,
                                     const FindSphereOptions& options);

/// Up to `count` spheres found one after the other (each one's inliers removed before the next),
/// best first.
std::vector<SeedSphere> FindSpheres(const std::vector<Eigen::Vector3d>& points,
                                    const FindSphereOptions& options, int count);

}  // namespace lasercell::calib::internal
