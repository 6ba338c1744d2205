#pragma once
// Robot joint-offset (and optional DH) identification from laser sweeps of fixed spheres taken
// from many poses of the vision robot, jointly with the hand-eye transform if asked (Skotheim et
// al. 2012 found their eye-in-hand result limited by uncalibrated joint offsets and name this as
// further work). Also the engine of the laser eye-in-hand
// calibration (calib/laser_hand_eye.hpp), which is the same problem with the robot held fixed.
//
// Frames and conventions:
//   - points are given in the `sensor` frame per profile (triangulated laser points), with the
//     robot joint values (rad) the controller reported for that profile;
//   - p_in_base = base_from_flange(joints; robot model) * flange_from_sensor * p_in_sensor,
//     base = the robot's base frame (`vision_base`), flange = `vision_flange`;
//   - spheres are fixed in the base; their centres (mm) and one common radius (mm) are
//     estimated (or the centres held near known values, e.g. from the half-sphere calibration).
// Cost: sum over points of ((|p_in_base - c_s| - r) / point_sigma)^2, one Ceres problem
// (calib/cost_functions/kinematic_sphere_cost.hpp). Robot parameters are corrections to the
// input chain in core's DhParameterVector order (joint offsets rad, a mm, d mm, alpha rad);
// hand-eye is a left perturbation [rotation vector rad; translation mm] of flange_from_sensor.
//
// Observability (calib/robot_observability.hpp): before solving, the column-scaled Jacobian at
// the seed is analysed; every unidentifiable direction is resolved by FIXING the robot
// parameter with the largest component (held at its input value, reported by name). Typical:
// with free sphere centres, joint_offset_1 ~ a rotation of all centres about base z (the offset
// becomes part of the base mount); with a free hand-eye transform, joint_offset_6 ~ the hand-eye
// rotation about flange z (the offset is absorbed in flange_from_sensor). A direction with no
// robot parameter (e.g. hand-eye translation vs sphere centres under pure translations) is
// degenerate data and throws InputError naming it.
//
// Uncertainty: covariance = s^2 (J^T J)^-1 at the solution, s^2 = sum r^2 / (m - n) (a
// posteriori variance factor, so a wrong point_sigma_mm does not bias the 1-sigma).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "calib/robot_observability.hpp"
#include "core/kinematics.hpp"
#include "core/se3.hpp"

