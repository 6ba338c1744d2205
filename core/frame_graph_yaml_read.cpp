// cell.yaml reading (format "lasercell.cell", version 1; the writer is frame_graph_yaml_write.cpp).
//
// Reading goes through yaml-cpp and checks everything: unknown fields (typos), counts, unit
// quaternions, frames, cycles. Messages count edges and joints from 1 and give the line.
// Every pose (static edges, robots' mounts) is kept as a QuaternionPose exactly as written
// (checked for |q| within 1e-9 of 1, not renormalized), so writing it again reproduces the text.

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <optional>
#include <set>
#include <span>
#include <string_view>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/io/file_util.hpp"

namespace lasercell {

namespace {

// Allowed fields per mapping; anything else is reported as a typo.
using Fields = std::span<const std::string_view>;
constexpr std::array<std::string_view, 6> kTopFields = {"format", "version", "frames",
                                                        "robots", "edges", "laser_planes"};
constexpr std::array<std::string_view, 2> kLaserSectionFields = {"version", "planes"};
constexpr std::array<std::string_view, 5> kLaserPlaneFields = {"frame", "normal", "point_mm",
                                                               "covariance", "provenance"};
constexpr std::array<std::string_view, 5> kRobotFields = {"model", "convention", "base_from_chain",
                                                          "chain_from_flange", "joints"};
constexpr std::array<std::string_view, 5> kJointFields = {"a_mm", "alpha_rad", "d_mm",
                                                          "theta_offset_rad", "joint_offset_rad"};
constexpr std::array<std::string_view, 7> kEdgeFields = {
    "parent", "child", "type", "parent_from_child", "covariance", "provenance", "robot"};
constexpr std::array<std::string_view, 6> kStaticFields = {
    "parent", "child", "type", "parent_from_child", "covariance", "provenance"};
constexpr std::array<std::string_view, 4> kDynamicFields = {"parent", "child", "type", "robot"};
constexpr std::array<std::string_view, 4> kProvenanceFields = {"tool", "date", "input_digest",
                                                               "residual_summary"};
constexpr std::array<std::string_view, 2> kPoseFields = {"translation_mm", "rotation_wxyz"};

template <typename Names>
std::string Joined(const Names& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + std::string(n);
  return out.empty() ? "(none)" : out;
}

std::string Kind(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "empty";
  if (node.IsSequence()) return "a list";
  if (node.IsMap()) return "a mapping";
  return "'" + node.Scalar() + "'";
}

/// Checks one cell file; every problem becomes a FileError naming the file and the line.
class CellReader {
 public:
  explicit CellReader(std::string name) : name_(std::move(name)) {}

  FrameGraph Read(const YAML::Node& root) {
    if (!root.IsDefined() || root.IsNull()) {
      throw FileError(name_, "is empty; expected a lasercell cell file starting with 'format: " +
                                 std::string(kCellFormatName) + "'");
    }
    if (!root.IsMap()) {
      Fail("is not a mapping at the top level (it is " + Kind(root) +
               "); expected a lasercell cell file starting with 'format: " + kCellFormatName + "'",
           root);
    }
    if (!Find(root, "format")) {
      Fail("missing field 'format' at the top level; a lasercell cell file starts with 'format: " +
               std::string(kCellFormatName) + "' (is this a cell file?)",
           root);
    }
    const YAML::Node format = Require(root, "format", "the top level");
    if (!format.IsScalar() || format.Scalar() != kCellFormatName) {
      Fail("format is " + Kind(format) + "; expected '" + kCellFormatName +
               "' (is this a lasercell cell file?)",
           format);
    }
    const YAML::Node version = Require(root, "version", "the top level");
    int number = 0;
    const std::string version_text = version.IsScalar() ? version.Scalar() : "";
    const auto parsed =
        std::from_chars(version_text.data(), version_text.data() + version_text.size(), number);
    if (version_text.empty() || parsed.ec != std::errc() ||
        parsed.ptr != version_text.data() + version_text.size()) {
      Fail("version is " + Kind(version) + ", not an integer; this lasercell reads version " +
               std::to_string(kCellFormatVersion),
           version);
    }
    if (number != kCellFormatVersion) {
      Fail("unsupported version " + std::to_string(number) + "; this lasercell reads version " +
               std::to_string(kCellFormatVersion) + " (use the lasercell that wrote the file)",
           version);
    }
    CheckKeys(root, kTopFields, "the top level");
    FrameGraph graph;
    ReadFrames(Require(root, "frames", "the top level"), graph);
    if (const auto robots = Find(root, "robots"); robots && !robots->IsNull()) {
      ReadRobots(*robots, graph);
    }
    if (const auto edges = Find(root, "edges"); edges && !edges->IsNull()) {
      ReadEdges(*edges, graph);
    }
    if (const auto planes = Find(root, "laser_planes"); planes && !planes->IsNull()) {
      ReadLaserPlanes(*planes, graph);
    }
    return graph;
  }

