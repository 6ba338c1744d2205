#pragma once
// Positioning uncertainty of an identified robot: where a point fixed in the sensor frame lands
// in the robot's base, and how well the identification knows it. The separate parameters of a
// joint identification can be poorly determined one by one while their sum is not (joint 6's
// offset and the hand-eye rotation about the flange axis are nearly one direction; the d of
// parallel joints act only as a sum), so a metrology engineer judges the robot by this: the
// 1-sigma of the mapped point, first order,
//   Sigma_p = J Sigma J^T,   J = d(base_from_flange(q; theta) * flange_from_sensor * p) / d theta,
// over the estimated robot parameters theta and, when estimated, the hand-eye left perturbation
// (calib/joint_identification.hpp), with Sigma the solve's covariance of those parameters (its
// rows and columns named by covariance_names). J by central differences.

#include <Eigen/Core>
#include <vector>

#include "calib/joint_identification.hpp"

namespace lasercell::calib {

/// Covariance (mm^2) of base_from_flange(joints) * flange_from_sensor * point_in_sensor under
/// the result's parameter covariance (robot parameters and hand-eye where they were estimated;
/// sphere centres and radius do not move the point). Zero when nothing was estimated. Throws
/// InputError for a wrong number of joint values or a non-finite input.
Eigen::Matrix3d PointCovarianceInBase(const JointIdentificationResult& result,
                                      const std::vector<double>& joints_rad,
                                      const Eigen::Vector3d& point_in_sensor);

/// PointCovarianceInBase at every sweep's middle profile, for the centroid of that sweep's
/// points in the sensor frame (the working point the laser measured there). Sweeps without
/// points are skipped.
PositioningUncertainty PositioningAtSweeps(const JointIdentificationResult& result,
                                           const std::vector<SphereSweep>& sweeps);

}  // namespace lasercell::calib
