#pragma once
// Sweep assembly: laser profiles (triangulation/profile_io.hpp) -> points in the sensor frame
// per profile (Triangulator) -> one PointCloud in a sweep frame.
//
// Motion models:
//  - kNone: every profile stays in `sensor` (a static sensor; for tests and single profiles).
//  - kLinear: a constant-velocity sweep. The sweep frame is `sensor`, meaning the sensor frame at
//    the sweep's time t0 (the frame cell.yaml edges to `sensor` name for a linear sweep, e.g. the
//    handling_base <- sensor edge of `calibrate spheres`); the sensor moves with `velocity_mm_s`
//    (expressed in that frame), so profile i, exposed at t_i = (timestamp_ns_i - t0_ns) * 1e-9 s,
//    is placed by sensor(t0) <- sensor(t_i) = Translation(velocity * t_i) (offset per profile =
//    timestamp x velocity). With a `target_frame` the sweep is then placed in that frame of a
//    FrameGraph through static edges only: target_from_sensor_i = graph.Transform(target_frame,
//    "sensor") * Translation(velocity * t_i). Such an edge to `sensor` holds for the one trajectory
//    it was measured on (the sensor at t0 of that sweep), not for the sensor in general.
//  - kRobot: the sensor rides a robot whose joints each profile records; the sweep frame is
//    `target_frame` of a FrameGraph and sweep_from_sensor_i = graph.Transform(target_frame,
//    "sensor", {robot: joints_i}) (kinematics + hand-eye from cell.yaml).
// The cloud keeps per point: profile index (file order), profile column j (the grid column; the
// image column is header.first_column + j, the same when the profile covers the full width),
// timestamp (s, relative to t0 for linear sweeps, sensor clock seconds otherwise) and intensity;
// it is organized (grid_rows = profiles, grid_cols = profile columns) with rejected cells absent.
// Units mm, s, rad.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

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
  /// Frame of the FrameGraph the sweep is expressed in. kRobot: required (e.g. "vision_base").
  /// kLinear: "" (default) keeps the sweep frame `sensor` (the sensor at t0); a name places the
  /// sweep there through static edges only. kNone: ignored.
  std::string target_frame;
  /// kRobot: robot whose joints the profiles record; "" = the profile file's header.robot.
  std::string robot;
  /// Fast (lookup tables) or exact (mrcal per pixel) triangulation.
  TriangulationPath path = TriangulationPath::kFast;
  /// Worker threads (core/parallel.hpp; <= 0: all cores). The result does not depend on it.
  int threads = 1;

  /// Throws OptionError naming `what` and the field.
  void Check(const std::string& what = "SweepOptions") const;
};

/// A sweep cloud and what happened on the way.
struct SweepResult {
  PointCloud cloud;                         ///< Points in the sweep frame (see the file comment).
  SweepMotion motion = SweepMotion::kNone;  ///< The motion model the sweep was assembled with.
  std::string frame;              ///< Name of the sweep frame ("sensor" or the target frame).
  std::size_t profiles = 0;       ///< Profiles read.
  TriangulationCounts counts;     ///< Over all profiles.
  std::size_t sequence_gaps = 0;  ///< Lost profiles detected from sequence-number jumps.
  /// Per profile (file order, = cloud.profile): the sensor pose when it was exposed, in the sweep
  /// frame (frame <- sensor). Its translation is the camera centre, from which the line of sight
  /// of every point of that profile starts (normal orientation, visibility).
  std::vector<Eigen::Isometry3d> frame_from_sensor;

  /// One line: profiles, points, rejections, frame.
  std::string Summary() const;
};

/// Assembles a sweep. The graph is needed for kRobot and for kLinear with a target frame
/// (nullptr otherwise). Throws InputError when the profiles do not fit the camera (image size),
/// when kRobot profiles carry no joints, when the graph has no path from "sensor" to the target
/// frame, or when a linear sweep's path to it passes a robot; OptionError for bad options.
SweepResult AssembleSweep(const ProfileSet& profiles, const Triangulator& triangulator,
                          const SweepOptions& options, const FrameGraph* graph = nullptr);

/// Where the laser plane of a scan comes from; the first one given wins.
struct LaserPlaneSource {
  /// A plane given as (n, d), n . p + d = 0 in the sensor frame, mm (e.g. from the command line
  /// or the simulator's truth/sensor.yaml); unset: the cell's plane.
  std::optional<Eigen::Vector4d> plane;
  /// Names the given plane in the summary ("--laser-plane", a file path).
  std::string plane_label;
  /// Otherwise the plane of this name in the cell's laser_planes section (frame "sensor").
  std::string laser = "laser";
};

/// What a scan needs besides its profiles and camera.
struct ScanSetup {
  Eigen::Vector4d laser_plane = Eigen::Vector4d::Zero();  ///< (n, d), sensor frame, mm.
  std::string laser_plane_source;  ///< plane_label, or the cell's name when it came from there.
  SweepOptions options;            ///< The sweep options, checked against the cell.
};

/// Chooses the laser plane (the given one, else cell->laser_planes()[source.laser]) and checks
/// the sweep options against the cell: a target frame needs the cell and a path from "sensor",
/// through static edges only for a linear sweep. `cell` may be null (no cell file); `cell_name`
/// names it in messages. Throws FileError naming the cell when its plane is missing or not in
/// frame "sensor", InputError when no plane is given at all or the frames do not connect.
ScanSetup ScanSetupFromCell(const FrameGraph* cell, const std::string& cell_name,
                            const LaserPlaneSource& source, const SweepOptions& options);

}  // namespace lasercell::triangulation
