// cell.yaml reading (format "lasercell.cell", version 1; the writer is frame_graph_yaml_write.cpp).
//
// Reading goes through yaml::Fields and checks everything: unknown or repeated fields (typos),
// counts, unit quaternions, frames, cycles. Every message names the file, the line and the field
// path (`edges[2].parent_from_child.rotation_wxyz`, lists counted from 0). Every pose (static
// edges, robots' mounts) is kept as a QuaternionPose exactly as written (checked for |q| within
// kUnitQuaternionTolerance of 1, not renormalized), so writing it again reproduces the text.

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <string>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/io/file_util.hpp"
#include "core/yaml_fields.hpp"

namespace lasercell {

namespace {

using yaml::Fields;

std::string Joined(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out.empty() ? "(none)" : out;
}

/// A frame name that must be listed in frames.
std::string FrameOf(Fields& fields, const char* key, const FrameGraph& graph) {
  std::string frame;
  fields.ReadRequired(key, &frame);
  if (!graph.HasFrame(frame)) {
    fields.Fail(key, ": frame '" + frame +
                         "' is not listed in frames; add it there or fix the name (frames: " +
                         Joined(graph.Frames()) + ")");
  }
  return frame;
}

EdgeProvenance ProvenanceOf(Fields& parent) {
  EdgeProvenance p;
  Fields f = parent.Sub("provenance");
  f.Known({"tool", "date", "input_digest", "residual_summary"});
  f.Done();
  f.Read("tool", &p.tool);
  f.Read("date", &p.date);
  f.Read("input_digest", &p.input_digest);
  f.Read("residual_summary", &p.residual_summary);
  return p;
}

void ReadFrames(Fields& top, FrameGraph& graph) {
  std::vector<std::string> frames;
  top.ReadRequired("frames", &frames);
  const YAML::Node list = top.node()["frames"];
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const std::string at = "field 'frames[" + std::to_string(i) + "]': ";
    if (graph.HasFrame(frames[i])) {
      top.FailAt(list[i], at + "frame '" + frames[i] + "' is listed twice in frames");
    }
    try {
      graph.AddFrame(frames[i]);
    } catch (const InputError& e) {
      top.FailAt(list[i], at + e.what());
    }
  }
}

DhJoint ReadJoint(Fields& j) {
  j.Known({"a_mm", "alpha_rad", "d_mm", "theta_offset_rad", "joint_offset_rad"});
  j.Done();
  DhJoint row;
  j.ReadRequired("a_mm", &row.a_mm);
  j.ReadRequired("alpha_rad", &row.alpha_rad);
  j.ReadRequired("d_mm", &row.d_mm);
  j.Read("theta_offset_rad", &row.theta_offset_rad);
  j.Read("joint_offset_rad", &row.joint_offset_rad);
  return row;
}

void ReadRobots(Fields& top, FrameGraph& graph) {
  Fields robots = top.Sub("robots");
  const std::vector<std::string> names = robots.Keys();
  for (const std::string& name : names) robots.Known(name.c_str());
  robots.Done();  // a robot declared twice
  for (const std::string& name : names) {
    Fields robot = robots.Sub(name.c_str());
    robot.Known({"model", "convention", "base_from_chain", "chain_from_flange", "joints"});
    robot.Done();
    std::string model;
    robot.ReadRequired("model", &model);
    if (model != "dh") {
      robot.Fail("model", ": unknown model '" + model + "'; this lasercell reads model: dh");
    }
    std::string convention;
    robot.ReadRequired("convention", &convention);
    if (convention != "standard" && convention != "modified") {
      robot.Fail("convention",
                 ": unknown convention '" + convention + "'; expected standard or modified");
    }
    QuaternionPose base_from_chain, chain_from_flange;  // identity when absent
    robot.ReadPose("base_from_chain", &base_from_chain);
    robot.ReadPose("chain_from_flange", &chain_from_flange);
    if (!robot.Has("joints")) robot.Fail("joints", "is required");
    std::vector<DhJoint> rows;
    for (Fields& j : robot.List("joints")) rows.push_back(ReadJoint(j));
    try {
      graph.SetRobot(name, DhChain(convention == "standard" ? DhConvention::kStandard
                                                            : DhConvention::kModified,
                                   std::move(rows), base_from_chain, chain_from_flange));
    } catch (const InputError& e) {
      robot.FailHere(std::string(": ") + e.what());
    }
  }
}

void ReadLaserPlanes(Fields& top, FrameGraph& graph) {
  Fields section = top.Sub("laser_planes");
  section.Known({"version", "planes"});
  section.Done();
  section.RequireVersion(kLaserPlanesSectionVersion, "laser_planes");
  if (!section.Has("planes")) section.Fail("planes", "is required");
  Fields planes = section.Sub("planes");
  const std::vector<std::string> names = planes.Keys();
  for (const std::string& name : names) planes.Known(name.c_str());
  planes.Done();  // a plane listed twice
  for (const std::string& name : names) {
    Fields f = planes.Sub(name.c_str());
    f.Known({"frame", "normal", "point_mm", "covariance", "camera_covariance", "error_modes",
             "provenance"});
    f.Done();
    LaserPlaneEntry plane;
    plane.frame = FrameOf(f, "frame", graph);
    f.ReadRequired("normal", &plane.normal);
    f.ReadRequired("point_mm", &plane.point_mm);
    Eigen::Matrix4d covariance;
    if (f.Read("covariance", &covariance)) plane.covariance = covariance;
    if (f.Read("camera_covariance", &covariance)) plane.camera_covariance = covariance;
    if (f.Has("error_modes")) {
      for (Fields& m : f.List("error_modes")) {
        m.Known({"intrinsics_step", "plane_step"});
        m.Done();
        SensorErrorMode mode;
        m.Read("intrinsics_step", &mode.intrinsics_step);
        m.ReadRequired("plane_step", &mode.plane_step);
        plane.error_modes.push_back(std::move(mode));
      }
    }
    plane.provenance = ProvenanceOf(f);
    try {
      graph.SetLaserPlane(name, plane);
    } catch (const InputError& e) {
      f.FailHere(std::string(": ") + e.what());
    }
  }
}

/// An edge's sensor_response: {laser, plane_digest, columns: 6 values per error mode}.
SensorModeResponse ReadSensorResponse(Fields& edge) {
  Fields f = edge.Sub("sensor_response");
  f.Known({"laser", "plane_digest", "columns"});
  f.Done();
  SensorModeResponse r;
  f.ReadRequired("laser", &r.laser);
  f.ReadRequired("plane_digest", &r.plane_digest);
  std::vector<double> values;
  f.ReadRequired("columns", &values);
  if (values.empty() || values.size() % 6 != 0) {
    f.Fail("columns", "holds " + std::to_string(values.size()) +
                          " values; expected 6 per error mode (rotation rad, translation mm)");
  }
  r.columns = Eigen::Map<const Eigen::Matrix<double, 6, Eigen::Dynamic>>(
      values.data(), 6, static_cast<Eigen::Index>(values.size() / 6));
  return r;
}

/// Rejects the fields an edge of this type does not have (after the check for typos).
void CheckTypeFields(const Fields& edge, std::initializer_list<const char*> allowed) {
  Fields specific(edge.node(), edge.path(), edge.file(), yaml::ErrorKind::kFile);
  specific.Known(allowed);
  specific.Done();
}

void ReadEdges(Fields& top, FrameGraph& graph) {
  std::vector<std::pair<std::string, std::string>> pairs;  // per edge, for duplicates
  std::vector<std::string> robots_used;                    // per edge ("" when static)
  std::vector<Fields> edges = top.List("edges");
  for (std::size_t i = 0; i < edges.size(); ++i) {
    Fields& edge = edges[i];
    edge.Known({"parent", "child", "type", "parent_from_child", "covariance", "sensor_response",
                "provenance", "robot"});
    edge.Done();
    std::string type;
    edge.ReadRequired("type", &type);
    const std::string parent = FrameOf(edge, "parent", graph);
    const std::string child = FrameOf(edge, "child", graph);
    for (std::size_t j = 0; j < pairs.size(); ++j) {
      if ((pairs[j].first == parent && pairs[j].second == child) ||
          (pairs[j].first == child && pairs[j].second == parent)) {
        edge.FailHere("would create a cycle: " + parent + " and " + child +
                      " are already joined by edges[" + std::to_string(j) + "]; keep only one");
      }
    }
    pairs.emplace_back(parent, child);
    if (type == "static") {
      CheckTypeFields(edge, {"parent", "child", "type", "parent_from_child", "covariance",
                             "sensor_response", "provenance"});
      robots_used.emplace_back();
      StaticEdge s;
      s.parent = parent;
      s.child = child;
      edge.ReadRequiredPose("parent_from_child", &s.parent_from_child);
      Matrix6d covariance;
      if (edge.Read("covariance", &covariance)) s.covariance = covariance;
      if (edge.Has("sensor_response")) s.sensor_response = ReadSensorResponse(edge);
      s.provenance = ProvenanceOf(edge);
      try {
        graph.SetStaticEdge(s);
      } catch (const InputError& e) {
        edge.FailHere(std::string(": ") + e.what());
      }
    } else if (type == "dynamic") {
      CheckTypeFields(edge, {"parent", "child", "type", "robot"});
      std::string robot;
      edge.ReadRequired("robot", &robot);
      const std::vector<std::string> declared = graph.Robots();
      if (std::find(declared.begin(), declared.end(), robot) == declared.end()) {
        edge.Fail("robot", ": robot '" + robot +
                               "' is not declared under robots; declare it or fix the name "
                               "(declared robots: " +
                               Joined(declared) + ")");
      }
      const auto used = std::find(robots_used.begin(), robots_used.end(), robot);
      if (used != robots_used.end()) {
        edge.Fail("robot", ": robot '" + robot + "' already drives edges[" +
                               std::to_string(used - robots_used.begin()) +
                               "]; a robot drives exactly one edge (base -> flange)");
      }
      robots_used.push_back(robot);
      try {
        graph.SetDynamicEdge({parent, child, robot});
      } catch (const InputError& e) {
        edge.FailHere(std::string(": ") + e.what());
      }
    } else {
      edge.Fail("type", ": unknown type '" + type + "'; expected static or dynamic");
    }
  }
}

FrameGraph ReadCell(const YAML::Node& root, const std::string& name) {
  const std::string starts =
      "; expected a lasercell cell file starting with 'format: " + std::string(kCellFormatName) +
      "'";
  if (!root.IsDefined() || root.IsNull()) throw FileError(name, "is empty" + starts);
  if (!root.IsMap()) {
    throw FileError(name, std::string("is not a mapping at the top level (it is ") +
                              (root.IsSequence() ? "a list" : "'" + root.Scalar() + "'") + ")" +
                              starts);
  }
  Fields top(root, "", name, yaml::ErrorKind::kFile);
  top.RequireFormat(kCellFormatName, kCellFormatVersion, "is this a lasercell cell file?");
  top.Known({"format", "version", "frames", "robots", "edges", "laser_planes"});
  top.Done();
  FrameGraph graph;
  ReadFrames(top, graph);
  ReadRobots(top, graph);
  ReadEdges(top, graph);
  if (top.Has("laser_planes")) ReadLaserPlanes(top, graph);
  return graph;
}

}  // namespace

FrameGraph FrameGraphFromYaml(const std::string& text, const std::string& name) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw FileError(name, "YAML syntax error at line " + std::to_string(e.mark.line + 1) +
                              ", column " + std::to_string(e.mark.column + 1) + ": " + e.msg +
                              "; fix the syntax");
  }
  try {
    return ReadCell(root, name);
  } catch (const YAML::Exception& e) {
    const std::string line = e.mark.is_null() ? "" : " at line " + std::to_string(e.mark.line + 1);
    throw FileError(name, "cannot read the YAML" + line + ": " + e.msg);
  }
}

FrameGraph LoadFrameGraph(const std::string& path) {
  return FrameGraphFromYaml(io::ReadFileBytes(path), path);
}

}  // namespace lasercell
