#pragma once
// Configuration of the workcell simulator (SIM.yaml). Every field has a default, so an empty
// file (or none) gives the standard cell; a file only lists what it changes. Loading rejects
// unknown fields and malformed values with an OptionError naming the field path (e.g.
// "sim.yaml: unknown field 'sensor.camera.fx'"); Check() rejects values out of range, and a
// sensor geometry that would see nothing of a target, naming the field to change.
//
// File layout (format lasercell.sim_config, version 1), all sections optional:
//   format: lasercell.sim_config
//   version: 1
//   profile: ideal | realistic   (the named base the other fields change; sim_profile.hpp)
//   seed: 1
//   sensor: {camera: {width_px, height_px, fx_px, fy_px, cx_px, cy_px, distortion: [8]},
//            baseline_mm, standoff_mm, fan_angle_deg,
//            mount_translation_mm: [x, y, z], mount_rotation_deg: [rx, ry, rz]}
//   render: {fan_rays, max_range_mm, intensity_gain, reference_range_mm, min_intensity,
//            max_view_angle_deg, sheet_thickness_mm, min_width_px, row_sigma_px,
//            intensity_sigma, dropout_probability, speckle_sigma_px,
//            speckle_correlation_px, speckle_intensity_sigma, occlusion_epsilon_mm,
//            reflection_probability, reflection_intensity, reflective_objects: [names]}
//   timing: {profiles, rate_hz, jitter_s, timestamp_noise_s, joint_noise_rad, start_ns}
//   cell: {vision_base_mm: [x, y, z], vision_base_yaw_deg, handling_base_mm: [x, y, z],
//          handling_base_yaw_deg, floor_size_mm,
//          albedo: {floor, pallet, seat, white_plane, spheres, stands, chessboard_light,
//                   chessboard_dark}}
//   vision_robot: {joint_offsets_deg: [6] (explicit), joint_offset_sigma_deg,
//                  dh_a_errors_mm: [6], dh_d_errors_mm: [6] (explicit), dh_length_sigma_mm}
//   sweep: {measuring_height_mm, length_mm, center_xy_mm: [x, y], direction_deg}
//   seats: {count, max_shift_mm, max_tilt_deg, max_yaw_deg, shape: {ChairSeatOptions fields},
//           rendered: {angular_steps, radial_steps, warp_mm}}
//   planes: {heights_mm: [...], size_mm: [x, y]}
//   spheres: {radius_mm, stand_heights_mm: [...], positions_xy_mm: [[x, y], ...], segments,
//             radius_tolerance_mm, radius_errors_mm: [...] (explicit)}
//   trajectory: {arc_radius_mm, arc_angle_deg, waypoints}
//   chessboard: {images, squares: [x, y], square_mm, border_mm}
//   images: {exposure, ambient, background_albedo, blur_sigma_px, noise_sigma, vignetting,
//            edge_samples, corner_sigma_px}
//   touches: {sigma_mm, tool_length_mm}
//   eye_in_hand: {poses, min_tilt_deg, max_tilt_deg, max_roll_deg, sweep_length_mm, profiles,
//                 range_offsets_mm}
//   joint_poses: {... the same fields}
//   hand_eye_images: {images, distance_mm, min_tilt_deg, max_tilt_deg, max_roll_deg,
//                     board_height_mm, board_yaw_deg}
//   captures: {planes, spheres, seats, trajectory, chessboard_images, laser_line_images,
//              meshes, touches, eye_in_hand, joint_poses}   (booleans)

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "datasets/camera_images.hpp"
#include "datasets/cell.hpp"
#include "datasets/chair_seat.hpp"
#include "datasets/laser_renderer.hpp"
#include "datasets/sensor.hpp"

namespace lasercell::datasets {

/// Current simulator configuration format version.
inline constexpr int kSimConfigVersion = 1;

/// Pointing-tool touches of the sphere tops by the handling robot (calibration step 3).
struct TouchOptions {
  double sigma_mm = 0.05;         ///< Gaussian error of a touched point, per axis, mm (>= 0).
  double tool_length_mm = 200.0;  ///< Pointing tool: tip on the handling flange's z axis, mm.

