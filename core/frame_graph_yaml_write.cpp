// cell.yaml writing (format "lasercell.cell", version 1; the reader is frame_graph_yaml_read.cpp).
//
// Writing is by hand, so the text is deterministic: frames sorted, robots sorted, static edges
// in insertion order followed by dynamic edges in insertion order; numbers by FormatDouble
// (shortest text that reads back to the same double); strings double-quoted and escaped.
//
// Static edges and robots' mounts (DhChain) hold the file's quaternions and translations
// (QuaternionPose), which are written as they are: reading them back gives the same doubles,
// and writing again the same text.

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <vector>

#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/io/file_util.hpp"
#include "core/yaml_fields.hpp"

namespace lasercell {

namespace {

/// Names plain when they are lower snake case (and not YAML's `null`), quoted otherwise.
std::string NameToken(const std::string& name) {
  const bool plain = !name.empty() && name != "null" && name[0] >= 'a' && name[0] <= 'z' &&
                     std::all_of(name.begin(), name.end(), [](char c) {
                       return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
                     });
  return plain ? name : yaml::Quoted(name);
}

/// FormatDouble for the writer: refuses non-finite values, naming them.
std::string Number(double value, const std::string& what) {
  if (!std::isfinite(value)) {
    throw InputError("cannot write " + what + ": the value is not finite (" +
                     std::to_string(value) + "); fix it before saving");
  }
  return FormatDouble(value);
}

/// PoseToFileNotation for the writer: refuses a pose with non-finite entries, naming it.
std::string Pose(const QuaternionPose& pose, const std::string& what) {
  if (!pose.rotation.coeffs().allFinite() || !pose.translation_mm.allFinite()) {
    throw InputError("cannot write " + what + ": the pose is not finite; fix it before saving");
  }
  return PoseToFileNotation(pose);
}

void WriteRobot(std::string& out, const std::string& name, const KinematicModel& model) {
  const auto* chain = dynamic_cast<const DhChain*>(&model);
  if (chain == nullptr) {
    throw InputError("cannot write robot '" + name + "': its kinematic model type '" +
                     model.TypeName() + "' has no cell-file form (this lasercell writes 'dh')");
  }
  const std::string what = "robot '" + name + "'";
  out += "  " + NameToken(name) + ":\n    model: dh\n";
  out += std::string("    convention: ") +
         (chain->convention() == DhConvention::kStandard ? "standard" : "modified") + "\n";
  out += "    base_from_chain: " + Pose(chain->base_from_chain_stored(), what) + "\n";
  out += "    chain_from_flange: " + Pose(chain->chain_from_flange_stored(), what) + "\n";
  if (chain->joints().empty()) {
    out += "    joints: []\n";
    return;
  }
  out += "    joints:\n";
  for (std::size_t i = 0; i < chain->joints().size(); ++i) {
    const DhJoint& j = chain->joints()[i];
    const std::string joint = what + " joint " + std::to_string(i + 1);
    out += "      - {a_mm: " + Number(j.a_mm, joint) +
           ", alpha_rad: " + Number(j.alpha_rad, joint) + ", d_mm: " + Number(j.d_mm, joint) +
           ", theta_offset_rad: " + Number(j.theta_offset_rad, joint) +
           ", joint_offset_rad: " + Number(j.joint_offset_rad, joint) + "}\n";
  }
}

void WriteStaticEdge(std::string& out, const StaticEdge& edge) {
  const std::string what = "static edge " + edge.parent + " <- " + edge.child;
  out += "  - parent: " + NameToken(edge.parent) + "\n    child: " + NameToken(edge.child) +
         "\n    type: static\n    parent_from_child: " + Pose(edge.parent_from_child, what) + "\n";
  if (edge.covariance) {
    out += "    covariance: [";
    for (int r = 0; r < 6; ++r) {
      if (r > 0) out += ",\n                 ";
      for (int c = 0; c < 6; ++c) {
        out += (c > 0 ? ", " : "") + Number((*edge.covariance)(r, c), what + " covariance");
      }
    }
    out += "]\n";
  }
  if (edge.sensor_response) {
    const SensorModeResponse& r = *edge.sensor_response;
    out += "    sensor_response:\n      laser: " + NameToken(r.laser) +
           "\n      plane_digest: " + yaml::Quoted(r.plane_digest) + "\n      columns: [";
    for (Eigen::Index k = 0; k < r.columns.cols(); ++k) {
      if (k > 0) out += ",\n                ";
      for (int i = 0; i < 6; ++i) {
        out += (i > 0 ? ", " : "") + Number(r.columns(i, k), what + " sensor_response");
      }
    }
    out += "]\n";
  }
  const EdgeProvenance& p = edge.provenance;
  out += "    provenance: {tool: " + yaml::Quoted(p.tool) + ", date: " + yaml::Quoted(p.date) +
         ", input_digest: " + yaml::Quoted(p.input_digest) +
         ", residual_summary: " + yaml::Quoted(p.residual_summary) + "}\n";
}

}  // namespace

std::string FormatDouble(double value) {
  std::array<char, 64> buffer{};
  const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
  return std::string(buffer.data(), result.ptr);
}

std::string PoseToFileNotation(const QuaternionPose& pose) {
  const Eigen::Vector3d& t = pose.translation_mm;
  const Eigen::Quaterniond& q = pose.rotation;
  return "{translation_mm: [" + FormatDouble(t.x()) + ", " + FormatDouble(t.y()) + ", " +
         FormatDouble(t.z()) + "], rotation_wxyz: [" + FormatDouble(q.w()) + ", " +
         FormatDouble(q.x()) + ", " + FormatDouble(q.y()) + ", " + FormatDouble(q.z()) + "]}";
}

std::string PoseToFileNotation(const Eigen::Isometry3d& pose) {
  return PoseToFileNotation(QuaternionPose::FromIsometry(pose));
}

std::string FrameGraphToYaml(const FrameGraph& graph) {
  std::string out = std::string("format: ") + kCellFormatName +
                    "\nversion: " + std::to_string(kCellFormatVersion) + "\nframes: [";
  const std::vector<std::string> frames = graph.Frames();
  for (std::size_t i = 0; i < frames.size(); ++i) {
    out += (i > 0 ? ", " : "") + NameToken(frames[i]);
  }
  out += "]\n";
  const std::vector<std::string> robots = graph.Robots();
  out += robots.empty() ? "robots: {}\n" : "robots:\n";
  for (const std::string& robot : robots) {
    WriteRobot(out, robot, graph.Robot(robot));
  }
  const bool no_edges = graph.static_edges().empty() && graph.dynamic_edges().empty();
  out += no_edges ? "edges: []\n" : "edges:\n";
  for (const StaticEdge& edge : graph.static_edges()) WriteStaticEdge(out, edge);
  for (const DynamicEdge& edge : graph.dynamic_edges()) {
    out += "  - parent: " + NameToken(edge.parent) + "\n    child: " + NameToken(edge.child) +
           "\n    type: dynamic\n    robot: " + NameToken(edge.robot) + "\n";
  }
  if (!graph.laser_planes().empty()) {
    out +=
        "laser_planes:\n  version: " + std::to_string(kLaserPlanesSectionVersion) + "\n  planes:\n";
    for (const auto& [name, plane] : graph.laser_planes()) {
      const std::string what = "laser plane '" + name + "'";
      const auto vec = [&](const Eigen::Vector3d& v) {
        std::string text("[");
        for (int k = 0; k < 3; ++k) {
          if (k > 0) text.append(", ");
          text.append(Number(v(k), what));
        }
        text.append("]");
        return text;
      };
      out += "    " + NameToken(name) + ":\n      frame: " + NameToken(plane.frame) +
             "\n      normal: " + vec(plane.normal) + "\n      point_mm: " + vec(plane.point_mm) +
             "\n";
      for (const auto& [key, matrix] : {std::pair{"covariance", &plane.covariance},
                                        std::pair{"camera_covariance", &plane.camera_covariance}}) {
        if (!*matrix) continue;
        const std::string indent(std::string(key).size() + 9, ' ');
        out += "      " + std::string(key) + ": [";
        for (int r = 0; r < 4; ++r) {
          if (r > 0) out += ",\n" + indent;
          for (int c = 0; c < 4; ++c) {
            if (c > 0) out += ", ";
            out += Number((**matrix)(r, c), what + " " + key);
          }
        }
        out += "]\n";
      }
      if (!plane.error_modes.empty()) out += "      error_modes:\n";
      for (const SensorErrorMode& m : plane.error_modes) {
        out += "        - {";
        if (!m.intrinsics_step.empty()) {
          out += "intrinsics_step: [";
          for (std::size_t i = 0; i < m.intrinsics_step.size(); ++i) {
            out += (i > 0 ? ", " : "") + Number(m.intrinsics_step[i], what + " error_modes");
          }
          out += "], ";
        }
        out += "plane_step: [";
        for (int i = 0; i < 4; ++i) {
          out += (i > 0 ? ", " : "") + Number(m.plane_step(i), what + " error_modes");
        }
        out += "]}\n";
      }
      const EdgeProvenance& p = plane.provenance;
      out += "      provenance: {tool: " + yaml::Quoted(p.tool) +
             ", date: " + yaml::Quoted(p.date) + ", input_digest: " + yaml::Quoted(p.input_digest) +
             ", residual_summary: " + yaml::Quoted(p.residual_summary) + "}\n";
    }
  }
  return out;
}

void SaveFrameGraph(const std::string& path, const FrameGraph& graph) {
  std::string text;
  try {
    text = FrameGraphToYaml(graph);  // Complete before anything touches the disk.
  } catch (const FileError&) {
    throw;
  } catch (const InputError& e) {
    throw FileError(path, std::string(e.what()) + "; nothing was written");
  }
  io::WriteFileAtomically(path, text);
}

}  // namespace lasercell
