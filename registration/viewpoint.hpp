#pragma once
// Where the sensor looks from, for orienting normals and for the verification projection grid.
// Frames: the viewpoint is expressed in the frame of the cloud it is used with (mm).
//  - kPoint: a perspective sensor at `position` (range scanners, depth cameras; UWA scans are
//    taken from the origin).
//  - kDirection: a sensor whose line of sight is the same everywhere (a laser-triangulation
//    sweep seen from far above): `direction` points from the sensor into the scene.

#include <Eigen/Core>
#include <string>

#include "core/error.hpp"

namespace lasercell::registration {

/// The sensor's line of sight, as a point or as a constant direction.
struct Viewpoint {
  enum class Kind { kPoint, kDirection };
  Kind kind = Kind::kPoint;                               ///< Perspective or constant.
  Eigen::Vector3d position = Eigen::Vector3d::Zero();     ///< Sensor position, mm (kPoint).
  Eigen::Vector3d direction = -Eigen::Vector3d::UnitZ();  ///< Viewing direction (kDirection).

  /// A perspective viewpoint at `position_mm`.
  static Viewpoint AtPoint(const Eigen::Vector3d& position_mm) {
    Viewpoint v;
    v.kind = Kind::kPoint;
    v.position = position_mm;
    return v;
  }
  /// A constant viewing direction (sensor -> scene), need not be unit.
  static Viewpoint AlongDirection(const Eigen::Vector3d& direction) {
    Viewpoint v;
    v.kind = Kind::kDirection;
    v.direction = direction;
    return v;
  }

  /// Unit vector from `p` toward the sensor (zero when p coincides with a point viewpoint).
  Eigen::Vector3d TowardSensor(const Eigen::Vector3d& p) const {
    if (kind == Kind::kDirection) return -direction.normalized();
    const Eigen::Vector3d d = position - p;
    const double n = d.norm();
    return n > 0.0 ? Eigen::Vector3d(d / n) : Eigen::Vector3d::Zero();
  }

  /// Throws OptionError naming `field` when the viewpoint is not finite or the direction is zero.
  void Check(const std::string& field) const {
    if (!position.allFinite() || !direction.allFinite()) {
      throw OptionError(field + ": viewpoint position/direction must be finite");
    }
    if (kind == Kind::kDirection && direction.norm() < 1e-12) {
      throw OptionError(field + ".direction: must be a non-zero vector (sensor -> scene)");
    }
  }
};

}  // namespace lasercell::registration
