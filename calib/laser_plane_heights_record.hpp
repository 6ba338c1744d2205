#pragma once
// records/planes.yaml: what a height fixture provides for the white-plane laser calibration
// (calib::CalibrateLaserPlaneFromHeights, `calibrate laser --planes`): the plate heights of the
// sweeps profiles/plane_<i>.lcp and the plate normal in the sensor frame. The distance to the
// plate is not recorded: the calibration estimates it (>= 3 heights). Written by the simulator,
// by a cell's recorder, read here.
//
//   format: lasercell.plane_heights
//   version: 1
//   heights_mm: [150, 250, 350]             # along the plate normal, arbitrary zero, mm
//   plate_normal_in_sensor: [0, 0, -1]      # unit, pointing towards the sensor

#include <Eigen/Core>
#include <string>
#include <vector>

namespace lasercell::calib {

/// The content of records/planes.yaml.
struct PlaneHeightsRecord {
  /// Height of the plate for plane_<i>.lcp, along the plate normal, relative to an arbitrary
  /// zero, mm.
  std::vector<double> heights_mm;
  /// Unit normal of the plate in the sensor frame, pointing towards the sensor
  /// (HeightPlaneOptions::plate_normal_in_sensor).
  Eigen::Vector3d plate_normal_in_sensor = -Eigen::Vector3d::UnitZ();
};

/// The YAML text of `record` (numbers in their shortest round-trip form).
std::string PlaneHeightsYaml(const PlaneHeightsRecord& record);

/// Parses records/planes.yaml text; `name` names it in messages. OptionError for an unknown or
/// mistyped field, a missing heights_mm or plate_normal_in_sensor; InputError for no heights, a
/// non-finite height or a zero plate normal (stored as given, not normalized).
PlaneHeightsRecord ParsePlaneHeightsYaml(const std::string& text, const std::string& name);

/// Reads and parses a records/planes.yaml file (FileError when it cannot be read).
PlaneHeightsRecord ReadPlaneHeightsYaml(const std::string& path);

}  // namespace lasercell::calib
