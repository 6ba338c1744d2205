// FrameGraph: named frames joined by static and dynamic edges, an undirected forest. Queries
// walk the unique path with a breadth-first search; the graphs of a cell are small (tens of
// frames), so adjacency is rebuilt per query instead of being cached and kept in sync.

#include "core/frame_graph.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <utility>

#include "core/error.hpp"
#include "core/pose_covariance.hpp"

namespace lasercell {

namespace {

bool IsLowerSnakeCase(const std::string& name) {
  if (name.empty() || name[0] < 'a' || name[0] > 'z') return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
  });
}

std::string JoinNames(const std::vector<std::string>& names) {
  if (names.empty()) return "(none)";
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

void CheckFrameName(const std::string& name) {
  if (IsLowerSnakeCase(name)) return;
  // Suggest the nearest valid name: lower case, other characters as '_', a letter first.
  std::string suggestion;
  for (const char c : name) {
    const char lower = (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c;
    suggestion += IsLowerSnakeCase(std::string("a") + lower) ? lower : '_';
  }
  if (!IsLowerSnakeCase(suggestion)) suggestion = "frame_" + suggestion;
  throw InputError("frame name '" + name +
                   "' is not lower snake case ([a-z][a-z0-9_]*); use e.g. '" + suggestion + "'");
}

/// "static edge a <- b", or "static edge" before the frames are named.
std::string EdgeName(const std::string& parent, const std::string& child) {
  if (parent.empty() && child.empty()) return "static edge";
  return "static edge " + parent + " <- " + child;
}

bool SamePair(const std::string& p, const std::string& c, const std::string& a,
              const std::string& b) {
  return (p == a && c == b) || (p == b && c == a);
}

/// Throws InputError unless `covariance` is finite and symmetric up to a relative 1e-9. The
/// YAML reader goes through SetStaticEdge, so a file is held to the same rule.
void CheckEdgeCovariance(const Matrix6d& covariance, const std::string& what) {
  if (!covariance.allFinite()) {
    throw InputError(what + " covariance has non-finite entries; pass a finite 6x6 matrix");
  }
  const double scale = std::max(1.0, covariance.cwiseAbs().maxCoeff());
  const double asymmetry = (covariance - covariance.transpose()).cwiseAbs().maxCoeff();
  if (asymmetry > 1e-9 * scale) {
    throw InputError(what + " covariance is not symmetric (max |C - C^T| = " +
                     FormatDouble(asymmetry) + "); pass a symmetric 6x6 matrix");
  }
}

void CheckErrorModes(const std::vector<SensorErrorMode>& modes, const std::string& what) {
  for (std::size_t k = 0; k < modes.size(); ++k) {
    const SensorErrorMode& m = modes[k];
    const std::string field = what + " error_modes[" + std::to_string(k) + "]";
    if (!m.plane_step.allFinite() ||
        !std::all_of(m.intrinsics_step.begin(), m.intrinsics_step.end(),
                     [](double v) { return std::isfinite(v); })) {
      throw InputError(field + " has non-finite values; pass finite steps");
    }
    if (!m.intrinsics_step.empty() && !modes[0].intrinsics_step.empty() &&
        m.intrinsics_step.size() != modes[0].intrinsics_step.size()) {
      throw InputError(field + " steps " + std::to_string(m.intrinsics_step.size()) +
                       " intrinsics where error_modes[0] steps " +
                       std::to_string(modes[0].intrinsics_step.size()) +
                       "; every mode steps the same camera (or none)");
    }
  }
}

void CheckSensorResponse(const SensorModeResponse& r, const std::string& what) {
  if (!IsLowerSnakeCase(r.laser)) {
    throw InputError(what + " sensor_response.laser '" + r.laser +
                     "' is not a laser plane name (lower snake case)");
  }
  if (r.columns.cols() == 0 || !r.columns.allFinite()) {
    throw InputError(what + " sensor_response needs one finite column of 6 values per error mode");
  }
}
}  // namespace

void StaticEdge::SetParentFromChild(const Eigen::Isometry3d& pose) {
  CheckRigidTransform(pose, EdgeName(parent, child) + " parent_from_child");
  parent_from_child = QuaternionPose::FromIsometry(pose);
}

FrameGraph::FrameGraph(const FrameGraph& other)
    : frames_(other.frames_),
      static_edges_(other.static_edges_),
      dynamic_edges_(other.dynamic_edges_),
      laser_planes_(other.laser_planes_) {
  for (const auto& [name, model] : other.robots_) robots_.emplace(name, model->Clone());
}

FrameGraph& FrameGraph::operator=(const FrameGraph& other) {
  if (this != &other) {
    FrameGraph copy(other);
    *this = std::move(copy);
  }
  return *this;
}

void FrameGraph::AddFrame(const std::string& name) {
  CheckFrameName(name);
  const auto it = std::lower_bound(frames_.begin(), frames_.end(), name);
  if (it == frames_.end() || *it != name) frames_.insert(it, name);
}

bool FrameGraph::HasFrame(const std::string& name) const {
  return std::binary_search(frames_.begin(), frames_.end(), name);
}

std::vector<std::string> FrameGraph::Frames() const { return frames_; }

void FrameGraph::SetStaticEdge(const StaticEdge& edge) {
  CheckFrameName(edge.parent);
  CheckFrameName(edge.child);
  const std::string what = EdgeName(edge.parent, edge.child);
  if (edge.parent == edge.child) {
    throw InputError(what + " joins a frame to itself; parent and child must differ");
  }
  CheckQuaternionPose(edge.parent_from_child, what + " parent_from_child");
  if (edge.covariance) CheckEdgeCovariance(*edge.covariance, what);
  if (edge.sensor_response) CheckSensorResponse(*edge.sensor_response, what);
  for (const DynamicEdge& d : dynamic_edges_) {
    if (SamePair(d.parent, d.child, edge.parent, edge.child)) {
      throw InputError(what + ": frames '" + edge.parent + "' and '" + edge.child +
                       "' are already joined by the dynamic edge of robot '" + d.robot +
                       "'; remove it first (RemoveEdge) to replace it by a static edge");
    }
  }
  for (StaticEdge& s : static_edges_) {
    if (SamePair(s.parent, s.child, edge.parent, edge.child)) {
      s = edge;  // Replaced in place: the other edges and the file order stay untouched.
      return;
    }
  }
  CheckNoCycle(edge.parent, edge.child);
  AddFrame(edge.parent);
  AddFrame(edge.child);
  static_edges_.push_back(edge);
}

void FrameGraph::SetLaserPlane(const std::string& name, const LaserPlaneEntry& plane) {
  if (!IsLowerSnakeCase(name)) {
    throw InputError("laser plane name '" + name +
                     "' is not lower snake case ([a-z][a-z0-9_]*); use e.g. 'laser'");
  }
  CheckFrameName(plane.frame);
  const std::string what = "laser plane '" + name + "'";
  if (!plane.normal.allFinite() || !plane.point_mm.allFinite()) {
    throw InputError(what + ": normal or point_mm is not finite; pass finite values");
  }
  if (!(std::abs(plane.normal.norm() - 1.0) <= 1e-9)) {
    throw InputError(what + ": normal has norm " + FormatDouble(plane.normal.norm()) +
                     "; expected a unit vector (norm within 1e-9 of 1)");
  }
  for (const auto& [field, matrix] : {std::pair{" covariance", &plane.covariance},
                                      std::pair{" camera_covariance", &plane.camera_covariance}}) {
    if (!*matrix) continue;
    const Eigen::Matrix4d& c = **matrix;
    if (!c.allFinite()) {
      throw InputError(what + field + " has non-finite entries; pass a finite 4x4 matrix");
    }
    const double scale = std::max(1.0, c.cwiseAbs().maxCoeff());
    if ((c - c.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale) {
      throw InputError(what + field + " is not symmetric; pass a symmetric 4x4 matrix");
    }
  }
  if (plane.camera_covariance && !plane.covariance) {
    throw InputError(what + ": camera_covariance is the camera's part of covariance; give both");
  }
  CheckErrorModes(plane.error_modes, what);
  AddFrame(plane.frame);
  laser_planes_[name] = plane;
}

bool FrameGraph::RemoveLaserPlane(const std::string& name) { return laser_planes_.erase(name) > 0; }

void FrameGraph::SetDynamicEdge(const DynamicEdge& edge) {
  CheckFrameName(edge.parent);
  CheckFrameName(edge.child);
  const std::string what = "dynamic edge " + edge.parent + " <- " + edge.child;
  if (edge.parent == edge.child) {
    throw InputError(what +
                     " joins a frame to itself; parent (base) and child (flange) must "
                     "differ");
  }
  if (robots_.find(edge.robot) == robots_.end()) {
    throw InputError(
        what + ": unknown robot '" + edge.robot +
        "'; register its model with SetRobot first (known robots: " + JoinNames(Robots()) + ")");
  }
  for (const StaticEdge& s : static_edges_) {
    if (SamePair(s.parent, s.child, edge.parent, edge.child)) {
      throw InputError(what + ": frames '" + edge.parent + "' and '" + edge.child +
                       "' are already joined by a static edge; remove it first (RemoveEdge)");
    }
  }
  // The robot's previous edge (if any) is replaced: check for cycles without it.
  const auto old = std::find_if(dynamic_edges_.begin(), dynamic_edges_.end(),
                                [&](const DynamicEdge& d) { return d.robot == edge.robot; });
  if (old != dynamic_edges_.end()) {
    const std::size_t index = static_cast<std::size_t>(old - dynamic_edges_.begin());
    const DynamicEdge previous = *old;
    dynamic_edges_.erase(old);
    try {
      CheckNoCycle(edge.parent, edge.child);
    } catch (...) {
      dynamic_edges_.insert(dynamic_edges_.begin() + static_cast<std::ptrdiff_t>(index), previous);
      throw;
    }
    AddFrame(edge.parent);
    AddFrame(edge.child);
    dynamic_edges_.insert(dynamic_edges_.begin() + static_cast<std::ptrdiff_t>(index), edge);
    return;
  }
  CheckNoCycle(edge.parent, edge.child);
  AddFrame(edge.parent);
  AddFrame(edge.child);
  dynamic_edges_.push_back(edge);
}

void FrameGraph::SetRobot(const std::string& robot, const KinematicModel& model) {
  if (robot.empty()) throw InputError("SetRobot: the robot name is empty; name the robot");
  robots_[robot] = model.Clone();
}

bool FrameGraph::RemoveEdge(const std::string& a, const std::string& b) {
  const auto s = std::find_if(static_edges_.begin(), static_edges_.end(), [&](const StaticEdge& e) {
    return SamePair(e.parent, e.child, a, b);
  });
  if (s != static_edges_.end()) {
    static_edges_.erase(s);
    return true;
  }
  const auto d =
      std::find_if(dynamic_edges_.begin(), dynamic_edges_.end(),
                   [&](const DynamicEdge& e) { return SamePair(e.parent, e.child, a, b); });
  if (d != dynamic_edges_.end()) {
    dynamic_edges_.erase(d);
    return true;
  }
  return false;
}

const KinematicModel& FrameGraph::Robot(const std::string& robot) const {
  const auto it = robots_.find(robot);
  if (it == robots_.end()) {
    throw InputError("unknown robot '" + robot + "'; known robots: " + JoinNames(Robots()));
  }
  return *it->second;
}

std::vector<std::string> FrameGraph::Robots() const {
  std::vector<std::string> names;
  for (const auto& entry : robots_) names.push_back(entry.first);
  return names;
}

std::vector<FrameGraph::Step> FrameGraph::Path(const std::string& to,
                                               const std::string& from) const {
  for (const std::string* name : {&to, &from}) {
    if (!HasFrame(*name)) {
      throw InputError("unknown frame '" + *name + "'; known frames: " + JoinNames(frames_));
    }
  }
  if (to == from) return {};
  // Undirected adjacency; BFS from `to` so that the recorded steps read to -> ... -> from.
  struct Link {
    std::string neighbor;
    Step step;  // walking from this frame to `neighbor`
  };
  std::map<std::string, std::vector<Link>> adjacency;
  for (std::size_t i = 0; i < static_edges_.size(); ++i) {
    const StaticEdge& e = static_edges_[i];
    adjacency[e.parent].push_back({e.child, {true, i, true}});
    adjacency[e.child].push_back({e.parent, {true, i, false}});
  }
  for (std::size_t i = 0; i < dynamic_edges_.size(); ++i) {
    const DynamicEdge& e = dynamic_edges_[i];
    adjacency[e.parent].push_back({e.child, {false, i, true}});
    adjacency[e.child].push_back({e.parent, {false, i, false}});
  }
  std::map<std::string, std::pair<std::string, Step>> reached_from;  // frame -> (previous, step)
  std::deque<std::string> queue{to};
  reached_from.emplace(to, std::make_pair(std::string(), Step{true, 0, true}));
  while (!queue.empty() && reached_from.find(from) == reached_from.end()) {
    const std::string current = queue.front();
    queue.pop_front();
    for (const Link& link : adjacency[current]) {
      if (reached_from.emplace(link.neighbor, std::make_pair(current, link.step)).second) {
        queue.push_back(link.neighbor);
      }
    }
  }
  if (reached_from.find(from) == reached_from.end()) {
    throw InputError("frames '" + to + "' and '" + from +
                     "' are not connected in the frame graph; add the edge (calibration or "
                     "robot) that joins their trees");
  }
  std::vector<Step> steps;
  for (std::string frame = from; frame != to;) {
    const auto& [previous, step] = reached_from.at(frame);
    steps.push_back(step);
    frame = previous;
  }
  std::reverse(steps.begin(), steps.end());
  return steps;
}

Eigen::Isometry3d FrameGraph::Transform(const std::string& to, const std::string& from,
                                        const JointValues& joints) const {
  Eigen::Isometry3d to_from_from = Eigen::Isometry3d::Identity();
  for (const Step& step : Path(to, from)) {
    Eigen::Isometry3d parent_from_child;
    if (step.is_static) {
      parent_from_child = static_edges_[step.index].ParentFromChild();
    } else {
      const DynamicEdge& edge = dynamic_edges_[step.index];
      const KinematicModel& model = Robot(edge.robot);
      const auto it = joints.find(edge.robot);
      if (it == joints.end() || static_cast<int>(it->second.size()) != model.NumJoints()) {
        throw InputError("Transform('" + to + "', '" + from + "') passes through robot '" +
                         edge.robot + "' (" + edge.parent + " <- " + edge.child +
                         "), which needs " + std::to_string(model.NumJoints()) +
                         " joint values (rad); " +
                         (it == joints.end() ? std::string("none were given")
                                             : std::to_string(it->second.size()) + " were given") +
                         "; pass them as joints[\"" + edge.robot + "\"]");
      }
      parent_from_child = model.BaseFromFlange(it->second);
    }
    to_from_from = to_from_from * (step.forward ? parent_from_child : parent_from_child.inverse());
  }
  return to_from_from;
}

TransformWithCovarianceResult FrameGraph::TransformWithCovariance(const std::string& to,
                                                                  const std::string& from,
                                                                  const JointValues& joints) const {
  TransformWithCovarianceResult result;
  // Transform checks the frames and the joint values and gives the pose; the walk below
  // repeats its products to know, at each edge, the prefix to_from_parent that moves the
  // edge's perturbation into the `to` frame.
  result.to_from_from = Transform(to, from, joints);
  Eigen::Isometry3d to_from_here = Eigen::Isometry3d::Identity();
  for (const Step& step : Path(to, from)) {
    Eigen::Isometry3d parent_from_child;
    if (step.is_static) {
      const StaticEdge& edge = static_edges_[step.index];
      parent_from_child = edge.ParentFromChild();
      if (edge.covariance) {
        // Forward the edge maps into the frame where we stand; backward we apply its inverse.
        const Matrix6d cov = step.forward ? *edge.covariance
                                          : InverseCovariance(parent_from_child, *edge.covariance);
        result.covariance = ComposeCovariance(to_from_here, result.covariance, cov);
      } else {
        result.edges_without_covariance.push_back(edge.parent + " <- " + edge.child);
      }
      if (edge.sensor_response) {
        // Forward: A Exp(xi) E B = Exp(Ad(A) xi) A E B; backward: A E^-1 Exp(-xi) B.
        SensorModeResponse moved = *edge.sensor_response;
        moved.columns =
            step.forward
                ? Matrix6d(Adjoint(to_from_here)) * moved.columns
                : Matrix6d(-Adjoint(to_from_here * parent_from_child.inverse())) * moved.columns;
        result.sensor_responses.push_back(std::move(moved));
      }
    } else {
      const DynamicEdge& edge = dynamic_edges_[step.index];
      parent_from_child = Transform(edge.parent, edge.child, joints);  // the one-edge path
      result.crosses_dynamic_edge = true;
      result.robots_on_path.push_back(edge.robot);
    }
    to_from_here = to_from_here * (step.forward ? parent_from_child : parent_from_child.inverse());
  }
  return result;
}

std::string TransformWithCovarianceResult::Summary() const {
  if (Complete()) return "covariance covers every edge on the path";
  std::string out;
  for (const std::string& edge : edges_without_covariance) {
    out += (out.empty() ? "" : "; ") + ("static edge " + edge + " (no covariance)");
  }
  for (const std::string& robot : robots_on_path) {
    out += (out.empty() ? "" : "; ") +
           ("robot " + robot + " (joint and kinematic uncertainty not modelled)");
  }
  return "covariance omits: " + out;
}

std::vector<std::string> FrameGraph::RobotsOnPath(const std::string& to,
                                                  const std::string& from) const {
  std::vector<std::string> robots;
  for (const Step& step : Path(to, from)) {
    if (!step.is_static) robots.push_back(dynamic_edges_[step.index].robot);
  }
  return robots;
}

bool FrameGraph::Connected(const std::string& a, const std::string& b) const {
  if (!HasFrame(a) || !HasFrame(b)) return false;
  try {
    Path(a, b);
    return true;
  } catch (const InputError&) {
    return false;
  }
}

void FrameGraph::CheckNoCycle(const std::string& a, const std::string& b) const {
  if (!Connected(a, b)) return;
  // Describe the existing path a -> ... -> b so the user sees which edges are in the way.
  std::string via = a;
  std::string frame = a;
  for (const Step& step : Path(a, b)) {
    const bool is_static = step.is_static;
    const std::string& parent =
        is_static ? static_edges_[step.index].parent : dynamic_edges_[step.index].parent;
    const std::string& child =
        is_static ? static_edges_[step.index].child : dynamic_edges_[step.index].child;
    frame = (frame == parent) ? child : parent;
    via += " -> " + frame +
           (is_static ? std::string(" (static)")
                      : " (dynamic, robot " + dynamic_edges_[step.index].robot + ")");
  }
  throw InputError("edge " + a + " - " + b + " would create a cycle: " + a + " and " + b +
                   " are already connected via " + via +
                   "; the frame graph must stay a tree: remove one of those edges first "
                   "(RemoveEdge) or check the parent/child names");
}

}  // namespace lasercell
