#pragma once
// Sweep assembly: laser profiles (triangulation/profile_io.hpp) -> points in the sensor frame
// per profile (Triangulator) -> one PointCloud in a sweep frame.
//
// Motion models:
//  - kNone: every profile stays in `sensor` (a static sensor; for tests and single profiles).
//  - kLinear: a constant-velocity sweep. The sweep frame is the sensor frame at time t0; the
//    sensor moves with `velocity_mm_s` (expressed in that frame), so profile i, exposed at
//    t_i = (timestamp_ns_i - t0_ns) * 1e-9 s, is placed by sweep_from_sensor_i =
//    Translation(velocity * t_i) (the seed's offset per profile = timestamp x velocity).
//  - kRobot: the sensor rides a robot whose joints each profile records; the sweep frame is
//    `target_frame` of a FrameGraph and sweep_from_sensor_i = graph.Transform(target_frame,
//    "sensor", {robot: joints_i}) (kinematics + hand-eye from cell.yaml).
// The cloud keeps per point: profile index (file order), profile column j (the grid column; the
// image column is header.first_column + j, the same when the profile covers the full width),
// timestamp (s, relative to t0 for linear sweeps, sensor clock seconds otherwise) and intensity;
// it is organized (grid_rows = profiles, grid_cols = profile columns) with rejected cells absent.
// Units mm, s, rad.

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>

#include "core/frame_graph.hpp"
#include "core/point_cloud.hpp"
#include "triangulation/profile_io.hpp"
#include "triangulation/triangulator.hpp"

namespace lasercell::triangulation {

/// How profiles are placed in the sweep frame.
enum class SweepMotion { kNone, kLinear, kRobot };

/// Options of AssembleSweep.
struct SweepOptions {
  SweepMotion motion = SweepMotion::kNone;  ///< Motion model (see the file comment).
  /// kLinear: sensor velocity in the sweep frame (= sensor frame at t0), mm/s.
  Eigen::Vector3d velocity_mm_s = Eigen::Vector3d::Zero();
  /// kLinear: time origin, sensor clock ns; unset: the first profile's timestamp.
  std::optional<std::int64_t> t0_ns;
  /// kRobot: frame the sweep is expressed in (e.g. "vision_base").
  std::string target_frame = "vision_base";
  /// kRobot: robot whose joints the profiles record; "" = the profile file's header.robot.
  std::string robot;
  /// Fast (lookup tables) or exact (mrcal per pixel) triangulation.
  TriangulationPath path = TriangulationPath::kFast;
  /// Worker threads (TBB; <= 0: all cores). The result does not depend on it.
  int threads = 1;

  /// Throws OptionError naming `what` and the field.
  void Check(const std::string& what = "SweepOptions") const;
};

/// A sweep cloud and what happened on the way.
struct SweepResult {
  PointCloud cloud;               ///< Points in the sweep frame (see the file comment).
  std::string frame;              ///< Name of the sweep frame ("sensor", "sensor_t0", target).
  std::size_t profiles = 0;       ///< Profiles read.
  TriangulationCounts counts;     ///< Over all profiles.
  std::size_t sequence_gaps = 0;  ///< Lost profiles detected from sequence-number jumps.

  /// One line: profiles, points, rejections, frame.
  std::string Summary() const;
};

/// Assembles a sweep. The graph is needed only for kRobot (nullptr otherwise). Throws
/// InputError when the profiles do not fit the camera (image size), when kRobot profiles carry
/// no joints or the graph has no path from "sensor" to the target frame, OptionError for bad
/// options.
SweepResult AssembleSweep(const ProfileSet& profiles, const Triangulator& triangulator,
                          const SweepOptions& options, const FrameGraph* graph = nullptr);

}  // namespace lasercell::triangulation
