#pragma once
// Eye-in-hand calibration of a laser sensor: sweeps of fixed spheres from
// several robot poses; one Ceres problem over vision_flange_from_sensor, the sphere centres (in
// the robot base) and their common radius, minimising the point-to-sphere distances of every
// swept point, each placed by FK(joints) * flange_from_sensor (robot model held fixed).
// Frames, units and the solver are those of calib/joint_identification.hpp (IdentifyRobot with
// the robot held); this header is the front function with its own result.

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "calib/joint_identification.hpp"
#include "core/kinematics.hpp"
#include "core/se3.hpp"

namespace lasercell::calib {

/// Options of CalibrateLaserHandEye (see JointIdentificationOptions for the shared fields; the
/// robot-parameter and hand-eye switches are set by the function).
struct LaserHandEyeOptions {
  JointIdentificationOptions solver;  ///< Noise, gates, radius, known centres, iterations.
  /// Throws OptionError naming the field.
  void Check() const { solver.Check(); }
};

/// Outcome of CalibrateLaserHandEye.
struct LaserHandEyeResult {
  bool converged = false;  ///< The solver converged.
  Eigen::Isometry3d flange_from_sensor = Eigen::Isometry3d::Identity();
  /// 6x6 over [rotation vector rad; translation mm], left perturbation.
  Matrix6d covariance = Matrix6d::Zero();
  std::vector<Eigen::Vector3d> sphere_centres_in_base;  ///< mm.
  std::vector<Eigen::Vector3d> sphere_centre_sigmas;    ///< 1-sigma per coordinate, mm.
  double radius_mm = 0, radius_sigma_mm = 0;
  double rms_mm = 0;  ///< RMS point-to-sphere distance over the points used.
  std::size_t points_used = 0;
  std::vector<SweepResidual> sweeps;
  std::vector<double> residuals_mm;
  ObservabilityReport observability;
  /// Predicted 1-sigma of the laser's working point in the base over the sweeps' poses, from
  /// the hand-eye covariance alone: the robot model is held as exact, so its own uncertainty
  /// is not in it (calibrate it jointly with `IdentifyRobot` and estimate_hand_eye for that).
  PositioningUncertainty positioning;
  std::vector<std::string> warnings;  ///< Those of the underlying joint identification.
  /// One line: converged, RMS, translation and rotation 1-sigma.
  std::string Summary() const;
};

/// Calibrates flange_from_sensor from sphere sweeps taken with `robot` (its model held fixed;
/// use the joint-identified model for the best result). `initial_flange_from_sensor` seeds the
/// solve (a few mm / degrees off is fine). Throws InputError as IdentifyRobot does, in
/// particular for pure-translation or single-axis motions.
LaserHandEyeResult CalibrateLaserHandEye(const DhChain& robot,
                                         const Eigen::Isometry3d& initial_flange_from_sensor,
                                         const std::vector<SphereSweep>& sweeps,
                                         const LaserHandEyeOptions& options = {});

}  // namespace lasercell::calib
