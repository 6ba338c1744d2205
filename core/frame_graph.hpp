#pragma once
// The cell's frame graph (ARCHITECTURE.md): a tree of named frames (lower snake case) joined by
//  - static edges `parent_from_child` from calibrations, each with provenance and an optional
//    6x6 covariance, and
//  - dynamic edges `base_from_flange` driven by a named robot's joint values (rad) through a
//    KinematicModel.
// Transform(to, from, joints) composes the path: it returns to_from_from, so
// p_in_to = graph.Transform("to", "from", joints) * p_in_from.
// Covariance convention: 6x6 over the perturbation xi = [rotation vector (rad); translation
// (mm)] applied on the left: parent_from_child_true = Exp(xi) * parent_from_child.
//
// Poses are stored as the cell file holds them (QuaternionPose, core/se3.hpp: a unit quaternion
// and a translation in mm): a static edge's `parent_from_child`, and a DhChain robot's
// base_from_chain and chain_from_flange. Matrices are derived (StaticEdge::ParentFromChild,
// DhChain::base_from_chain); a matrix given by a calibration is converted once
// (StaticEdge::SetParentFromChild, DhChain::set_base_from_chain). Reading a file keeps the
// quaternions' coefficients exactly as written, so nothing is lost between file and memory.
//
// File (cell.yaml, see FrameGraphToYaml): format "lasercell.cell", version 1, in this order:
//   format, version, frames (sorted), robots (sorted by name), then edges: first the static
//   edges in insertion order (a replaced edge keeps its place; reading a file inserts them in
//   file order), then the dynamic edges in insertion order (a file listing them interleaved is
//   rewritten in this order). Poses are {translation_mm: [x, y, z], rotation_wxyz: [w, x, y,
//   z]}; numbers are printed as the shortest text that reads back to the same double; the file
//   is written atomically. Every tool updates only its own edges, hence only their lines.
//   Optional last section `laser_planes` (omitted when there are none), versioned on its own:
//     laser_planes:
//       version: 1
//       planes:
//         laser:
//           frame: sensor
//           normal: [nx, ny, nz]
//           point_mm: [x, y, z]
//           covariance: [16 numbers, row-major 4x4 over [n; d]]   # optional
//           provenance: {tool: "...", date: "...", input_digest: "...", residual_summary: "..."}
//   The plane is n . p + d = 0 in `frame`, d = -n . point_mm (LaserPlaneEntry).
// Round trip: for any file FrameGraphToYaml wrote, FrameGraphFromYaml then FrameGraphToYaml
//   gives the identical text, and reading that again gives the identical doubles (static
//   edges and robots' mounts hold the file's quaternions and translations themselves). So for
//   a graph built in memory, write -> read -> write gives identical text, and every stored
//   quaternion and translation reads back bit-exactly.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/kinematics.hpp"
#include "core/se3.hpp"

namespace lasercell {

/// Where a static edge came from.
struct EdgeProvenance {
  std::string tool;              ///< e.g. "lasercell calibrate spheres 0.1.0".
  std::string date;              ///< ISO 8601 UTC, e.g. "2026-11-26T10:00:00Z".
  std::string input_digest;      ///< Digest of the inputs (e.g. "sha256:..."), may be empty.
  std::string residual_summary;  ///< One line, e.g. "rms 0.021 mm over 4 spheres".
};

/// How a calibrated edge moved with each error mode of the laser-triangulation sensor whose
/// points it was calibrated from (LaserPlaneEntry::error_modes): a consumer that measures
/// through the same sensor counts that shared error once, with its sign, instead of as two
/// independent errors (localize/laser_plane_uncertainty.hpp).
struct SensorModeResponse {
  std::string laser;  ///< Name of the laser plane whose error_modes the columns follow.
  /// provenance.input_digest of that plane when the edge was calibrated: a plane calibrated
  /// again has other modes, and a consumer then ignores the response (and says so).
  std::string plane_digest;
  /// Column k: left perturbation [rotvec (rad); translation (mm)] of parent_from_child at mode
  /// k's +1 sigma. Exactly 6 rows, one column per mode.
  Eigen::Matrix<double, 6, Eigen::Dynamic> columns;
};

/// A fixed transform between two frames, parent_from_child (p_in_parent = T * p_in_child),
/// stored as the cell file holds it.
struct StaticEdge {
  std::string parent;  ///< Frame the pose maps into.
  std::string child;   ///< Frame the pose maps from.
  /// The pose: a unit quaternion (|q| within 1e-9 of 1) kept exactly as given or read, never
  /// renormalized, and the child's origin in parent coordinates (mm). SetParentFromChild stores
  /// the canonical sign (CanonicalQuaternion).
  QuaternionPose parent_from_child;
  EdgeProvenance provenance;
  std::optional<Matrix6d> covariance;  ///< Over [rotvec rad; translation mm], left perturbation.
  /// Optional: the edge's response to a sensor's error modes (calibrated through that sensor).
  /// Its share is not in `covariance`.
  std::optional<SensorModeResponse> sensor_response;

