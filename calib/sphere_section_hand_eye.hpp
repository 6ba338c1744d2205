#pragma once
// Eye-in-hand calibration of a line-laser profiler from ONE profile per robot pose across a
// fixed sphere (the profiler gives calibrated points; no camera model, no sweep, no joints:
// base_from_flange comes from the controller as a Cartesian pose).
//
// Geometry. The laser plane is the sensor's y = 0 plane; a profile across the sphere is a circle
// arc there (calib/circle_fit.hpp) with centre (x_c, z_c) and radius r. The sphere centre lies
// on the normal through the circle centre, at h = sqrt(R^2 - r^2) from the plane, on the side
// the user states (one profile cannot tell which: `sphere_side`):
//   s_i = (x_c, side * h, z_c)                                          (sensor frame)   (1)
// The sphere does not move, so with base_from_flange_i = (R_i, t_i) and X = flange_from_sensor
//   R_i (R_X s_i + t_X) + t_i = c   for every pose i.                                     (2)
// Seed: (2) is linear in (vec R_X, t_X, c) (15 unknowns, >= 5 poses), solved in least squares
// and R_X projected onto SO(3). Refinement: minimise sum_i |R_i (R_X s_i(R) + t_X) + t_i - c|^2
// over X (left perturbation [w; u] as calib/cost_functions/kinematic_sphere_cost.hpp), c and
// optionally R, unweighted: the residual of (2) is dominated by the robot's positioning error,
// which is isotropic in the base and the same for every pose, not by the section's own noise.
// Covariance s^2 (J^T J)^-1, s^2 = SSR / (3 n - p) (a posteriori variance factor).
//
// Scores. The centre spread: the sections' centres (1) mapped into the base by (2), RMS and
// largest distance from their mean (the sphere is fixed, so a perfect calibration and robot
// would put them on one point). It is also what the fit minimises, so it is optimistic; the
// leave-one-pose-out score is not: X, c (and R) from the other poses predict the left-out
// section's centre, and its distance from their c is the prediction error.
// Units mm, rad (deg where the name says so).

#include <Eigen/Geometry>
#include <limits>
#include <string>
#include <vector>

#include "calib/circle_fit.hpp"
#include "core/frame_graph.hpp"
#include "core/se3.hpp"

