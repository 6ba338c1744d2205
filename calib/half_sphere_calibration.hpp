#pragma once
// Half-sphere calibration of the sweep frame into the handling robot's base (Skotheim et al. 2012,
// calibration step 3).
//
// Frames: `sweep` = the frame the sweep cloud is in; for a linear sweep (triangulation's
// linear assembly) this is the `sensor` frame at the sweep start, so the result is
// handling_base_from_sensor valid for that sweep trajectory only. `handling_base`: the handling
// robot's base, where its controller reports the pointing-tool tip. Units mm, rad.
//
// Inputs: sphere centres in the sweep frame with their covariances (FitSphere, scaled by the
// residual variance) and, per sphere, the handling robot's touch of its top. The top is
//   top = centre + (radius + tool_tip_radius) * up,
// where `up` (up_in_handling_base) is the direction against gravity in handling_base. It is
// known, not estimated: by default +z of handling_base, i.e. the robot stands level (as in the
// simulated cell and the reference cell); a robot mounted otherwise must state it. A tilt of
// `up` by a angle shifts every touched centre by r * a sideways (0.44 mm per degree for r = 25):
// a common shift, absorbed by the translation.
// So centre_in_handling_base = touch - (r + tip) * up, with covariance sigma_touch^2 I, and a
// weighted rigid fit (rigid_fit.hpp) of the swept centres to them gives handling_base_from_sweep
// with its 6x6 covariance. With fitted (free) radii the tops themselves are fitted instead:
// top_in_sweep = c + (r + tip) R^T up with the joint centre-radius covariance, against the touch
// points (the radius and the centre height are strongly correlated on a cap seen from above).
//
// Correspondence: the touches are labelled, the swept spheres are not. Every injective
// assignment of the smaller set into the larger is scored by the RMS of a closed-form rigid fit;
// the best wins if it is consistent (rms <= max_match_rms_mm) and no other assignment is
// (otherwise: InputError, "ambiguous"). Fewer than 3 matched spheres or collinear spheres:
// InputError naming the degeneracy. Outcomes on valid data (unmatched spheres, a weighted fit
// that did not converge, chi2 beyond the stated sigmas) are warnings in the result.
//
// CalibrateHalfSpheresInSweep composes the whole step from a sweep cloud and a touches file's
// contents: SegmentSpheres, then CalibrateHalfSpheres; half_sphere_report.hpp writes its JSON
// and HTML report.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "calib/rigid_fit.hpp"
#include "calib/sphere_segmentation.hpp"
#include "core/frame_graph.hpp"
#include "core/point_cloud.hpp"

namespace lasercell::calib {

/// One pointing-tool touch of a sphere top, as the handling robot's controller reports it.
struct SphereTouch {
  int sphere = 0;  ///< Label of the sphere (from the touches file).
  Eigen::Vector3d point_in_handling_base = Eigen::Vector3d::Zero();  ///< Tool tip, mm.
  std::optional<std::vector<double>> joints_rad;  ///< Reported joints, if recorded (rad).
};

/// Contents of a touches file (format lasercell.touches, version 1; see ParseTouchesYaml).
struct SphereTouches {
  std::string robot = "handling_robot";    ///< Robot that touched.
  std::string frame = "handling_base";     ///< Frame of the points.
  double stated_sigma_mm = 0.05;           ///< Per-axis 1-sigma of a touch point, mm.
  std::optional<double> sphere_radius_mm;  ///< Nominal sphere radius, if stated.
  /// The spheres' radius tolerance, +- mm about sphere_radius_mm (a ball's grade), if stated.
  std::optional<double> sphere_radius_tolerance_mm;
  std::optional<Eigen::Isometry3d> handling_flange_from_tool_tip;  ///< Pointing tool, if stated.
  std::vector<SphereTouch> touches;
};

/// Parses a touches file's text; `name` appears in errors. Throws FileError naming the file, the
/// line and the field path (yaml::Fields, e.g. `touches[2].joints_rad`):
/// unknown fields, wrong format/version, a frame other than handling_base, values
/// that are not numbers, fields in other units (`*_m`, `*_deg`, ...), points that look like
/// metres among millimetres (mixed units), joints that look like degrees, duplicate labels.
SphereTouches ParseTouchesYaml(const std::string& text, const std::string& name);

/// A sphere found in the sweep.
struct SweptSphere {
  Eigen::Vector3d center_in_sweep = Eigen::Vector3d::Zero();  ///< mm.
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();   ///< Of the centre, mm^2.
  double radius_mm = 0;                                       ///< Fitted or given radius.
  double radius_sigma_mm = 0;                                 ///< 0 when the radius was given.
  /// Cross-covariance of centre and radius (mm^2; zero when the radius was given).
  Eigen::Vector3d center_radius_covariance = Eigen::Vector3d::Zero();
};

/// Options of CalibrateHalfSpheres.
struct HalfSphereCalibrationOptions {
  /// Direction against gravity in handling_base (normalized on use; non-zero).
  Eigen::Vector3d up_in_handling_base = Eigen::Vector3d::UnitZ();
  double touch_sigma_mm = 0.05;     ///< Per-axis 1-sigma of a touch point (> 0), mm.
  double tool_tip_radius_mm = 0.0;  ///< Radius of a ball tip (>= 0; 0 = a point tip), mm.
  /// Largest RMS (mm) of the closed-form fit for an assignment of touches to swept spheres to
  /// count as consistent (> 0).
  double max_match_rms_mm = 2.0;
  RigidFitOptions rigid;  ///< Weighted fit (collinearity threshold, covariance scaling).