  /// Throws OptionError naming `what` and the field.
  void Check(const std::string& what = "touches") const;
};

/// A set of short sphere sweeps by the vision robot from distinct poses (eye-in-hand, joint
/// offsets). Pose i aims at sphere i % count: the sensor's optical axis is tilted from the
/// vertical by U(min_tilt, max_tilt) towards an azimuth (stratified over 360 deg) and rolled
/// about the vertical by U(-max_roll, max_roll); it then moves sweep_length_mm along the laser
/// plane normal (joint-space motion between IK waypoints of the NOMINAL robot) over `profiles`
/// exposures at timing.rate_hz.
struct PoseSweepOptions {
  int poses = 24;                 ///< Number of robot poses (sweeps).
  double min_tilt_deg = 5.0;      ///< Smallest tilt of the optical axis from the vertical, deg.
  double max_tilt_deg = 25.0;     ///< Largest tilt, deg.
  double max_roll_deg = 60.0;     ///< Roll about the vertical, +- deg.
  double sweep_length_mm = 80.0;  ///< Travel of each sweep, mm.
  int profiles = 40;              ///< Exposures per sweep.
  /// Pose i sees its sphere farther along the laser's central ray by
  /// range_offsets_mm[i % size] (the sensor backs off along that ray, so the laser plane still
  /// cuts the sphere): sweeps at several ranges make the camera centre observable in the laser
  /// eye-in-hand problem (at one range a rotation about the sphere is seen only through it).
  std::vector<double> range_offsets_mm = {-100.0, 0.0, 100.0};

  /// Throws OptionError naming `what` and the field.
  void Check(const std::string& what) const;
};

/// Eye-in-hand camera calibration images: the sensor camera on the vision robot photographs a
/// chessboard lying flat in the cell (pattern up, centred on the sweep centre) from `images`
/// robot poses: optical axis through the board centre, tilted from the vertical by a uniform
/// angle in [min_tilt_deg, max_tilt_deg] about a horizontal axis whose azimuth is stratified
/// over the circle, rolled about it by +- max_roll_deg.
struct HandEyeImageOptions {
  int images = 15;                 ///< Number of robot poses / images.
  double distance_mm = 700.0;      ///< Camera centre to board centre along the optical axis, mm.
  double min_tilt_deg = 10.0;      ///< Smallest tilt of the optical axis from the vertical, deg.
  double max_tilt_deg = 35.0;      ///< Largest tilt, deg.
  double max_roll_deg = 60.0;      ///< Roll about the optical axis, +- deg.
  double board_height_mm = 150.0;  ///< Height of the printed face above the floor, mm.
  double board_yaw_deg = 15.0;     ///< Rotation of the board about the vertical, deg.

  /// Throws OptionError naming `what` and the field.
  void Check(const std::string& what) const;
};

/// Everything the simulator needs; defaults give the standard cell.
struct SimConfig {
  /// The named profile this config was built on ("ideal" or "realistic", sim_profile.hpp). It
  /// records the base only; the fields below are what the simulator uses.
  std::string profile = "ideal";
  std::uint64_t seed = 1;  ///< Master seed: same seed (and config) -> identical files.

  SensorOptions sensor;  ///< Camera, laser geometry.
  /// Camera centre in the vision-robot flange frame, mm (the nominal mount puts the sensor
  /// looking down along the flange's +z with the laser plane normal along flange +x).
  Eigen::Vector3d mount_translation_mm = Eigen::Vector3d(12.0, -95.0, 160.0);
  /// Extra rotation of the mount (rotation vector, deg) on top of the nominal orientation.
  Eigen::Vector3d mount_rotation_deg = Eigen::Vector3d(0.8, -1.1, 2.3);

  LaserRenderOptions render;  ///< Photometry, sampling and noise.
  SweepTiming timing;         ///< Profiles per sweep, rate, jitter.

  // Cell layout.
  Eigen::Vector3d vision_base_mm = Eigen::Vector3d(0.0, -480.0, 750.0);  ///< UR5 base (cell).
  double vision_base_yaw_deg = 90.0;  ///< UR5 base rotation about cell z.
  Eigen::Vector3d handling_base_mm = Eigen::Vector3d(1350.0, 0.0, 0.0);  ///< Handling base.
  double handling_base_yaw_deg = 180.0;  ///< Handling base rotation about cell z.
  double floor_size_mm = 4000.0;         ///< Floor edge.
  CellAlbedo albedo;                     ///< Surface reflectances.

  // The true vision robot.
  std::optional<std::vector<double>> joint_offsets_deg;  ///< Explicit true joint offsets.
  double joint_offset_sigma_deg = 0.1;  ///< Else drawn N(0, sigma) per joint from the seed.
  /// Explicit DH length errors of the true robot, added to a_i and d_i (6 values each, mm).
  std::optional<std::vector<double>> dh_a_errors_mm;
  std::optional<std::vector<double>> dh_d_errors_mm;
  /// Else drawn N(0, sigma) per a_i and d_i from the seed (0: the true robot has exact lengths,
  /// only joint offsets differ from the nominal UR5).
  double dh_length_sigma_mm = 0.0;

  // Linear sweeps (calibration planes, spheres, part scenes).
  double measuring_height_mm =
      244.0;                       ///< Height (cell z) where the laser crosses the optical axis.
  double sweep_length_mm = 900.0;  ///< Travel of a linear sweep.
  Eigen::Vector2d sweep_center_xy_mm = Eigen::Vector2d::Zero();  ///< Sweep midpoint (cell xy).
  double sweep_direction_deg = 0.0;  ///< Sweep direction in the cell xy plane.