  /// parent_from_child as a matrix (parent_from_child.ToIsometry()); the stored coefficients
  /// stay untouched.
  Eigen::Isometry3d ParentFromChild() const { return parent_from_child.ToIsometry(); }
  /// Sets parent_from_child from a matrix: one conversion to the canonical unit quaternion
  /// (QuaternionPose::FromIsometry). Throws InputError, naming the edge, unless the pose is
  /// finite with an orthonormal, right-handed rotation (|R^T R - I| < 1e-9).
  void SetParentFromChild(const Eigen::Isometry3d& parent_from_child);
};

/// A transform driven by a robot's joints: parent = robot base, child = robot flange.
struct DynamicEdge {
  std::string parent;  ///< Robot base frame, e.g. "vision_base".
  std::string child;   ///< Robot flange frame, e.g. "vision_flange".
  std::string robot;   ///< Robot name, key into JointValues, e.g. "vision_robot".
};

/// One direction of a laser-triangulation sensor's calibration error, at +1 sigma: a step of the
/// camera's intrinsics (empty: the camera unchanged) and the laser plane's step [dn; dd] that
/// goes with it (the plane refitted through the stepped camera, or a principal axis of the
/// plane fit's own covariance). The sensor's error is sum_k a_k mode_k with independent
/// a_k ~ N(0, 1); every point measured through the sensor shares it.
struct SensorErrorMode {
  std::vector<double> intrinsics_step;                   ///< Camera lens model's order.
  Eigen::Vector4d plane_step = Eigen::Vector4d::Zero();  ///< [dn (unitless); dd (mm)].
};

/// A laser light plane, n . p + d = 0 for points p of `frame` (for a laser-triangulation sensor
/// the `sensor` frame, i.e. the camera frame). Stored as the cell file holds it: the unit normal
/// and a point on the plane (p0), both kept exactly as given or read.
struct LaserPlaneEntry {
  std::string frame = "sensor";                        ///< Frame the plane is expressed in.
  Eigen::Vector3d normal = Eigen::Vector3d::UnitY();   ///< Unit normal (|n| within 1e-9 of 1).
  Eigen::Vector3d point_mm = Eigen::Vector3d::Zero();  ///< A point of the plane (p0), mm.
  /// Optional 4x4 covariance over [n (3, unitless); d (mm)] with d = -n . p0 (rank 3: the
  /// normal is unit), as the calibration estimated it.
  std::optional<Eigen::Matrix4d> covariance;
  /// Optional: the part of `covariance` the camera's own (intrinsics) uncertainty causes. That
  /// error is shared by everything measured through the same camera, including calibrations
  /// made with this plane (a sensor-to-robot placement), so a consumer that treats the plane and
  /// such a calibration as independent must not count it twice.
  std::optional<Eigen::Matrix4d> camera_covariance;
  /// Optional: the sensor's error modes (camera and plane together), sum_k plane_step
  /// plane_step^T = covariance. Calibrations made through this sensor store their response to
  /// them (StaticEdge::sensor_response).
  std::vector<SensorErrorMode> error_modes;
  EdgeProvenance provenance;  ///< Which calibration produced it.