  /// Throws OptionError naming the field.
  void Check() const;
};

/// One matched sphere.
struct HalfSphereResidual {
  int sphere = 0;         ///< Touch label.
  std::size_t swept = 0;  ///< Index into the swept spheres.
  Eigen::Vector3d center_in_sweep = Eigen::Vector3d::Zero();
  Eigen::Vector3d center_in_handling_base = Eigen::Vector3d::Zero();  ///< From the touch.
  Eigen::Vector3d residual_mm = Eigen::Vector3d::Zero();  ///< touched - T * swept (handling_base).
  double residual_norm_mm = 0;
  double mahalanobis = 0;  ///< sqrt(e^T S^-1 e).
  double radius_mm = 0;    ///< Radius used for the top offset.
};

/// Outcome of CalibrateHalfSpheres.
struct HalfSphereCalibrationResult {
  Eigen::Isometry3d handling_base_from_sweep = Eigen::Isometry3d::Identity();
  /// 6x6 over [rotvec (rad); translation (mm)], left perturbation (core/frame_graph.hpp).
  Matrix6d covariance = Matrix6d::Zero();
  RigidFitResult fit;                        ///< The weighted rigid fit.
  std::vector<HalfSphereResidual> spheres;   ///< Matched spheres, in touch order.
  double match_rms_mm = 0;                   ///< Closed-form RMS of the chosen assignment.
  double runner_up_match_rms_mm = 0;         ///< Of the second best (0 when there is none).
  std::vector<std::size_t> unmatched_swept;  ///< Swept spheres without a touch.
  std::vector<int> unmatched_touches;        ///< Touch labels without a swept sphere.
  std::vector<std::string> warnings;         ///< Unmatched spheres, no convergence.

