#pragma once
// Private helpers of the laser-plane calibration: a total least-squares plane through points
// and the orientation rule of its planes (d <= 0). Ray-plane intersection is core's
// (core/ray_plane.hpp).

#include <Eigen/Core>
#include <vector>

namespace lasercell::calib::internal {

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