  /// d of n . p + d = 0 (mm): minus the signed distance of the frame origin along n.
  double OffsetMm() const { return -normal.dot(point_mm); }
};

/// Joint values (rad) per robot name.
using JointValues = std::map<std::string, std::vector<double>>;

/// FrameGraph::TransformWithCovariance: a transform, its first-order covariance from the static
/// edges' covariances, and what that covariance leaves out.
struct TransformWithCovarianceResult {
  /// The transform, exactly as FrameGraph::Transform returns it.
  Eigen::Isometry3d to_from_from = Eigen::Isometry3d::Identity();
  /// Covariance of to_from_from over [rotation vector (rad); translation (mm)], left
  /// perturbation in the `to` frame (to_from_from_true = Exp(xi) * to_from_from), composed to
  /// first order from the static edges on the path that carry a covariance, edges assumed
  /// independent (core/pose_covariance.hpp). Zero when none does.
  Matrix6d covariance = Matrix6d::Zero();
  /// Static edges on the path without a covariance ("parent <- child", in path order from
  /// `to`): counted as exact, so `covariance` understates the uncertainty by their share.
  std::vector<std::string> edges_without_covariance;
  /// The sensor_response of each static edge on the path that has one, its columns moved into
  /// left perturbations of to_from_from (in the `to` frame).
  std::vector<SensorModeResponse> sensor_responses;
  /// True when the path passes through a dynamic (robot) edge. Its joint-reading and
  /// kinematic-model uncertainty is not modelled: the robot edge counts as exact.
  bool crosses_dynamic_edge = false;
  /// The robots of those dynamic edges, in path order from `to`.
  std::vector<std::string> robots_on_path;

  /// True when every edge on the path contributed its uncertainty (no edge without covariance,
  /// no robot edge).
  bool Complete() const { return edges_without_covariance.empty() && !crosses_dynamic_edge; }
  /// One line naming what the covariance leaves out, e.g. "covariance omits: static edge
  /// cell <- handling_base (no covariance); robot vision_robot (joint and kinematic uncertainty
  /// not modelled)", or "covariance covers every edge on the path".
  std::string Summary() const;
};

/// Named frames joined by static and dynamic edges; a forest without cycles.
class FrameGraph {
 public:
  FrameGraph() = default;
  FrameGraph(const FrameGraph& other);
  FrameGraph& operator=(const FrameGraph& other);
  FrameGraph(FrameGraph&&) noexcept = default;
  FrameGraph& operator=(FrameGraph&&) noexcept = default;

  /// Adds a frame (no-op when present). Throws InputError for names that are not lower snake
  /// case ([a-z][a-z0-9_]*).
  void AddFrame(const std::string& name);
  bool HasFrame(const std::string& name) const;  ///< The frame exists.
  /// All frames in sorted order.
  std::vector<std::string> Frames() const;

  /// Adds or replaces the static edge between edge.parent and edge.child (in either direction;
  /// a replaced edge takes the new direction and keeps its place in the file). Frames are added
  /// when missing. The pose is stored as given (no renormalization). Throws InputError when the
  /// edge would close a cycle, the quaternion or translation is not finite, |rotation| is off 1
  /// by more than 1e-9, or the covariance is not finite and symmetric.
  void SetStaticEdge(const StaticEdge& edge);
  /// Adds or replaces the dynamic edge of `edge.robot`. The robot must be registered.
  void SetDynamicEdge(const DynamicEdge& edge);
  /// Registers (or replaces) the kinematic model of a robot.
  void SetRobot(const std::string& robot, const KinematicModel& model);
  /// Adds or replaces the laser plane `name` (lower snake case, e.g. "laser"); its frame is added
  /// when missing. Throws InputError when the name is not lower snake case, the normal is not
  /// unit (within 1e-9), a value is not finite or the covariance is not symmetric.
  void SetLaserPlane(const std::string& name, const LaserPlaneEntry& plane);
  /// Removes a laser plane; returns false when there was none.
  bool RemoveLaserPlane(const std::string& name);
  /// Laser planes by name (sorted).
  const std::map<std::string, LaserPlaneEntry>& laser_planes() const { return laser_planes_; }