 private:
  [[noreturn]] void Fail(const std::string& problem, const YAML::Node& node) const {
    std::string line;
    if (node.IsDefined() && !node.Mark().is_null()) {
      line = " (line " + std::to_string(node.Mark().line + 1) + ")";
    }
    throw FileError(name_, problem + line);
  }

  static std::optional<YAML::Node> Find(const YAML::Node& map, const std::string& key) {
    for (auto it = map.begin(); it != map.end(); ++it) {
      if (it->first.IsScalar() && it->first.Scalar() == key) return it->second;
    }
    return std::nullopt;
  }

  YAML::Node Require(const YAML::Node& map, const std::string& key, const std::string& where) {
    const auto node = Find(map, key);
    if (!node) Fail("missing field '" + key + "' in " + where, map);
    return *node;
  }

  /// Catches typos: every key must be one of `allowed`, and appear once.
  void CheckKeys(const YAML::Node& map, Fields allowed, const std::string& where) {
    std::set<std::string> seen;
    for (auto it = map.begin(); it != map.end(); ++it) {
      const std::string key = it->first.IsScalar() ? it->first.Scalar() : "?";
      if (std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
        Fail("unknown field '" + key + "' in " + where + "; expected " + Joined(allowed),
             it->first);
      }
      if (!seen.insert(key).second) {
        Fail("field '" + key + "' appears twice in " + where + "; keep one", it->first);
      }
    }
  }

  void ExpectMap(const YAML::Node& node, const std::string& where) {
    if (!node.IsMap()) Fail(where + " must be a mapping, got " + Kind(node), node);
  }

  std::string Text(const YAML::Node& node, const std::string& where) {
    if (node.IsNull()) return "";
    if (!node.IsScalar()) Fail(where + " must be a text, got " + Kind(node), node);
    return node.Scalar();
  }

  double Number(const YAML::Node& node, const std::string& where) {
    if (!node.IsScalar()) Fail(where + " must be a number, got " + Kind(node), node);
    const std::string& text = node.Scalar();
    double value = 0;
    const auto result = std::from_chars(text.data(), text.data() + text.size(), value);
    if (text.empty() || result.ec != std::errc() || result.ptr != text.data() + text.size() ||
        !std::isfinite(value)) {
      Fail(where + " is '" + text + "', not a finite number", node);
    }
    return value;
  }

  std::vector<double> Numbers(const YAML::Node& node, std::size_t count, const std::string& where) {
    if (!node.IsSequence() || node.size() != count) {
      Fail(where + " must be a list of " + std::to_string(count) + " numbers, got " +
               (node.IsSequence() ? std::to_string(node.size()) + " values" : Kind(node)),
           node);
    }
    std::vector<double> values;
    for (std::size_t i = 0; i < count; ++i) {
      values.push_back(Number(node[i], where + "[" + std::to_string(i) + "]"));
    }
    return values;
  }

