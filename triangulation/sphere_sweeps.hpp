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
#include <string>
#include <vector>

#include "calib/camera_model.hpp"
#include "calib/joint_identification.hpp"
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

}  // namespace lasercell::triangulation