  // Part scenes.
  int seat_count = 3;                   ///< Seat placements in a cell capture set.
  SeatPlacementOptions seat_placement;  ///< Table I ranges.
  ChairSeatOptions seat_shape;          ///< Seat geometry: the CAD model (models/seat.*).
  /// The physical seat the sensor sees: tessellation and warp against the CAD (defaults: the
  /// CAD itself).
  SeatRenderOptions seat_render;

  // Calibration targets.
  std::vector<double> plane_heights_mm = {150.0, 250.0, 350.0};   ///< White plane top heights.
  Eigen::Vector2d plane_size_mm = Eigen::Vector2d(800.0, 600.0);  ///< White plane size.
  SphereTargets spheres;                                          ///< Half spheres on stands.
  /// Manufacturing tolerance of the sphere radius, mm: unless spheres.radius_errors_mm lists
  /// them, each sphere's true radius is radius_mm + U(-tol, tol), drawn from a stream of its
  /// own (0: every sphere is exactly radius_mm). Records state radius_mm.
  double sphere_radius_tolerance_mm = 0.0;

  // Robot-trajectory sweep: the sensor follows a horizontal arc about the sweep centre.
  double arc_radius_mm = 150.0;  ///< Arc radius, mm.
  double arc_angle_deg = 180.0;  ///< Arc angle (semicircle).
  int arc_waypoints = 13;        ///< IK waypoints; joints are interpolated linearly between.

  // Camera images (intrinsics calibration, peak-detector tests). The board's albedos come from
  // cell.albedo.chessboard_light/dark.
  ChessboardTarget chessboard;  ///< Printed board: squares, square_mm, border_mm.
  int chessboard_images = 20;   ///< Chessboard views in a cell capture set.
  ImageRenderOptions images;    ///< Photometry, blur, noise of the images.
  /// Detector-level corner noise, px per coordinate, for captures that synthesize corner
  /// detections from the true projections instead of rendering images (calibration benches
  /// and tests that need many views fast). Ideal 0.03 px (SB on this renderer's images);
  /// realistic 0.15 px (real views of ../shared/data: 0.18 px RMS reprojection after
  /// intrinsics).
  double corner_sigma_px = 0.03;

  // Robot-side calibration captures (hand-eye, joint offsets, half spheres).
  TouchOptions touches;  ///< Handling-robot pointing-tool touches of the sphere tops.
  /// Multi-pose sphere sweeps for eye-in-hand calibration (rotations about several axes).
  PoseSweepOptions eye_in_hand;
  /// >= 50 robot poses, each with a short sphere sweep, for joint-offset identification.
  PoseSweepOptions joint_poses{50, 5.0, 35.0, 180.0, 60.0, 30, {-100.0, 0.0, 100.0}};
  /// Chessboard images from the sensor camera on the vision robot (eye-in-hand).
  HandEyeImageOptions hand_eye_images;

  // What a cell capture set contains.
  bool capture_planes = true;
  bool capture_spheres = true;
  bool capture_seats = true;
  bool capture_trajectory = true;
  bool capture_chessboard_images = true;  ///< images/chessboard_NNN.png + truth/chessboard.yaml.
  bool capture_laser_line_images = true;  ///< images/laser_line_*.png + truth/laser_lines.yaml.
  bool write_meshes = true;               ///< models/*.ply and models/*.stl.
  bool capture_touches = true;            ///< records/touches.yaml + truth/touches.yaml.
  bool capture_eye_in_hand = true;        ///< profiles/eye_in_hand_NN.lcp.
  bool capture_joint_poses = true;        ///< profiles/joint_pose_NNN.lcp.
  /// images/hand_eye_NNN.png + records/hand_eye_images.yaml + truth/hand_eye_images.yaml. Off
  /// by default: 15 more 1024 x 1024 renders (~3 s, minutes under ASan).
  bool capture_hand_eye_images = false;

  /// Throws OptionError naming the field ("SimConfig.<path>") when a value is out of range or a
  /// target lies outside the sensor's measuring range at the configured sweep height.
  void Check() const;
};

/// Parses SIM.yaml text; `name` (the file) appears in errors. Throws OptionError naming the
/// field for unknown fields, wrong types, wrong list lengths, unknown format/version.
SimConfig SimConfigFromYaml(const std::string& text, const std::string& name);
/// Reads SIM.yaml.
SimConfig LoadSimConfig(const std::string& path);
/// Serializes every field (deterministic; numbers round-trip exactly).
std::string SimConfigToYaml(const SimConfig& config);

}  // namespace lasercell::datasets