namespace lasercell::calib {

/// One laser profile: reported joints and its triangulated points in the sensor frame.
struct SweptProfile {
  std::vector<double> joints_rad;                 ///< Joint values reported for the exposure.
  std::vector<Eigen::Vector3d> points_in_sensor;  ///< Laser points, sensor frame, mm.
};

/// One short sweep of one sphere from one robot pose.
struct SphereSweep {
  std::string name;                    ///< For messages and reports, e.g. the profile file.
  int sphere = 0;                      ///< Which fixed sphere it aims at (0-based).
  std::vector<SweptProfile> profiles;  ///< In time order.
};

/// Options of IdentifyRobot. Units mm, rad.
struct JointIdentificationOptions {
  bool estimate_joint_offsets = true;  ///< Joint offsets (rad).
  bool estimate_dh_deltas = false;     ///< Also a, d (mm) and alpha (rad) of every joint.
  bool estimate_hand_eye = false;      ///< Also flange_from_sensor.
  bool estimate_radius = true;         ///< Sphere radius free (else radius_mm held).
  double radius_mm = 0;                ///< Initial (or held) radius; 0: from the seed fits.
  double point_sigma_mm = 0.1;         ///< A-priori point noise (weights; > 0).
  /// Known sphere centres in the base (index = sphere); empty: centres free.
  std::vector<Eigen::Vector3d> known_centres_in_base;
  double known_centre_sigma_mm = 0.05;  ///< 1-sigma of each known centre coordinate (> 0).
  int max_points_per_sweep = 300;       ///< Points per sweep used in the solve (evenly picked).
  double seed_gate_mm = 1.5;            ///< Inlier gate of the per-sweep seed sphere fit.
  /// Seed sphere centres of one sphere seen from different sweeps agree within this (the
  /// initial model's error, mm); candidates farther from the consensus are other objects.
  double seed_consistency_mm = 60;
  double gate_sigmas = 4;     ///< Final inlier gate, in robust sigmas of the residuals.
  double min_gate_mm = 0.05;  ///< The final gate is at least this.
  /// Plausible sphere radii for the seed fit (mm); when radius_mm is given, the seed accepts
  /// only radius_mm +- 20 %. Raise max_radius_mm for targets larger than 80 mm.
  double min_radius_mm = 5;
  double max_radius_mm = 80;
  int max_iterations = 100;            ///< Ceres iterations per solve.
  ObservabilityOptions observability;  ///< Unidentifiable-direction detection.
  /// Throws OptionError naming the field.
  void Check() const;
};

/// Residual statistics of one sweep at the solution.
struct SweepResidual {
  std::string name;
  int sphere = 0;
  std::size_t points = 0;  ///< Points used.
  double rms_mm = 0;       ///< RMS point-to-sphere distance.
  double max_abs_mm = 0;   ///< Largest |distance|.
  double mean_mm = 0;      ///< Mean signed distance (a pose error shows as a bias).
};

/// Names of the hand-eye columns of JointIdentificationResult::covariance, in the order of the
/// left perturbation [rotation vector rad; translation mm].
inline constexpr std::array<const char*, 6> kHandEyeParameterNames = {
    "hand_eye_rx", "hand_eye_ry", "hand_eye_rz", "hand_eye_tx", "hand_eye_ty", "hand_eye_tz"};

/// The predicted positioning 1-sigma over a set of robot poses (calib/robot_positioning.hpp).
struct PositioningUncertainty {
  double rms_mm = 0;  ///< RMS over the poses of sqrt(trace(Sigma_p)) (3D 1-sigma), mm.
  double max_mm = 0;  ///< Largest sqrt(trace(Sigma_p)), mm.
  int poses = 0;
};

/// Outcome of IdentifyRobot.
struct JointIdentificationResult {
  bool converged = false;   ///< The solver converged.
  std::string termination;  ///< Ceres' termination message.
  int iterations = 0;       ///< Ceres iterations (all passes).
  DhChain robot;            ///< The identified chain (input with corrections applied).
  Eigen::Isometry3d flange_from_sensor = Eigen::Isometry3d::Identity();
  /// 6x6 over [rotation vector rad; translation mm], left perturbation (when estimated).
  std::optional<Matrix6d> flange_from_sensor_covariance;
  std::vector<std::string> parameter_names;             ///< 4 n robot parameters (DhParameterName).
  std::vector<double> parameter_corrections;            ///< Identified minus input (rad or mm).
  std::vector<double> parameter_sigmas;                 ///< 1-sigma; 0 when not estimated or fixed.
  std::vector<bool> parameter_estimated;                ///< True when solved for (not fixed).
  std::vector<Eigen::Vector3d> sphere_centres_in_base;  ///< Per sphere index (mm).
  std::vector<Eigen::Vector3d> sphere_centre_sigmas;    ///< 1-sigma per coordinate.
  double radius_mm = 0;
  double radius_sigma_mm = 0;  ///< 0 when held.
  double rms_mm = 0;           ///< RMS point-to-sphere distance over the points used.
  double variance_factor = 0;  ///< s^2 = sum r^2 / (m - n), r in units of point_sigma.
  /// Per-sweep mean residuals against the within-sweep scatter (calib/sweep_bias.hpp); above
  /// kSweepBiasWarningRatio a warning says the model misses something.
  double sweep_bias_ratio = 0;
  std::size_t points_used = 0;
  std::size_t points_rejected = 0;  ///< Seed inliers beyond the final gate.
  std::vector<SweepResidual> sweeps;
  std::vector<double> residuals_mm;   ///< Signed point-to-sphere distances of the points used.
  ObservabilityReport observability;  ///< At the solution (after fixing).
  /// Covariance of every estimated parameter, names in covariance_names (robot parameters,
  /// hand_eye_rx.. tz, centre_<s>_x.., radius).
  Eigen::MatrixXd covariance;
  std::vector<std::string> covariance_names;
  /// Predicted 1-sigma of where the laser's working point lands in the base, over the sweeps'
  /// poses, from the covariance of the robot parameters and hand-eye that were estimated
  /// (PositioningAtSweeps).
  PositioningUncertainty positioning;
  std::vector<std::string> warnings;  ///< Observability changed, sweep residuals, no convergence.
  /// One line: converged, RMS, offsets, fixed parameters.
  std::string Summary() const;
};

/// Identifies the robot model (and optionally the hand-eye transform) from sphere sweeps. The
/// input chain is the starting model (e.g. NominalUr5() or the model in cell.yaml; 6 joints);
/// flange_from_sensor is the hand-eye transform (held unless estimate_hand_eye).
/// Throws InputError for: a chain without 6 joints, no sweeps, a profile without (or with the
/// wrong number of) joint values, non-finite points, known centres missing a sphere, fewer
/// constraints than parameters, flange rotations all equal (pure translations) or all about one
/// axis while the hand-eye transform is estimated, a sweep where no sphere is found, or a
/// degenerate direction the observability analysis cannot resolve by fixing a robot parameter.
JointIdentificationResult IdentifyRobot(const DhChain& robot,
                                        const Eigen::Isometry3d& flange_from_sensor,
                                        const std::vector<SphereSweep>& sweeps,
                                        const JointIdentificationOptions& options);

}  // namespace lasercell::calib
