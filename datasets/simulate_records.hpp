#pragma once
// The simulator's truth and record files as text (truth/sensor.yaml, truth/robots.yaml,
// truth/captures.yaml entries, records/linear_sweep.yaml), and the reader of truth/sensor.yaml
// beside its writer. Field meanings: datasets/SIMULATOR.md. Numbers print to round-trip exactly
// (core FormatDouble; infinities as .inf), poses in the file notation {translation_mm,
// rotation_wxyz}.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>
#include <string>

#include "datasets/laser_renderer.hpp"
#include "datasets/simulate.hpp"
#include "triangulation/linear_sweep.hpp"

namespace lasercell::datasets {

/// Number and pose spelling of every simulator file.
namespace sim_text {
/// Shortest round-trip text; infinities in YAML spelling (.inf, -.inf).
std::string Num(double v);
/// "[x, y, z]".
std::string Vec(const Eigen::Vector3d& v);
/// {translation_mm: [...], rotation_wxyz: [...]} (core PoseToFileNotation).
std::string Pose(const Eigen::Isometry3d& pose);
}  // namespace sim_text

/// A part scene: its frame name (seat_000, ...) and where it lies.
struct SeatCapture {
  std::string name;
  SeatPlacement placement;
};

/// truth/captures.yaml: the preamble (seed, base poses, hole centre in the part).
std::string CapturesPreambleYaml(const SimConfig& config, const CellTruth& truth);
/// truth/captures.yaml: one capture's name, kind, profile file and counts.
std::string CaptureHeaderYaml(const CaptureReport& report);
/// truth/captures.yaml: the linear sweep of a capture (start pose and velocity in cell and
/// handling_base).
std::string LinearSweepTruthYaml(const LinearSweep& sweep, const Eigen::Isometry3d& hb_from_cell,
                                 const SimConfig& config);
/// truth/captures.yaml: the true exposure times ("" when the timestamps are the true times).
std::string ExposureTimesTruthYaml(const SweepResult& result, const SimConfig& config);
/// truth/captures.yaml: a seat capture's placement, part pose and hole.
std::string SeatTruthYaml(const SeatCapture& seat, const CellTruth& truth,
                          const Eigen::Isometry3d& hb_from_cell);
/// truth/sensor.yaml (format lasercell.sim_sensor, version 1).
std::string SensorTruthYaml(const CellTruth& truth, const SimConfig& config);
/// truth/robots.yaml (format lasercell.sim_robots, version 1).
std::string RobotsTruthYaml(const CellTruth& truth);

/// What a cell with a linear axis knows of its sweeps (no truth), for records/linear_sweep.yaml
/// (triangulation::LinearSweepRecordYaml): when the motion starts and its velocity in the sensor
/// frame at t0 (the axis direction as the sensor is mounted on it, and the commanded speed).
/// `lasercell scan triangulate --velocity-mm-s` takes the latter.
triangulation::LinearSweepRecord LinearSweepRecordOf(const LinearSweep& sweep,
                                                     const SimConfig& config);

/// What truth/sensor.yaml holds for a scan: the laser plane in the sensor frame (= camera
/// frame), mm. The other sections (poses, range, lens, noise) are accepted and not read here.
struct SimSensorTruth {
  Eigen::Vector3d laser_normal_in_sensor = Eigen::Vector3d::UnitY();  ///< Unit normal n.
  double laser_d_mm = 0;                                              ///< d of n . p + d = 0, mm.
  std::optional<Eigen::Vector3d> laser_point_in_sensor_mm;  ///< A point of the plane (emitter).

  /// (n, d).
  Eigen::Vector4d LaserPlane() const;
};

/// Parses truth/sensor.yaml text strictly (core yaml::Fields). FileError naming `name` when it
/// is not a sensor truth file (format) or has no laser_plane_in_sensor; OptionError naming the
/// field for unknown or malformed fields.
SimSensorTruth ParseSensorTruth(const std::string& text, const std::string& name);
/// Reads truth/sensor.yaml.
SimSensorTruth ReadSensorTruth(const std::string& path);

}  // namespace lasercell::datasets
