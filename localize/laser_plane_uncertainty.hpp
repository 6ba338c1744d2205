#pragma once
// First-order propagation of the laser plane's calibration uncertainty into the pose of a part
// fitted to the sweep.
//
// A sweep point p (sensor frame) lies on its camera ray through the sensor origin and on the
// calibrated plane n . p + d = 0. The same pixel under the plane (n + dn, d + dd) gives s p with
// s = (d + dd) / (d - dn . p), so to first order
//   dp = p (p^T dn + dd) / d                                                          (1)
// and R_i dp in the target frame (R_i: rotation of the profile's target_from_sensor).
// ICP's point-to-plane objective (Chen & Medioni 1992), linearised at the found pose, moves the
// pose by the left perturbation xi = [w; v] (target frame) that solves
//   H xi = sum_i a_i n_i^T R_i dp_i,   H = sum_i a_i a_i^T,   a_i = [p_i x n_i; n_i]     (2)
// over the points the part explains, so xi = A [dn; dd] with A (6x4) = H^+ B, and the pose
// gains the covariance A Sigma_plane A^T. One plane calibration's error is shared by every
// point of every sweep made with it: unlike the scan noise in ICP's own covariance it does not
// shrink with the number of points, which is why it is its own term.
// Units mm, rad.

#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "core/se3.hpp"

namespace lasercell::localize {

/// The calibrated laser plane of a sweep, its covariance and where each profile's sensor was.
struct LaserPlaneUncertainty {
  Eigen::Vector4d plane_in_sensor = Eigen::Vector4d::Zero();  ///< (n, d), n unit, mm.
  Eigen::Matrix4d covariance = Eigen::Matrix4d::Zero();       ///< Over [n; d] (rank 3).
  /// target_from_sensor of each profile, indexed by the cloud's `profile` attribute.
  std::vector<Eigen::Isometry3d> target_from_sensor;
  /// Optional, both or neither: the sensor's error modes (camera and plane together,
  /// triangulation/sensor_error_field.hpp: a sensor-frame point's displacement, 3 x K, at each
  /// mode's +1 sigma) and the placement's response to the same modes (6 x K, left
  /// perturbations of target <- sensor in the target frame), for a placement calibrated
  /// through the same sensor (StaticEdge::sensor_response). Then each mode moves the pose by
  /// x_k = H^+ B_k + placement_response_k (eq. 2 with the mode's dp, plus what the placement
  /// did), the term is sum_k x_k x_k^T, and `covariance` is not used.
  std::function<Eigen::Matrix<double, 3, Eigen::Dynamic>(const Eigen::Vector3d&)>
      mode_displacements;
  Eigen::Matrix<double, 6, Eigen::Dynamic> placement_response;
  /// Throws OptionError naming the field: plane not finite, n not unit (1e-6), |d| < 1 mm,
  /// covariance not finite or not symmetric, no sensor pose, mode_displacements without
  /// placement_response (or the reverse), placement_response not finite.
  void Check() const;
};

/// Pose covariance (6x6 over [rotation rad; translation mm], left perturbation in the target
/// frame) that the plane's covariance gives a part fitted point-to-plane to `points` with
/// `normals` (target frame, unit) seen in `profiles` (eq. 2). Directions the points do not
/// constrain (H's eigenvalues below 1e-9 x its largest) get no share. Throws InputError when the
/// sizes disagree, there are fewer than 6 points or a profile index has no sensor pose.
Matrix6d LaserPlanePoseCovariance(const LaserPlaneUncertainty& plane,
                                  std::span<const Eigen::Vector3d> points,
                                  std::span<const Eigen::Vector3d> normals,
                                  std::span<const std::int32_t> profiles);

}  // namespace lasercell::localize
