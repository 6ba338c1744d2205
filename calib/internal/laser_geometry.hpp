#pragma once
// Small private helpers of the laser-plane calibration: ray/plane intersection and a total
// least-squares plane through points. The triangulation module will hold the shared versions
// (triangulation/triangulator*); this copy is private to calib until then.

#include <Eigen/Core>
#include <optional>
#include <vector>

namespace lasercell::calib::internal {

/// The point where the ray t * ray (t > 0, from the origin) meets n . p + d = 0; nullopt when
/// the ray is parallel to the plane (|n . ray| < 1e-12) or the plane lies behind the origin.
std::optional<Eigen::Vector3d> IntersectRayPlane(const Eigen::Vector3d& ray,
                                                 const Eigen::Vector3d& normal, double offset);

/// A plane (unit normal, offset) through points by total least squares (smallest eigenvector of
/// the scatter), the normal oriented so that the offset is <= 0 (n points from the origin
/// towards the plane). Requires >= 3 points.
struct TlsPlane {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double offset_mm = 0;
  double rms_mm = 0;
  /// Eigenvalues of the scatter per point (ascending): the middle one ~0 means collinear.
  Eigen::Vector3d spread_mm2 = Eigen::Vector3d::Zero();
};
TlsPlane FitPlaneTls(const std::vector<Eigen::Vector3d>& points);

/// Orients (n, d) so that d <= 0 (n points from the frame origin towards the plane).
void OrientPlane(Eigen::Vector3d& normal, double& offset);

}  // namespace lasercell::calib::internal