  /// The pose as written: the quaternion's coefficients are checked, not renormalized.
  QuaternionPose Pose(const YAML::Node& node, const std::string& where) {
    ExpectMap(node, where);
    CheckKeys(node, kPoseFields, where);
    const auto t = Numbers(Require(node, "translation_mm", where), 3, where + ".translation_mm");
    const YAML::Node rotation = Require(node, "rotation_wxyz", where);
    const auto q = Numbers(rotation, 4, where + ".rotation_wxyz");
    const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (!(std::abs(norm - 1.0) <= kUnitQuaternionTolerance)) {
      Fail(where + ": rotation_wxyz has norm " + FormatDouble(norm) +
               "; expected a unit quaternion (norm within 1e-9 of 1), w first",
           rotation);
    }
    return {Eigen::Quaterniond(q[0], q[1], q[2], q[3]), Eigen::Vector3d(t[0], t[1], t[2])};
  }

  void ReadFrames(const YAML::Node& frames, FrameGraph& graph) {
    if (!frames.IsSequence()) {
      Fail("frames must be a list of frame names, got " + Kind(frames), frames);
    }
    for (std::size_t i = 0; i < frames.size(); ++i) {
      const std::string name = Text(frames[i], "frames entry " + std::to_string(i + 1));
      if (graph.HasFrame(name)) Fail("frame '" + name + "' is listed twice in frames", frames[i]);
      try {
        graph.AddFrame(name);
      } catch (const InputError& e) {
        Fail(std::string("frames: ") + e.what(), frames[i]);
      }
    }
  }

  void ReadRobots(const YAML::Node& robots, FrameGraph& graph) {
    ExpectMap(robots, "robots");
    for (auto it = robots.begin(); it != robots.end(); ++it) {
      const std::string name = Text(it->first, "a robot name");
      const std::string where = "robot '" + name + "'";
      const YAML::Node robot = it->second;
      ExpectMap(robot, where);
      const std::vector<std::string> declared = graph.Robots();
      if (std::find(declared.begin(), declared.end(), name) != declared.end()) {
        Fail(where + " is declared twice under robots; keep one", it->first);
      }
      const auto model = Find(robot, "model");
      if (model && Text(*model, where + " model") != "dh") {
        Fail(where + ": unknown model " + Kind(*model) + "; this lasercell reads model: dh",
             *model);
      }
      CheckKeys(robot, kRobotFields, where);
      Require(robot, "model", where);
      const YAML::Node convention_node = Require(robot, "convention", where);
      const std::string convention = Text(convention_node, where + " convention");
      if (convention != "standard" && convention != "modified") {
        Fail(where + ": unknown convention '" + convention + "'; expected standard or modified",
             convention_node);
      }
      QuaternionPose base_from_chain, chain_from_flange;  // identity when absent
      if (const auto n = Find(robot, "base_from_chain")) {
        base_from_chain = Pose(*n, where + " base_from_chain");
      }
      if (const auto n = Find(robot, "chain_from_flange")) {
        chain_from_flange = Pose(*n, where + " chain_from_flange");
      }
      const YAML::Node joints = Require(robot, "joints", where);
      if (!joints.IsSequence()) Fail(where + " joints must be a list, got " + Kind(joints), joints);
      std::vector<DhJoint> rows;
      for (std::size_t i = 0; i < joints.size(); ++i) {
        const std::string joint = where + " joint " + std::to_string(i + 1);
        ExpectMap(joints[i], joint);
        CheckKeys(joints[i], kJointFields, joint);
        DhJoint row;
        row.a_mm = Number(Require(joints[i], "a_mm", joint), joint + " a_mm");
        row.alpha_rad = Number(Require(joints[i], "alpha_rad", joint), joint + " alpha_rad");
        row.d_mm = Number(Require(joints[i], "d_mm", joint), joint + " d_mm");
        if (const auto n = Find(joints[i], "theta_offset_rad")) {
          row.theta_offset_rad = Number(*n, joint + " theta_offset_rad");
        }
        if (const auto n = Find(joints[i], "joint_offset_rad"))
          row.joint_offset_rad = Number(*n, joint + " joint_offset_rad");
        rows.push_back(row);
      }
      try {
        graph.SetRobot(name, DhChain(convention == "standard" ? DhConvention::kStandard
                                                              : DhConvention::kModified,
                                     std::move(rows), base_from_chain, chain_from_flange));
      } catch (const InputError& e) {
        Fail(where + ": " + e.what(), robot);
      }
    }
  }

