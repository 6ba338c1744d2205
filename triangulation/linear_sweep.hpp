#pragma once
// The motion of a linear sweep as a cell with a linear axis records it: records/linear_sweep.yaml
// (format lasercell.linear_sweep, version 1). The sweep frame is `sensor`, the sensor frame at
// the sweep's t0; the sensor moves with a constant velocity expressed in that frame, so a point
// of the profile stamped t_ns lies at
//   p_in_sensor(t0) = p_in_sensor(t) + velocity_mm_s_in_sensor * (t_ns - t0_ns) * 1e-9.
// No truth: what the axis knows (start time, direction as the sensor is mounted on it, commanded
// speed). Units mm, s, ns.

#include <Eigen/Core>
#include <cstdint>
#include <string>

#include "triangulation/sweep.hpp"

namespace lasercell::triangulation {

/// records/linear_sweep.yaml.
struct LinearSweepRecord {
  std::int64_t t0_ns = 0;  ///< Time origin of the sweep, sensor clock ns.
  /// Sensor velocity in the sensor frame at t0, mm/s.
  Eigen::Vector3d velocity_mm_s_in_sensor = Eigen::Vector3d::Zero();
  double speed_mm_s = 0;  ///< |velocity|, mm/s (informative; the velocity rules).

  /// SweepOptions of this motion: kLinear with velocity_mm_s and t0_ns set (other fields default).
  SweepOptions Options() const;
};

/// The file text; numbers print to round-trip exactly.
std::string LinearSweepRecordYaml(const LinearSweepRecord& record);
/// Parses the file text strictly (yaml::Fields); `name` names it in messages. OptionError on an
/// unknown or missing field, a wrong format/version or a non-finite velocity.
LinearSweepRecord ParseLinearSweepRecord(const std::string& text, const std::string& name);
/// Reads records/linear_sweep.yaml (FileError when it cannot be read).
LinearSweepRecord ReadLinearSweepRecord(const std::string& path);

}  // namespace lasercell::triangulation
