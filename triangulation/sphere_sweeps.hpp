#pragma once
// The sphere-sweep list (records/sphere_sweeps.yaml, format lasercell.sphere_sweeps, version 1):
// named sets of short laser sweeps of fixed spheres, each taken from one pose of the vision
// robot, e.g.
//   format: lasercell.sphere_sweeps
//   version: 1
//   eye_in_hand:
//     - {profiles_file: profiles/eye_in_hand_00.lcp, aimed_at_sphere: 0}
//   joint_poses:
//     - {profiles_file: profiles/joint_pose_000.lcp, aimed_at_sphere: 2}
// The simulator writes it (SphereSweepListYaml), the robot-side calibrations read it
// (LoadSphereSweeps): every profile of every sweep is triangulated by the Triangulator's exact
// path with its default validity rules, the same points `lasercell scan triangulate --exact`
// gives for that profile file.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

#include "calib/camera_model.hpp"
#include "calib/joint_identification.hpp"
#include "calib/joint_report.hpp"
#include "calib/laser_hand_eye.hpp"
#include "calib/robot_in_cell.hpp"
#include "core/frame_graph.hpp"
#include "triangulation/triangulator.hpp"

namespace lasercell::triangulation {

/// One entry of a sweep set.
struct SphereSweepEntry {
  std::string profiles_file;  ///< Profile file (.lcp with joints), relative to the list's dir.
  int aimed_at_sphere = 0;    ///< Index of the sphere the sweep aims at (0-based).
};

/// One named set of sweeps (e.g. eye_in_hand, joint_poses).
struct SphereSweepSet {
  std::string name;
  std::vector<SphereSweepEntry> sweeps;
};

/// The whole list, sets in file order.
struct SphereSweepList {
  std::vector<SphereSweepSet> sets;
  /// The set called `name`, or nullptr.
  const SphereSweepSet* Find(const std::string& name) const;
};

/// The list's YAML text (what records/sphere_sweeps.yaml holds).
std::string SphereSweepListYaml(const SphereSweepList& list);

/// Parses a list strictly (core/yaml_fields): format and version required, every other
/// top-level key a non-empty sequence of {profiles_file, aimed_at_sphere >= 0}; unknown fields
/// are errors. `name` appears in messages. Throws OptionError naming the file and the field.
SphereSweepList ParseSphereSweepList(const std::string& text, const std::string& name);

/// Reads the list at `path`, takes set `set` and triangulates every sweep of it: each profile's
/// peaks -> points in the sensor frame by `Triangulator(camera, plane_in_sensor, options)`'s
/// exact path, rejected peaks dropped. A profile file is looked up relative to the list's
/// directory, then to its parent. Throws FileError for a missing set, a profile file without
/// joint values or of another image size than the camera; InputError for a plane the
/// triangulator refuses.
std::vector<calib::SphereSweep> LoadSphereSweeps(const std::string& path, const std::string& set,
                                                 const calib::CameraModel& camera,
                                                 const Eigen::Vector4d& plane_in_sensor,
                                                 const TriangulatorOptions& options = {});

/// What the robot-side calibrations from sphere sweeps read (`calibrate joints`,
/// `calibrate handeye-laser`). Units mm.
struct SphereSweepProblemSpec {
  std::string cell;                 ///< cell.yaml with the robot and the flange <-> sensor edge.
  std::string camera;               ///< The sensor camera (.cameramodel).
  std::string sweeps;               ///< The sweep list (records/sphere_sweeps.yaml).
  std::string set = "joint_poses";  ///< Sweep set in the list.
  std::string robot = "vision_robot";
  std::string sensor_frame = "sensor";
  /// Laser plane n . p + d = 0 in the sensor frame (normalized here); empty: the cell's
  /// calibrated `laser` plane.
  std::optional<Eigen::Vector4d> laser_plane;
  /// Sphere tops touched by the handling robot (records/touches.yaml); empty: centres free.
  std::string touches;
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();  ///< Against gravity in handling_base.
  double point_sigma_mm = 0.1;                    ///< A-priori point noise.
  double radius_mm = 0;                           ///< Initial sphere radius; 0: from the data.
  int max_points_per_sweep = 300;
};

/// The loaded problem: the cell, its robot, the hand-eye start, the triangulated sweeps and
/// the solver options the spec sets (noise, radius, points, centres known from the touches).
struct SphereSweepProblem {
  FrameGraph graph;
  calib::RobotInCell robot;
  Eigen::Isometry3d flange_from_sensor = Eigen::Isometry3d::Identity();
  std::vector<calib::SphereSweep> sweeps;
  calib::JointIdentificationOptions solver;
};

/// Loads cell, camera, plane, sweeps and touches. Throws FileError/OptionError/InputError
/// naming the file or field (a zero plane normal is an OptionError on `laser_plane`).
SphereSweepProblem LoadSphereSweepProblem(const SphereSweepProblemSpec& spec);

/// A joint-offset identification (calib::IdentifyRobot) on a loaded problem and the cell it
/// gives: the spec's robot with the identified kinematics and, with `with_hand_eye`, the
/// flange -> sensor edge estimated with it. What `calibrate joints` writes.
struct JointCalibration {
  calib::JointIdentificationResult result;
  calib::SphereSweepRun run;  ///< For the result document and the report.
  FrameGraph cell;            ///< The spec's cell, updated.
};
/// Loads the problem (LoadSphereSweepProblem) and identifies the robot's joint offsets (and the
/// DH lengths with `dh_deltas`); throws what those throw.
JointCalibration CalibrateJointsFromSweeps(const SphereSweepProblemSpec& spec, bool with_hand_eye,
                                           bool dh_deltas);

/// The laser eye-in-hand (calib::CalibrateLaserHandEye) on a loaded problem and the cell with
/// the new flange -> sensor edge. What `calibrate handeye-laser` writes.
struct LaserHandEyeCalibration {
  calib::LaserHandEyeResult result;
  calib::SphereSweepRun run;
  FrameGraph cell;
};
LaserHandEyeCalibration CalibrateLaserHandEyeFromSweeps(const SphereSweepProblemSpec& spec);
/// The spec defaults of the laser eye-in-hand: the `eye_in_hand` sweep set and up to 5000 points
/// per sweep (6 unknowns plus the spheres: every point helps, and it stays fast, ~1 s).
SphereSweepProblemSpec LaserHandEyeSpecDefaults();

}  // namespace lasercell::triangulation
