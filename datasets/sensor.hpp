#pragma once
// The simulated laser-triangulation sensor: a 1024 x 1024 camera with a mrcal
// LENSMODEL_OPENCV8 lens and a 660 nm line laser (45 deg fan), as in the seed's sensor class
// (Photonfocus MV1-D1024E-3D-like: 10.6 um pixels, on-chip peak per column).
//
// Frames: the `sensor` frame IS the camera frame (mrcal/OpenCV convention: +x along image
// columns, +y along rows, +z the optical axis; origin at the projection centre), so
// sensor_from_camera is the identity and the laser plane is given in that frame. Pixel
// coordinates put the centre of the top-left pixel at (0, 0). Units mm, rad, px.
//
// Laser geometry: the emitter sits at baseline_mm along -y of the camera; its fan plane contains
// the camera's x direction and the point at standoff_mm on the optical axis, so the line runs
// across the image columns and a height change moves the peak along a column.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "calib/camera_model.hpp"

namespace lasercell::datasets {

/// Camera intrinsics in mrcal's LENSMODEL_OPENCV8 parametrisation.
struct CameraIntrinsics {
  int width_px = 1024;    ///< Image columns.
  int height_px = 1024;   ///< Image rows.
  double fx_px = 1132.0;  ///< Focal length in columns, px (12 mm lens / 10.6 um pixels).
  double fy_px = 1132.0;  ///< Focal length in rows, px.
  double cx_px = 515.3;   ///< Principal point column, px.
  double cy_px = 508.6;   ///< Principal point row, px.
  /// OpenCV rational distortion k1 k2 p1 p2 k3 k4 k5 k6 (mrcal OPENCV8 order).
  std::array<double, 8> distortion = {-0.112, 0.071, 2.1e-4, -1.3e-4, -0.018, 0.011, -0.006, 0.002};

  /// mrcal intrinsics vector: fx fy cx cy k1 k2 p1 p2 k3 k4 k5 k6.
  std::array<double, 12> MrcalVector() const;
  /// Throws OptionError naming `what` and the field.
  void Check(const std::string& what = "camera") const;
};

/// The camera of these intrinsics: calib::CameraModel with mrcal LENSMODEL_OPENCV8 (the one
/// camera wrapper of lasercell; the simulator renders through it). InputError when a value is
/// not finite or the imager size is not positive (CameraIntrinsics::Check is stricter).
calib::CameraModel MakeCameraModel(const CameraIntrinsics& intrinsics = {});

/// The simulator's projection: the pixel of a point in the camera frame, or nullopt when it is
/// not in front of the camera (z <= 1e-9 mm), more than atan(3) (~72 deg) off the optical axis
/// (where the rational OPENCV8 model folds back) or does not project to a finite pixel.
std::optional<Eigen::Vector2d> ProjectInView(const calib::CameraModel& camera,
                                             const Eigen::Vector3d& p_in_camera);

/// The laser's fan plane in the sensor frame.
struct LaserPlane {
  Eigen::Vector3d origin_in_sensor = Eigen::Vector3d::Zero();   ///< Emitter (fan apex), mm.
  Eigen::Vector3d normal_in_sensor = Eigen::Vector3d::UnitY();  ///< Unit plane normal.
  Eigen::Vector3d center_in_sensor = Eigen::Vector3d::UnitZ();  ///< Unit central fan ray.
  double fan_angle_rad = 0.7853981633974483;                    ///< Full fan angle.

  /// Unit direction of the fan ray at angle alpha (rad) from the central ray, towards +lateral.
  Eigen::Vector3d RayDirection(double alpha_rad) const;
  /// Unit in-plane direction perpendicular to the central ray (normal x center).
  Eigen::Vector3d Lateral() const { return normal_in_sensor.cross(center_in_sensor); }
  /// Plane as (unit n, d) with n . p + d = 0 for points p on it (sensor frame).
  Eigen::Vector4d Coefficients() const;
};

/// Geometry of the sensor, as a user would specify it.
struct SensorOptions {
  CameraIntrinsics camera;      ///< Lens and imager.
  double baseline_mm = 250.0;   ///< Emitter distance from the camera centre (along -y).
  double standoff_mm = 700.0;   ///< Distance along the optical axis where the laser crosses it.
  double fan_angle_deg = 45.0;  ///< Full laser fan angle.

  /// Throws OptionError naming `what` and the field.
  void Check(const std::string& what = "sensor") const;
};

/// Camera + laser.
struct SensorModel {
  calib::CameraModel camera = MakeCameraModel();  ///< mrcal LENSMODEL_OPENCV8.
  LaserPlane laser;
  /// The measuring range along the laser's central ray that the image rows cover at the
  /// central column, mm from the emitter: [near, far] (far may be +inf).
  std::array<double, 2> central_range_mm = {0, 0};
};

/// Builds the sensor model from options (Check()s them first).
SensorModel MakeSensor(const SensorOptions& options);

/// Rotation of the sensor in a frame whose -z is "down": the laser's central ray points along
/// -z and the laser plane normal along `sweep_direction` (projected to horizontal).
Eigen::Matrix3d SensorLookingDown(const LaserPlane& laser, const Eigen::Vector3d& sweep_direction);

/// A mrcal .cameramodel text for the camera (extrinsics rt_cam_ref = the given pose, identity by
/// default), with every number printed to round-trip exactly. mrcal's own writer
/// (mrcal_write_cameramodel_file) prints 6 decimals and writes non-atomically, so the simulator
/// writes this text with WriteFileAtomically; mrcal_read_cameramodel_string reads it back.
std::string MrcalCameraModelText(
    const CameraIntrinsics& intrinsics,
    const Eigen::Isometry3d& camera_from_ref = Eigen::Isometry3d::Identity());

/// Parses a .cameramodel text with mrcal's reader; throws FileError(name, ...) unless it is an
/// OPENCV8 model.
CameraIntrinsics CameraIntrinsicsFromMrcalText(const std::string& text, const std::string& name);

}  // namespace lasercell::datasets