  EdgeProvenance ProvenanceOf(const YAML::Node& node, const std::string& pw) {
    ExpectMap(node, pw);
    CheckKeys(node, kProvenanceFields, pw);
    const auto text = [&](const char* key) {
      const auto n = Find(node, key);
      return n ? Text(*n, pw + " " + key) : std::string();
    };
    return {text("tool"), text("date"), text("input_digest"), text("residual_summary")};
  }

  void ReadLaserPlanes(const YAML::Node& section, FrameGraph& graph) {
    ExpectMap(section, "laser_planes");
    CheckKeys(section, kLaserSectionFields, "laser_planes");
    const YAML::Node version = Require(section, "version", "laser_planes");
    const std::string text = version.IsScalar() ? version.Scalar() : "";
    if (text != std::to_string(kLaserPlanesSectionVersion)) {
      Fail("laser_planes version is " + Kind(version) + "; this lasercell reads version " +
               std::to_string(kLaserPlanesSectionVersion) +
               " (use the lasercell that wrote the file)",
           version);
    }
    const YAML::Node planes = Require(section, "planes", "laser_planes");
    ExpectMap(planes, "laser_planes planes");
    for (auto it = planes.begin(); it != planes.end(); ++it) {
      const std::string name = Text(it->first, "a laser plane name");
      const std::string where = "laser plane '" + name + "'";
      if (graph.laser_planes().count(name) > 0) {
        Fail(where + " is listed twice under laser_planes; keep one", it->first);
      }
      const YAML::Node node = it->second;
      ExpectMap(node, where);
      CheckKeys(node, kLaserPlaneFields, where);
      LaserPlaneEntry plane;
      const YAML::Node frame = Require(node, "frame", where);
      plane.frame = Text(frame, where + " frame");
      if (!graph.HasFrame(plane.frame)) {
        Fail(where + ": frame '" + plane.frame +
                 "' is not listed in frames; add it there or fix the name (frames: " +
                 Joined(graph.Frames()) + ")",
             frame);
      }
      const auto n = Numbers(Require(node, "normal", where), 3, where + " normal");
      const auto p = Numbers(Require(node, "point_mm", where), 3, where + " point_mm");
      plane.normal = Eigen::Vector3d(n[0], n[1], n[2]);
      plane.point_mm = Eigen::Vector3d(p[0], p[1], p[2]);
      if (const auto c = Find(node, "covariance")) {
        const auto values = Numbers(*c, 16, where + " covariance");
        plane.covariance =
            Eigen::Map<const Eigen::Matrix<double, 4, 4, Eigen::RowMajor>>(values.data());
      }
      if (const auto pr = Find(node, "provenance")) {
        plane.provenance = ProvenanceOf(*pr, where + " provenance");
      }
      try {
        graph.SetLaserPlane(name, plane);
      } catch (const InputError& e) {
        Fail(e.what(), node);
      }
    }
  }

  StaticEdge StaticEdgeOf(const YAML::Node& edge, const std::string& where,
                          const std::string& parent, const std::string& child) {
    StaticEdge s;
    s.parent = parent;
    s.child = child;
    s.parent_from_child =
        Pose(Require(edge, "parent_from_child", where), where + " parent_from_child");
    if (const auto c = Find(edge, "covariance")) {
      const auto values = Numbers(*c, 36, where + " covariance");
      s.covariance = Eigen::Map<const Eigen::Matrix<double, 6, 6, Eigen::RowMajor>>(values.data());
    }
    if (const auto p = Find(edge, "provenance")) {
      const std::string pw = where + " provenance";
      ExpectMap(*p, pw);
      CheckKeys(*p, kProvenanceFields, pw);
      const auto text = [&](const char* key) {
        const auto n = Find(*p, key);
        return n ? Text(*n, pw + " " + key) : std::string();
      };
      s.provenance = {text("tool"), text("date"), text("input_digest"), text("residual_summary")};
    }
    return s;
  }