  /// Removes the edge between a and b (either direction); returns false when there was none.
  bool RemoveEdge(const std::string& a, const std::string& b);

  const std::vector<StaticEdge>& static_edges() const { return static_edges_; }
  const std::vector<DynamicEdge>& dynamic_edges() const { return dynamic_edges_; }
  /// The robot's model; throws InputError when unknown.
  const KinematicModel& Robot(const std::string& robot) const;
  /// Robot names in sorted order.
  std::vector<std::string> Robots() const;

  /// to_from_from along the unique path. Throws InputError for unknown frames, frames in
  /// different trees ("not connected"), or a path through a dynamic edge whose robot has no
  /// (or the wrong number of) joint values in `joints`.
  Eigen::Isometry3d Transform(const std::string& to, const std::string& from,
                              const JointValues& joints = {}) const;
  /// Transform(to, from, joints) with the first-order covariance of to_from_from composed from
  /// the covariances of the static edges on the path (an edge walked child -> parent
  /// contributes the covariance of its inverse, InverseCovariance), and the list of what is not
  /// modelled (edges without covariance, robot edges). Throws what Transform throws.
  TransformWithCovarianceResult TransformWithCovariance(const std::string& to,
                                                        const std::string& from,
                                                        const JointValues& joints = {}) const;
  /// Robots whose dynamic edges lie on the path from `from` to `to`.
  std::vector<std::string> RobotsOnPath(const std::string& to, const std::string& from) const;
  /// True when a path exists.
  bool Connected(const std::string& a, const std::string& b) const;

 private:
  struct Step {
    bool is_static;
    std::size_t index;  // into static_edges_ or dynamic_edges_
    bool forward;       // true: walking parent -> child (apply parent_from_child)
  };
  std::vector<Step> Path(const std::string& to, const std::string& from) const;
  void CheckNoCycle(const std::string& a, const std::string& b) const;

  std::vector<std::string> frames_;
  std::vector<StaticEdge> static_edges_;
  std::vector<DynamicEdge> dynamic_edges_;
  std::map<std::string, std::unique_ptr<KinematicModel>> robots_;
  std::map<std::string, LaserPlaneEntry> laser_planes_;
};

/// Version of the optional `laser_planes` section of cell.yaml.
inline constexpr int kLaserPlanesSectionVersion = 1;

/// Cell-file format name (the `format:` field) and current version.
inline constexpr const char* kCellFormatName = "lasercell.cell";
inline constexpr int kCellFormatVersion = 1;

/// Serializes a frame graph as cell.yaml text: deterministic, in the order given at the top of
/// this file; static edges' and robots' mounting poses are written exactly as stored. Throws
/// InputError for non-finite values or a robot model without a file form.
std::string FrameGraphToYaml(const FrameGraph& graph);
/// Parses cell.yaml text; `name` appears in error messages. Static edges and robots' mounts
/// keep the quaternion coefficients as written (checked, not renormalized). Throws FileError
/// naming the file and the problem: unknown format/version, an edge naming an undeclared frame,
/// a cycle, a non-unit quaternion (|q| off 1 by more than 1e-9), malformed numbers or fields.
FrameGraph FrameGraphFromYaml(const std::string& text, const std::string& name);
/// Reads cell.yaml.
FrameGraph LoadFrameGraph(const std::string& path);
/// Writes cell.yaml atomically.
void SaveFrameGraph(const std::string& path, const FrameGraph& graph);

/// Pose in the file notation, one line: {translation_mm: [x, y, z], rotation_wxyz: [w, x, y, z]},
/// with the coefficients exactly as stored.
std::string PoseToFileNotation(const QuaternionPose& pose);
/// The same for a matrix, through QuaternionPose::FromIsometry (CanonicalQuaternion).
std::string PoseToFileNotation(const Eigen::Isometry3d& pose);
/// Formats a double with the shortest text that reads back to the same value.
std::string FormatDouble(double value);

}  // namespace lasercell
