#pragma once
// What the robot-side calibrations (calibrate joints, calibrate handeye-laser, calibrate
// handeye) look up in a cell's frame graph: the robot's DH chain with its base and flange
// frames, the flange <-> sensor edge (the hand-eye starting guess), the sensor's calibrated
// laser plane, and known sphere centres from the handling robot's touches of the sphere tops.
// Also the flange -> sensor edge they write back. Units mm, rad.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

#include "calib/half_sphere_calibration.hpp"
#include "core/frame_graph.hpp"
#include "core/kinematics.hpp"

namespace lasercell::calib {

/// A robot of the cell: its DH chain and the frames of its dynamic edge (base -> flange).
struct RobotInCell {
  DhChain chain;
  std::string base;    ///< Parent frame of the robot's dynamic edge, e.g. vision_base.
  std::string flange;  ///< Child frame, e.g. vision_flange.
};

/// The robot `robot` of `graph`. `cell` names the file in messages. Throws FileError when the
/// robot is not a DH chain or has no dynamic edge (InputError from the graph when unknown).
RobotInCell FindRobot(const FrameGraph& graph, const std::string& robot, const std::string& cell);

/// flange_from_sensor from the static edge joining the two frames (either direction). Throws
/// FileError naming `cell` when there is none (the hand-eye needs an initial guess).
Eigen::Isometry3d FlangeFromSensor(const FrameGraph& graph, const std::string& flange,
                                   const std::string& sensor, const std::string& cell);

/// The cell's calibrated laser plane `name` as (n, d), n . p + d = 0 in `sensor_frame` (mm).
/// Throws OptionError when the cell has none (run `lasercell calibrate laser` or give
/// --laser-plane) or it is given in another frame.
Eigen::Vector4d CellLaserPlane(const FrameGraph& graph, const std::string& cell,
                               const std::string& sensor_frame, const std::string& name = "laser");

/// Sphere centres in a robot's base from touches of the sphere tops.
struct KnownSphereCentres {
  std::vector<Eigen::Vector3d> centres_in_base;  ///< Index = sphere label, mm.
  double sigma_mm = 0;                           ///< Per-axis 1-sigma of a touch point, mm.
  double radius_mm = 0;                          ///< Sphere radius used for the top offset, mm.
};

/// centre_in_handling_base = top - radius * up, mapped into `base` through the cell: the touch
/// records are points in handling_base and `up` (against gravity) is given in handling_base,
/// +z by default, the convention of the half-sphere calibration (HalfSphereCalibrationOptions::
/// up_in_handling_base). The radius is the touches' sphere_radius_mm, else `radius_mm` (> 0).
/// Throws FileError naming `name` when the labels are not 0 .. n-1 (each touched once), no
/// radius is known, the sigma is not positive, or handling_base is not connected to `base`.
KnownSphereCentres CentresFromTouches(
    const SphereTouches& touches, const std::string& name, const FrameGraph& graph,
    const std::string& base, double radius_mm = 0,
    const Eigen::Vector3d& up_in_handling_base = Eigen::Vector3d::UnitZ());

/// The flange -> sensor edge a calibration writes: pose, covariance and provenance with the
/// residual summary "rms R mm over P points, S sweeps" and the current UTC date.
StaticEdge FlangeSensorEdge(const std::string& flange, const std::string& sensor,
                            const Eigen::Isometry3d& flange_from_sensor,
                            const std::optional<Matrix6d>& covariance, const std::string& tool,
                            double rms_mm, std::size_t points, std::size_t sweeps);

}  // namespace lasercell::calib