namespace lasercell::calib {

/// One profile across the fixed sphere and the robot pose it was taken from.
struct SphereSectionProfile {
  std::string name;  ///< For messages and reports, e.g. the profile file.
  Eigen::Isometry3d base_from_flange = Eigen::Isometry3d::Identity();  ///< mm.
  /// Calibrated profile points, sensor frame (in the laser plane y = 0), mm.
  std::vector<Eigen::Vector3d> points_in_sensor;
};

/// Options of CalibrateHandEyeFromSphereSections. Units mm.
struct SphereSectionHandEyeOptions {
  double sphere_radius_mm = 0;   ///< Nominal sphere radius (required, > 0).
  bool estimate_radius = false;  ///< Radius free (sections at several heights fix it).
  /// Side of the laser plane the sphere centre lies on: +1 the sensor's +y, -1 its -y
  /// (required: a single profile cannot tell).
  int sphere_side = 0;
  /// Sections whose radius is below this fraction of the sphere's are not used (near the pole
  /// the arc is short and the centre poorly fixed), in (0, 1).
  double min_section_radius_ratio = 0.2;
  /// Sections whose radius exceeds this fraction of the sphere's are not used: the lift h of
  /// eq. (1) moves by r / h times any radius error, 10x at 0.995; in (min ratio, 1).
  double max_section_radius_ratio = 0.995;
  /// The circle fit per profile; its radius range is set from the sphere radius (min ratio to
  /// 1.05 R), the other fields are used as given.
  CircleFitOptions circle{.inlier_gate_mm = 0.2};
  bool leave_one_out = true;  ///< Also the leave-one-pose-out scores (one re-solve per pose).
  int max_iterations = 100;   ///< Gauss-Newton iterations of the refinement (> 0).
  /// Throws OptionError naming the field.
  void Check() const;
};

/// What one profile gave.
struct SphereSection {
  std::string name;
  bool used = false;
  std::string why_not;     ///< When !used: no circle, too small, too close to the equator.
  CircleFitResult circle;  ///< In the laser plane's (x, z), mm.
  Eigen::Vector3d centre_in_sensor = Eigen::Vector3d::Zero();  ///< Eq. (1) at the solution.
  Eigen::Vector3d centre_in_base = Eigen::Vector3d::Zero();    ///< Eq. (2) at the solution.
  double distance_mm = 0;  ///< |centre_in_base - sphere centre|.
  /// Leave-one-pose-out: distance of this section's centre, predicted by the solution of the
  /// other poses, from their sphere centre (NaN when not computed).
  double loo_distance_mm = std::numeric_limits<double>::quiet_NaN();
  double loo_translation_change_mm = std::numeric_limits<double>::quiet_NaN();  ///< |dt_X|.
  double loo_rotation_change_deg = std::numeric_limits<double>::quiet_NaN();    ///< angle(dR_X).
};

/// Outcome of CalibrateHandEyeFromSphereSections.
struct SphereSectionHandEyeResult {
  bool converged = false;  ///< The refinement converged.
  int iterations = 0;      ///< Gauss-Newton iterations.
  Eigen::Isometry3d flange_from_sensor = Eigen::Isometry3d::Identity();
  /// 6x6 over [rotation vector rad; translation mm], left perturbation.
  Matrix6d covariance = Matrix6d::Zero();
  Eigen::Vector3d sphere_centre_in_base = Eigen::Vector3d::Zero();  ///< mm.
  Eigen::Matrix3d sphere_centre_covariance = Eigen::Matrix3d::Zero();
  double radius_mm = 0;                 ///< Sphere radius used (fitted with estimate_radius).
  double radius_sigma_mm = 0;           ///< 0 when held at the nominal radius.
  std::vector<SphereSection> sections;  ///< One per input profile, input order.
  std::size_t sections_used = 0;        ///< Sections in the solution.
  double spread_rms_mm = 0;  ///< RMS distance of the used sections' centres from their mean.
  double spread_max_mm = 0;  ///< Largest such distance.
  double loo_rms_mm = std::numeric_limits<double>::quiet_NaN();  ///< RMS of loo_distance_mm.
  double loo_max_mm = std::numeric_limits<double>::quiet_NaN();  ///< Largest loo_distance_mm.
  /// Largest change of the hand-eye translation (mm) / rotation (deg) when one pose is left out.
  double loo_translation_change_max_mm = std::numeric_limits<double>::quiet_NaN();
  double loo_rotation_change_max_deg = std::numeric_limits<double>::quiet_NaN();
  double rotation_span_deg = 0;       ///< Largest angle between two used poses' flange rotations.
  std::vector<std::string> warnings;  ///< Singular covariance, no convergence.
  /// One line: sections used, spread, leave-one-out, 1-sigma.
  std::string Summary() const;
};

/// Calibrates flange_from_sensor from one profile per robot pose across a fixed sphere (see the
/// file comment). Throws OptionError for bad options and InputError naming the problem for:
/// non-finite poses or points, points off the laser plane (|y| > 0.01 mm), fewer than 5 usable
/// sections (each profile's reason is in the message), and poses whose flange rotations span
/// less than 2 deg or turn about one axis only (the hand-eye rotation and translation are then
/// not determined: add poses tilted about two axes).
SphereSectionHandEyeResult CalibrateHandEyeFromSphereSections(
    const std::vector<SphereSectionProfile>& profiles, const SphereSectionHandEyeOptions& options);

/// The flange -> sensor edge of `result` for the robot `robot` of `cell` (`cell_name` names the
/// file in errors), with covariance and provenance
/// (`calibrate handeye-laser --profiles`, the centre spread over the sections used).
StaticEdge SphereSectionEdge(const FrameGraph& cell, const std::string& cell_name,
                             const std::string& robot, const std::string& sensor_frame,
                             const SphereSectionHandEyeResult& result);

}  // namespace lasercell::calib
