#pragma once
// Robot-side calibration captures of the simulated cell: the handling
// robot's pointing-tool touches of the sphere tops, and short sphere sweeps of the vision robot
// from many poses (eye-in-hand; joint-offset identification).
//
// What a real cell records and what only the simulator knows are kept apart: a Touch holds the
// measured point (true top + N(0, sigma) per axis) and the joints the controller reports for it;
// the true sphere centre is truth. A PoseSweep's joints are what the controller commands and
// reports: solved by IK on the NOMINAL vision robot, then executed by the TRUE robot (joint
// offsets), which poses the sensor for rendering.
//
// Frames: cell, handling_base, vision_base (see simulate.hpp). Units mm, rad.

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "datasets/camera_images.hpp"
#include "datasets/laser_renderer.hpp"
#include "datasets/simulate.hpp"

namespace lasercell::datasets {

/// One pointing-tool touch of a sphere top by the handling robot.
struct Touch {
  int sphere = 0;                                                       ///< Sphere index.
  Eigen::Vector3d true_top_in_handling_base = Eigen::Vector3d::Zero();  ///< Truth.
  Eigen::Vector3d measured_in_handling_base = Eigen::Vector3d::Zero();  ///< Recorded point.
  /// Joints the controller reports at the measured point (tool pointing down, tilted towards the
  /// robot when needed); nullopt when the handling robot cannot reach it.
  std::optional<std::vector<double>> joints_rad;
  double tool_tilt_deg = 0;  ///< Tilt of the tool from the vertical used for the IK.
};

/// handling_flange_from_tool_tip of the pointing tool: tip on the flange z axis.
Eigen::Isometry3d PointingTool(const TouchOptions& options);

/// Touches of every sphere top (one per sphere, in order), noise from `seed`.
std::vector<Touch> SimulateTouches(const SimConfig& config, const CellTruth& truth,
                                   std::uint64_t seed);

/// One planned short sphere sweep of the vision robot.
struct PoseSweep {
  int sphere = 0;              ///< Sphere aimed at.
  double tilt_deg = 0;         ///< Tilt of the optical axis from the vertical.
  double azimuth_deg = 0;      ///< Direction of the tilt axis in the cell xy plane.
  double roll_deg = 0;         ///< Roll about the vertical.
  double range_offset_mm = 0;  ///< Sphere this much farther along the laser ray than standard.
  JointTrajectory trajectory;  ///< Commanded (nominal-IK) joints: start, middle, end.
  /// Sensor poses the NOMINAL model promises at the waypoints (what the controller believes).
  std::vector<Eigen::Isometry3d> commanded_cell_from_sensor;
  std::size_t sphere_columns_at_middle = 0;  ///< Noise-free columns on the sphere, mid exposure.
};

/// Plans `options.poses` reachable sweeps that see their sphere, from the random stream `seed`.
/// Throws OptionError naming `what` (e.g. "SimConfig.eye_in_hand") when too few are found.
std::vector<PoseSweep> PlanPoseSweeps(const SimConfig& config, const CellTruth& truth,
                                      const PoseSweepOptions& options, std::uint64_t seed,
                                      const std::string& what);

/// Timing of one pose sweep: config.timing with options.profiles exposures.
SweepTiming PoseSweepTiming(const SimConfig& config, const PoseSweepOptions& options);

/// Renders a planned sweep in the sphere scene (`renderer`), the TRUE robot posing the sensor;
/// the profiles carry the commanded joints.
SweepResult RenderPoseSweep(const LaserRenderer& renderer, const CellTruth& truth,
                            const PoseSweep& sweep, const SweepTiming& timing, std::uint64_t seed,
                            int threads);

/// records/touches.yaml: what the cell records (measured points, joints, tool); no truth.
std::string TouchesRecordYaml(const SimConfig& config, const std::vector<Touch>& touches);
/// truth/touches.yaml: true sphere centres and tops, touch errors.
std::string TouchesTruthYaml(const SimConfig& config, const CellTruth& truth,
                             const std::vector<Touch>& touches);
/// The truth of one pose sweep for truth/captures.yaml (indented as a captures entry): joint
/// waypoints, commanded and true sensor poses at them, drawn angles, the sphere.
std::string PoseSweepTruthYaml(const SimConfig& config, const CellTruth& truth,
                               const PoseSweep& sweep);

/// One eye-in-hand chessboard image: commanded joints (recorded) and its truth.
struct HandEyeImage {
  std::vector<double> joints_rad;  ///< Commanded joints: nominal IK of the planned camera pose.
  Eigen::Isometry3d commanded_cell_from_camera = Eigen::Isometry3d::Identity();  ///< Planned.
  /// True camera pose: the TRUE robot at joints_rad (cell frame; camera = sensor frame).
  Eigen::Isometry3d true_cell_from_camera = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d camera_from_board = Eigen::Isometry3d::Identity();  ///< True.
  std::vector<Eigen::Vector2d> corners_px;             ///< True projections of the inner corners.
  double tilt_deg = 0, azimuth_deg = 0, roll_deg = 0;  ///< Drawn angles.
};

/// Eye-in-hand chessboard images (planned, not rendered).
struct HandEyeImageSet {
  Eigen::Isometry3d cell_from_board = Eigen::Isometry3d::Identity();  ///< Board lying flat.
  std::vector<HandEyeImage> images;
};

/// Plans config.hand_eye_images.images poses of the vision robot whose camera sees the whole
/// board of `target` (every inner corner >= 25 px inside the image) from the TRUE robot, the
/// joints solved by IK on the NOMINAL robot. Board poses are in the target frame
/// (camera_images.hpp). Throws OptionError naming SimConfig.hand_eye_images when a pose cannot
/// be found.
HandEyeImageSet PlanHandEyeImages(const SimConfig& config, const CellTruth& truth,
                                  const ChessboardTarget& target, std::uint64_t seed);

/// records/hand_eye_images.yaml: image files and commanded joints; no truth.
std::string HandEyeImagesRecordYaml(const ChessboardTarget& target, const HandEyeImageSet& set);
/// truth/hand_eye_images.yaml: board in cell and vision_base, true and commanded camera poses,
/// camera_from_board and true corner pixels per image.
std::string HandEyeImagesTruthYaml(const CellTruth& truth, const HandEyeImageSet& set);
/// File name of hand-eye image i: images/hand_eye_NNN.png.
std::string HandEyeImageFile(std::size_t i);

/// Sensor pose of the TRUE robot at joints q (cell frame).
Eigen::Isometry3d TrueCellFromSensor(const CellTruth& truth, const std::vector<double>& q);

}  // namespace lasercell::datasets
