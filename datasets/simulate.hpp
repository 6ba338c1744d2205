#pragma once
// lasercell workcell simulator: physically plausible capture sets of the whole cell, with ground
// truth. Front functions for the CLI: SimulateCell (every calibration capture and a
// few part scenes) and SimulateSeats (Table-I-like part scenes only).
//
// Conventions (ARCHITECTURE.md): units mm, rad (degrees only in names ending _deg), time in s or
// int64 ns as named; transforms target_from_source; frames cell, vision_base, vision_flange,
// sensor (== camera, see sensor.hpp), handling_base, handling_flange, and one frame per part
// instance (seat_000, ...). Same config and seed -> byte-identical files for any thread count.
//
// Output folder (see datasets/SIMULATOR.md for every field):
//   profiles/<capture>.lcp        laser profiles (triangulation/profile_io.hpp, format v1)
//   truth/camera.cameramodel      the true camera (mrcal, LENSMODEL_OPENCV8)
//   truth/cell.yaml               the true frame graph (core/frame_graph.hpp): true robot models
//                                 (vision robot with its joint offsets), mounts, part frames
//   truth/sensor.yaml             laser plane, emitter, fan, measuring range, intrinsics
//   truth/robots.yaml             nominal vs true vision robot: joint offsets
//   truth/captures.yaml           per capture: sweep (linear: start pose + velocity; robot:
//                                 joint waypoints), targets (plane heights, sphere centres, part
//                                 poses, hole centres in handling_base), valid peak counts
//   truth/sim_config.yaml         the full effective configuration
//   images/chessboard_NNN.png     chessboard views through the true lens (truth/chessboard.yaml:
//                                 camera_from_board and true inner-corner pixels per image)
//   images/laser_line_*.png       raw laser-line images (truth/laser_lines.yaml: exact rows)
//   models/seat.ply, models/pallet.ply, models/sphere_targets.ply   meshes (PLY, mm), and the
//                                 same as .stl (binary STL, core/io/mesh_io.hpp)
//   profiles/eye_in_hand_NN.lcp, profiles/joint_pose_NNN.lcp   short sphere sweeps of the vision
//                                 robot from many poses, commanded joints in every profile
//                                 (datasets/calibration_captures.hpp)
//   records/touches.yaml          handling-robot pointing-tool touches of the sphere tops as the
//                                 cell records them (noisy points + joints; no truth)
//   records/sphere_sweeps.yaml    the eye_in_hand and joint_poses sweep sets (no truth)
//   truth/touches.yaml            true sphere centres/tops of the touches
//   images/hand_eye_NNN.png       (captures.hand_eye_images, off by default) chessboard images
//                                 by the sensor camera on the vision robot; records/
//                                 hand_eye_images.yaml: commanded joints per image (no truth);
//                                 truth/hand_eye_images.yaml: board in cell/vision_base,
//                                 camera poses, camera_from_board, true corner pixels

#include <Eigen/Geometry>
#include <cstddef>
#include <string>
#include <vector>

#include "core/frame_graph.hpp"
#include "core/kinematics.hpp"
#include "core/progress.hpp"
#include "datasets/cell.hpp"
#include "datasets/chair_seat.hpp"
#include "datasets/sensor.hpp"
#include "datasets/sim_config.hpp"

namespace lasercell::datasets {

/// Everything true about the simulated cell, derived from a SimConfig.
struct CellTruth {
  CellLayout layout;
  SensorModel sensor;
  Eigen::Isometry3d vision_flange_from_sensor = Eigen::Isometry3d::Identity();
  DhChain nominal_vision_robot;           ///< core NominalUr5().
  DhChain true_vision_robot;              ///< Nominal + joint offsets + DH length errors.
  std::vector<double> joint_offsets_rad;  ///< True joint offsets (rad).
  std::vector<double> dh_a_errors_mm;     ///< True errors added to the nominal a_i (mm).
  std::vector<double> dh_d_errors_mm;     ///< True errors added to the nominal d_i (mm).
  DhChain handling_robot;                 ///< ApproximateNachiSc15f().
  ChairSeat seat;      ///< The part as the sensor sees it (seats.rendered: tessellation, warp).
  ChairSeat seat_cad;  ///< The part's CAD model (seats.shape), written to models/seat.*.
  /// The calibration spheres as made: radius_errors_mm explicit or drawn within
  /// sphere_radius_tolerance_mm (records state the nominal radius_mm).
  SphereTargets spheres;

