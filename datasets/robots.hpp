#pragma once
// Robots of the simulated cell. The vision robot is a UR5 (core NominalUr5); its "true" model
// adds per-joint offset errors (and optionally DH length errors) that the nominal model lacks,
// which the joint-offset calibration must recover. The handling robot stands for the Nachi
// SC15F (approximate standard-DH table; only its base frame and reach matter here).
// Units mm and rad; base_from_flange as in core/kinematics.hpp.

#include <Eigen/Geometry>
#include <optional>
#include <vector>

#include "core/kinematics.hpp"

namespace lasercell::datasets {

/// Errors of the true robot relative to its nominal DH table.
struct RobotErrors {
  std::vector<double> joint_offset_rad;  ///< Added to every joint angle (size = joints).
  std::vector<double> a_error_mm;        ///< Added to a_i (empty = none).
  std::vector<double> d_error_mm;        ///< Added to d_i (empty = none).
};

/// The nominal chain with `errors` applied (joint offsets go into DhJoint::joint_offset_rad).
DhChain ApplyRobotErrors(const DhChain& nominal, const RobotErrors& errors);

/// Approximate standard-DH model of a Nachi SC15F-class 6-axis arm (reach ~1.6 m).
DhChain ApproximateNachiSc15f();

/// Options of the numerical inverse kinematics.
struct IkOptions {
  int max_iterations = 200;      ///< Damped Gauss-Newton steps.
  double tolerance_mm = 1e-7;    ///< Stop when the translation error is below this...
  double tolerance_rad = 1e-10;  ///< ...and the rotation error below this.
  double damping = 1e-6;         ///< Levenberg damping (mm^2).
  double max_step_rad = 0.2;     ///< Largest joint change per step.
};

/// Joint values (rad) with model.BaseFromFlange(q) == base_from_flange, found by damped
/// least squares from `seed` (numerical Jacobian); nullopt when it does not converge.
std::optional<std::vector<double>> SolveIk(const KinematicModel& model,
                                           const Eigen::Isometry3d& base_from_flange,
                                           const std::vector<double>& seed,
                                           const IkOptions& options = {});

}  // namespace lasercell::datasets