  void ReadEdges(const YAML::Node& edges, FrameGraph& graph) {
    if (!edges.IsSequence()) Fail("edges must be a list, got " + Kind(edges), edges);
    std::vector<std::pair<std::string, std::string>> pairs;  // per edge, for duplicates
    std::vector<std::string> robots_used;                    // per edge ("" when static)
    for (std::size_t i = 0; i < edges.size(); ++i) {
      const YAML::Node edge = edges[i];
      const std::string where = "edge " + std::to_string(i + 1);
      ExpectMap(edge, where);
      CheckKeys(edge, kEdgeFields, where);
      const YAML::Node type_node = Require(edge, "type", where);
      const std::string type = Text(type_node, where + " type");
      std::array<std::string, 2> ends;
      for (int k = 0; k < 2; ++k) {
        const char* role = k == 0 ? "parent" : "child";
        const YAML::Node node = Require(edge, role, where);
        ends[k] = Text(node, where + " " + role);
        if (!graph.HasFrame(ends[k])) {
          Fail(where + ": " + role + " frame '" + ends[k] +
                   "' is not listed in frames; add it there or fix the name (frames: " +
                   Joined(graph.Frames()) + ")",
               node);
        }
      }
      for (std::size_t j = 0; j < pairs.size(); ++j) {
        if ((pairs[j].first == ends[0] && pairs[j].second == ends[1]) ||
            (pairs[j].first == ends[1] && pairs[j].second == ends[0])) {
          Fail(where + " would create a cycle: " + ends[0] + " and " + ends[1] +
                   " are already joined by edge " + std::to_string(j + 1) + "; keep only one",
               edge);
        }
      }
      pairs.emplace_back(ends[0], ends[1]);
      if (type == "static") {
        CheckKeys(edge, kStaticFields, where + " (type static)");
        robots_used.emplace_back();
        const StaticEdge s = StaticEdgeOf(edge, where, ends[0], ends[1]);
        try {
          graph.SetStaticEdge(s);
        } catch (const InputError& e) {
          Fail(where + ": " + e.what(), edge);
        }
      } else if (type == "dynamic") {
        CheckKeys(edge, kDynamicFields, where + " (type dynamic)");
        const YAML::Node robot_node = Require(edge, "robot", where);
        const std::string robot = Text(robot_node, where + " robot");
        const std::vector<std::string> declared = graph.Robots();
        if (std::find(declared.begin(), declared.end(), robot) == declared.end()) {
          Fail(where + ": robot '" + robot +
                   "' is not declared under robots; declare it or fix the name (declared "
                   "robots: " +
                   Joined(declared) + ")",
               robot_node);
        }
        const auto used = std::find(robots_used.begin(), robots_used.end(), robot);
        if (used != robots_used.end()) {
          Fail(where + ": robot '" + robot + "' already drives edge " +
                   std::to_string(used - robots_used.begin() + 1) +
                   "; a robot drives exactly one edge (base -> flange)",
               robot_node);
        }
        robots_used.push_back(robot);
        try {
          graph.SetDynamicEdge({ends[0], ends[1], robot});
        } catch (const InputError& e) {
          Fail(where + ": " + e.what(), edge);
        }
      } else {
        Fail(where + ": unknown type '" + type + "'; expected static or dynamic", type_node);
      }
    }
  }

  std::string name_;
};

}  // namespace

FrameGraph FrameGraphFromYaml(const std::string& text, const std::string& name) {
  try {
    return CellReader(name).Read(YAML::Load(text));
  } catch (const YAML::ParserException& e) {
    throw FileError(name, "YAML syntax error at line " + std::to_string(e.mark.line + 1) +
                              ", column " + std::to_string(e.mark.column + 1) + ": " + e.msg +
                              "; fix the syntax");
  } catch (const YAML::Exception& e) {
    const std::string line = e.mark.is_null() ? "" : " at line " + std::to_string(e.mark.line + 1);
    throw FileError(name, "cannot read the YAML" + line + ": " + e.msg);
  }
}

FrameGraph LoadFrameGraph(const std::string& path) {
  return FrameGraphFromYaml(io::ReadFileBytes(path), path);
}

}  // namespace lasercell