  /// The true frame graph: cell -> vision_base -> (vision_robot) -> vision_flange -> sensor ->
  /// camera, cell -> handling_base -> (handling_robot) -> handling_flange.
  FrameGraph Graph() const;
};

/// Builds the true cell (Check()s the config; draws the joint offsets from the seed unless given).
CellTruth MakeCellTruth(const SimConfig& config);

/// A linear constant-velocity sweep: sensor pose at t = 0 (cell frame) and velocity.
struct LinearSweep {
  Eigen::Isometry3d cell_from_sensor_start = Eigen::Isometry3d::Identity();
  Eigen::Vector3d velocity_mm_s = Eigen::Vector3d::Zero();  ///< Cell frame.
  /// Pose at time t (s).
  Eigen::Isometry3d At(double t_s) const {
    return Eigen::Translation3d(velocity_mm_s * t_s) * cell_from_sensor_start;
  }
};

/// The config's linear sweep: laser straight down, crossing the optical axis at
/// measuring_height_mm, centred on sweep.center_xy_mm, sweep.length_mm long over the sweep's
/// duration (profiles - 1) / rate_hz.
LinearSweep MakeLinearSweep(const SimConfig& config, const SensorModel& sensor);

/// Joint-space trajectory: waypoints at times, linear interpolation (clamped at the ends).
struct JointTrajectory {
  std::vector<double> times_s;                  ///< Increasing.
  std::vector<std::vector<double>> joints_rad;  ///< One joint vector per time.
  /// Joint values at time t (s).
  std::vector<double> At(double t_s) const;
};

/// The config's robot sweep: the sensor on a horizontal arc (trajectory.*) about the sweep
/// centre, looking down, laser line radial; waypoints solved with the NOMINAL robot (as a
/// controller would), so the true robot misses them by its joint offsets. Throws OptionError
/// naming trajectory/cell fields when the vision robot cannot reach a waypoint.
JointTrajectory MakeArcTrajectory(const SimConfig& config, const CellTruth& truth);

/// What was written for one capture.
struct CaptureReport {
  std::string name;           ///< e.g. "seat_002".
  std::string kind;           ///< white_plane, spheres, seat, seat_trajectory,
                              ///< eye_in_hand_sphere, joint_poses_sphere.
  std::string profiles_file;  ///< Relative to the output folder.
  std::size_t profiles = 0;
  std::size_t valid_peaks = 0;
};

/// What a simulation wrote.
struct SimulationReport {
  std::vector<CaptureReport> captures;
  std::vector<std::string> files;  ///< Every file written, relative to the output folder.
  double seconds = 0;              ///< Wall time.
  /// One line, e.g. "7 captures, 2.3M peaks, 15 files in 6.1 s".
  std::string Summary() const;
};

/// Writes a complete capture set to `out_dir` (created if missing): white plane at every
/// planes.heights_mm, the sphere targets, seats.count part scenes, one robot-trajectory sweep,
/// the sphere touches, the eye-in-hand and joint-offset pose sweeps (all as enabled in
/// config.captures*), truth and meshes. Throws OptionError for a bad config
/// (naming the field), including a capture in which the sensor sees nothing; FileError when a
/// file cannot be written. `threads` <= 0 uses all cores; output is identical for any value.
SimulationReport SimulateCell(const SimConfig& config, const std::string& out_dir,
                              const ProgressCallback& progress = {}, int threads = 0);

/// Writes only part scenes: `placements` seats drawn like Table I (seat_000 ...), with truth.
/// Placement i is the same as SimulateCell's seat i for the same seed.
SimulationReport SimulateSeats(const SimConfig& config, int placements, const std::string& out_dir,
                               const ProgressCallback& progress = {}, int threads = 0);

}  // namespace lasercell::datasets