  /// One line: rms over N spheres, 1-sigma.
  std::string Summary() const;
};

/// Calibrates handling_base_from_sweep. Throws InputError for fewer than 3 matchable spheres,
/// collinear spheres, inconsistent or ambiguous correspondences, bad options.
HalfSphereCalibrationResult CalibrateHalfSpheres(const std::vector<SweptSphere>& swept,
                                                 const std::vector<SphereTouch>& touches,
                                                 const HalfSphereCalibrationOptions& options);

/// Swept spheres from a segmentation (centre covariance and radius from each fit).
std::vector<SweptSphere> SweptSpheresFrom(const SphereSegmentationResult& segmentation);

/// The static edge handling_base <- sweep_frame with the result's pose and covariance.
StaticEdge HalfSphereEdge(const HalfSphereCalibrationResult& result, const std::string& sweep_frame,
                          const EdgeProvenance& provenance);

/// Options of CalibrateHalfSpheresInSweep: what the touches file may leave open. Units mm.
struct HalfSphereSweepOptions {
  double radius_mm = 0;       ///< Nominal sphere radius (> 0); 0: the touches' sphere_radius_mm.
  bool free_radius = false;   ///< Fit each sphere's radius instead of fixing it to radius_mm.
  double touch_sigma_mm = 0;  ///< Per-axis 1-sigma of a touch (> 0); 0: stated_sigma_mm.
  /// +- tolerance of each sphere's true radius about the nominal one, mm; < 0: the touches
  /// file's sphere_radius_tolerance_mm (none stated: 0). With the radius fixed, a sphere whose
  /// radius is off by dr moves its fitted centre towards the seen cap, c += (sum u u^T)^-1
  /// sum u dr (the fit's normal equations, u the unit directions to its points), and its touched
  /// centre (touch - r up) by dr up; the two cancel only for a cap seen along `up`. Each
  /// sphere's dr is taken uniform within the tolerance (1 sigma = tol / sqrt 3) and independent
  /// of the others; the calibration's response to each (the rigid fit redone at +-1 sigma) is
  /// added to its covariance (radius_covariance). Not used with free_radius (the radius is
  /// fitted).
  double radius_tolerance_mm = -1;
  /// Direction against gravity in handling_base (HalfSphereCalibrationOptions).
  Eigen::Vector3d up_in_handling_base = Eigen::Vector3d::UnitZ();
  /// Appended to the failure when no sphere is found, e.g. the cloud reader's unit hint
  /// (io::ReadReport::unit_hint); may be empty.
  std::string sweep_unit_hint;
  /// Optional: the displacement (sweep frame, mm; 3 x K) of sweep point i under each of the
  /// sensor's K error modes at +1 sigma (triangulation/sensor_error_field.hpp). When set, the
  /// result holds the calibration's response to each mode (mode_response): the spheres' points
  /// move, their fits and the rigid fit follow, to first order.
  std::function<Eigen::Matrix<double, 3, Eigen::Dynamic>(std::size_t)> point_displacements;
};

/// Names of a run's inputs, for messages, the result JSON and the report (paths, usually).
struct HalfSphereInputNames {
  std::string cell;                    ///< The cell file the edge goes to.
  std::string sweep = "sweep";         ///< The sweep cloud.
  std::string touches = "touches";     ///< The touches file.
  std::string sweep_frame = "sensor";  ///< Frame of the sweep cloud (the edge's child).
};

/// Outcome of CalibrateHalfSpheresInSweep.
struct HalfSphereSweepResult {
  /// False when no sphere of the radius was found in the sweep (an outcome, see `failure`).
  bool calibrated = false;
  /// Why nothing was calibrated: the radius, the segmentation summary, the unit hint and the
  /// strongest rejected candidate's reason.
  std::string failure;
  SphereSegmentationResult segmentation;  ///< Spheres found in the sweep.
  /// The calibration (when calibrated); its warnings include the matched spheres' fit warnings,
  /// as "sphere N: ...".
  HalfSphereCalibrationResult calibration;
  double radius_mm = 0;            ///< Radius used (option or touches file).
  double touch_sigma_mm = 0;       ///< Touch sigma used (option or touches file).
  double radius_tolerance_mm = 0;  ///< Radius tolerance used (option or touches file; 0: none).
  /// The radius tolerance's share of calibration.covariance (HalfSphereSweepOptions::
  /// radius_tolerance_mm; zero without one or with free radii).
  Matrix6d radius_covariance = Matrix6d::Zero();
  Eigen::Vector3d up_in_handling_base = Eigen::Vector3d::UnitZ();  ///< Normalized.
  /// With options.point_displacements: column k is the left perturbation [rotvec (rad);
  /// translation (mm)] of handling_base_from_sweep at the sensor's mode k (+1 sigma); 0 columns
  /// otherwise (StaticEdge::sensor_response).
  Eigen::Matrix<double, 6, Eigen::Dynamic> mode_response;
};

/// Segments the spheres out of `sweep` (SegmentSpheres, radius fixed unless free_radius) and
/// calibrates handling_base_from_sweep against the touches (CalibrateHalfSpheres). Throws
/// InputError when neither the options nor the touches give the radius, and, prefixed with the
/// sweep and touches names, the degeneracies CalibrateHalfSpheres names; OptionError for bad
/// options. No sphere in the sweep is reported (calibrated = false), not thrown.
HalfSphereSweepResult CalibrateHalfSpheresInSweep(const PointCloud& sweep,
                                                  const SphereTouches& touches,
                                                  const HalfSphereSweepOptions& options,
                                                  const HalfSphereInputNames& names = {});

/// Throws InputError (naming `cell_name`) when handling_base and `sweep_frame` are already
/// joined by other edges than their own (the new edge would close a cycle), e.g. through a
/// hand-eye edge: a half-sphere calibration holds for one sweep and needs a frame of its own.
void CheckHalfSphereEdgeFits(const FrameGraph& graph, const std::string& sweep_frame,
                             const std::string& cell_name);

/// Provenance of the edge: tool "lasercell calibrate spheres VERSION", the UTC date,
/// `input_digest` (InputDigest over the sweep file and the touches text) and the residual line
/// "rms R mm over N spheres, chi2/dof X/D".
EdgeProvenance HalfSphereProvenance(const HalfSphereCalibrationResult& result,
                                    const std::string& input_digest);

}  // namespace lasercell::calib
