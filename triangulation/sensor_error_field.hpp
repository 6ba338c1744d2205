#pragma once
// Where a laser-triangulation sensor's calibration error moves the points it measures.
//
// A point p (sensor frame) is measured at the pixel q = project(theta, p) where its camera ray
// meets the laser plane n . p + d = 0. Under an error mode (core/frame_graph.hpp
// SensorErrorMode: a step dtheta of the intrinsics and [dn; dd] of the plane, at +1 sigma) the
// same pixel is triangulated to p + dp with, to first order,
//   dq/dp dp + dq/dtheta dtheta = 0        (the pixel stays)
//   n^T dp + dn^T p + dd = 0               (the point stays on the stepped plane)
// three equations for dp. With dtheta = 0 this is dp = p (p^T dn + dd) / d (the plane-only
// formula of localize/laser_plane_uncertainty.hpp). Every point measured through the sensor
// shares the modes' coefficients, so two things measured through it (a sensor-to-robot
// calibration and a part's pose) err together: consumers propagate mode by mode.
// Units mm, rad.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <functional>
#include <memory>
#include <vector>

#include "calib/camera_model.hpp"
#include "core/frame_graph.hpp"
#include "core/point_cloud.hpp"

namespace lasercell::triangulation {

/// The displacement of measured points under each error mode of one sensor (camera + plane).
class SensorErrorField {
 public:
  /// Throws InputError when the plane has no error modes, a mode's intrinsics step does not
  /// have camera.NumIntrinsics() values, or the plane passes within 1 mm of the sensor origin.
  SensorErrorField(const calib::CameraModel& camera, const LaserPlaneEntry& plane);

  /// Number of modes (columns of Displacements).
  Eigen::Index Modes() const { return static_cast<Eigen::Index>(modes_.size()); }

  /// dp (3 x Modes(), mm) of the point p measured at p_in_sensor. Zero columns for a point the
  /// first-order system cannot move (ray parallel to the plane).
  Eigen::Matrix<double, 3, Eigen::Dynamic> Displacements(const Eigen::Vector3d& p_in_sensor) const;

 private:
  calib::CameraModel camera_;
  Eigen::Vector3d normal_;
  std::vector<SensorErrorMode> modes_;
  Eigen::MatrixXd intrinsics_steps_;  // NumIntrinsics() x Modes(); zero columns for plane modes
};

/// The displacement (3 x Modes(), in the cloud's frame) of cloud point i: the field at the
/// point's sensor-frame position in its profile, frame_from_sensor[profile[i]], turned into
/// the cloud's frame. The function keeps its own copies. Throws InputError when the cloud has
/// no profile attribute, or a profile index has no sensor pose.
std::function<Eigen::Matrix<double, 3, Eigen::Dynamic>(std::size_t)> CloudPointDisplacements(
    const SensorErrorField& field, const PointCloud& cloud,
    const std::vector<Eigen::Isometry3d>& frame_from_sensor);

}  // namespace lasercell::triangulation
