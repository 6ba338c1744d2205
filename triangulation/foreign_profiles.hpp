#pragma once
// Calibrated laser profiles written by other software, read into lasercell's units and frames.
// Unlike lasercell's own profile files (profile_io.hpp: raw peak rows per image column, to be
// triangulated here), these profiles are already metric: the sensor's own calibration turned
// each peak into a point.
//
// scan_line files (RobCalibrator, the Fanuc robot/line-profiler calibration tool, saves one per
// robot pose from the calibrated output of its Automation Technology C5 laser profiler; file
// names like p1.yml or 1_3C_line.yml). An OpenCV FileStorage YAML file:
//     %YAML:1.0
//     ---
//     scan_line: [ 1.82700005e+01, 0., -1.63049793e+01, -9.50893860e+01, 0., .Nan, ... ]
// `scan_line` is ONE profile: a flat sequence of (x, y, z) triples, one per sensor column in
// column order, in mm in the sensor frame, whose x-z plane is the laser plane, so y == 0 for
// every point. A column where the sensor saw no peak holds `.Nan` (the z, or the whole triple).
// Other keys are ignored. The file carries no pose: the robot pose of each profile comes from
// a separate pose file (calib/pose_io.hpp, format xyzwpr).

#include <Eigen/Core>
#include <cstddef>
#include <string>
#include <vector>

#include "calib/sphere_section_hand_eye.hpp"

namespace lasercell::triangulation {

/// A finite point of a scan_line profile with |y| above this (mm) is not in the laser plane.
inline constexpr double kScanLinePlaneTolerance = 1e-3;

/// One calibrated profile of a scan_line file.
struct ScanLineProfile {
  /// The finite (x, 0, z) points, mm, sensor frame, in file (column) order.
  std::vector<Eigen::Vector3d> points_in_sensor;
  std::size_t columns = 0;  ///< Triples in the file (sensor columns, with or without a peak).
  std::size_t missing = 0;  ///< Triples holding a NaN (columns without a peak).
};

/// Reads a scan_line file (see the file comment). Throws FileError(path, ...) when the file is
/// missing or unreadable, is not OpenCV FileStorage, has no `scan_line` key, `scan_line` is not
/// a flat sequence of numbers or its length is not a multiple of 3, a value is infinite, a
/// finite point has |y| > kScanLinePlaneTolerance, or no point is finite.
ScanLineProfile ReadScanLineProfile(const std::string& path);

/// One section per scan_line file, with its robot pose from `poses_path` (calib/pose_io.hpp in
/// `pose_format`: Euler files do not say their convention, so "auto" is refused for them), in
/// pose order: the input of calib::CalibrateHandEyeFromSphereSections. Throws OptionError when
/// the numbers of profiles and poses differ, and as ReadScanLineProfile and LoadRobotPoses.
std::vector<calib::SphereSectionProfile> LoadSphereSections(
    const std::vector<std::string>& profile_paths, const std::string& poses_path,
    const std::string& pose_format);

}  // namespace lasercell::triangulation
