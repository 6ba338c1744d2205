#include "calib/robot_in_cell.hpp"

#include <cmath>

#include "core/error.hpp"
#include "core/provenance.hpp"

namespace lasercell::calib {

RobotInCell FindRobot(const FrameGraph& graph, const std::string& robot, const std::string& cell) {
  const auto* chain = dynamic_cast<const DhChain*>(&graph.Robot(robot));
  if (!chain) throw FileError(cell, "robot '" + robot + "' is not a DH chain");
  for (const DynamicEdge& e : graph.dynamic_edges()) {
    if (e.robot == robot) return {*chain, e.parent, e.child};
  }
  throw FileError(cell, "robot '" + robot + "' has no dynamic edge (base -> flange)");
}

Eigen::Isometry3d FlangeFromSensor(const FrameGraph& graph, const std::string& flange,
                                   const std::string& sensor, const std::string& cell) {
  for (const StaticEdge& e : graph.static_edges()) {
    if (e.parent == flange && e.child == sensor) return e.ParentFromChild();
    if (e.parent == sensor && e.child == flange) return e.ParentFromChild().inverse();
  }
  throw FileError(cell, "has no static edge between '" + flange + "' and '" + sensor +
                            "' (the hand-eye transform); add an initial guess");
}

Eigen::Vector4d CellLaserPlane(const FrameGraph& graph, const std::string& cell,
                               const std::string& sensor_frame, const std::string& name) {
  const auto it = graph.laser_planes().find(name);
  if (it == graph.laser_planes().end()) {
    throw OptionError(cell + " has no laser plane '" + name +
                      "': run `lasercell calibrate laser` first or give --laser-plane nx,ny,nz,d");
  }
  if (it->second.frame != sensor_frame) {
    throw OptionError(cell + ": laser plane '" + name + "' is given in frame '" + it->second.frame +
                      "', expected '" + sensor_frame + "'");
  }
  const Eigen::Vector3d& n = it->second.normal;
  return {n.x(), n.y(), n.z(), it->second.OffsetMm()};
}

KnownSphereCentres CentresFromTouches(const SphereTouches& touches, const std::string& name,
                                      const FrameGraph& graph, const std::string& base,
                                      double radius_mm,
                                      const Eigen::Vector3d& up_in_handling_base) {
  KnownSphereCentres k;
  k.radius_mm = touches.sphere_radius_mm.value_or(radius_mm);
  k.sigma_mm = touches.stated_sigma_mm;
  if (!(k.radius_mm > 0)) {
    throw FileError(name,
                    "sphere_radius_mm is missing or not positive: the centres are the "
                    "touched tops minus the radius");
  }
  if (!(k.sigma_mm > 0)) throw FileError(name, "stated_sigma_mm must be positive");
  if (!(up_in_handling_base.norm() > 0) || !up_in_handling_base.allFinite()) {
    throw OptionError("up_in_handling_base must be a finite non-zero direction");
  }
  const std::string& frame = touches.frame;
  if (!graph.HasFrame(frame) || !graph.HasFrame(base) || !graph.Connected(base, frame)) {
    throw FileError(name, "its frame '" + frame + "' is not connected to '" + base +
                              "' in the cell; the cell must hold both robots' bases");
  }
  const Eigen::Isometry3d base_from_frame = graph.Transform(base, frame);
  const Eigen::Vector3d up = up_in_handling_base.normalized();
  const std::size_t n = touches.touches.size();
  k.centres_in_base.assign(n, Eigen::Vector3d::Constant(NAN));
  for (const SphereTouch& t : touches.touches) {
    if (t.sphere < 0 || t.sphere >= static_cast<int>(n)) {
      throw FileError(name, "sphere index " + std::to_string(t.sphere) + " out of range");
    }
    k.centres_in_base[static_cast<std::size_t>(t.sphere)] =
        base_from_frame * (t.point_in_handling_base - k.radius_mm * up);
  }
  for (const Eigen::Vector3d& c : k.centres_in_base) {
    if (!c.allFinite()) throw FileError(name, "every sphere needs exactly one touch");
  }
  return k;
}

StaticEdge FlangeSensorEdge(const std::string& flange, const std::string& sensor,
                            const Eigen::Isometry3d& flange_from_sensor,
                            const std::optional<Matrix6d>& covariance, const std::string& tool,
                            double rms_mm, std::size_t points, std::size_t sweeps) {
  StaticEdge edge;
  edge.parent = flange;
  edge.child = sensor;
  edge.SetParentFromChild(flange_from_sensor);
  edge.covariance = covariance;
  edge.provenance = {tool, UtcTimestampIso(), "",
                     "rms " + std::to_string(rms_mm) + " mm over " + std::to_string(points) +
                         " points, " + std::to_string(sweeps) + " sweeps"};
  return edge;
}

}  // namespace lasercell::calib
