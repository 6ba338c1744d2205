// `lasercell frames show CELL.yaml` and `lasercell frames get CELL.yaml --to A --from B`.
#include <charconv>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "tools/commands.hpp"

namespace lasercell::tools {
namespace {

// Undirected adjacency for printing: neighbour frame and a description of the edge.
struct Link {
  std::string to;
  std::string text;
};

// Four significant digits: enough for an uncertainty.
std::string Short(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

std::string DescribeStatic(const StaticEdge& e, bool forward) {
  std::string text =
      "static " + e.parent + "_from_" + e.child + " = " + PoseToFileNotation(e.parent_from_child);
  if (!forward) text += " (edge stored in the other direction)";
  const auto& p = e.provenance;
  if (!p.tool.empty() || !p.date.empty()) {
    text += "\n      by: " + p.tool + (p.tool.empty() || p.date.empty() ? "" : ", ") + p.date;
  }
  if (!p.residual_summary.empty()) text += "\n      residuals: " + p.residual_summary;
  if (!p.input_digest.empty()) text += "\n      inputs: " + p.input_digest;
  if (e.covariance) {
    const auto& c = *e.covariance;
    text += "\n      1-sigma: rotation [";
    for (int i = 0; i < 3; ++i) {
      text += (i ? ", " : "") + Short(std::sqrt(std::max(0.0, c(i, i))) * 180.0 / M_PI);
    }
    text += "] deg, translation [";
    for (int i = 3; i < 6; ++i) {
      text += (i > 3 ? ", " : "") + Short(std::sqrt(std::max(0.0, c(i, i))));
    }
    text += "] mm";
  }
  return text;
}

void PrintTree(const FrameGraph& graph, const std::string& frame, const std::string& indent,
               std::map<std::string, std::vector<Link>>& links, std::set<std::string>& seen) {
  for (const Link& link : links[frame]) {
    if (seen.count(link.to)) continue;
    seen.insert(link.to);
    // Detail lines (provenance, 1-sigma) line up under the edge they describe.
    std::string text = link.text;
    for (std::size_t pos = 0; (pos = text.find('\n', pos)) != std::string::npos; pos += 1) {
      text.insert(pos + 1, indent + "   ");
    }
    std::printf("%s+- %s: %s\n", indent.c_str(), link.to.c_str(), text.c_str());
    PrintTree(graph, link.to, indent + "   ", links, seen);
  }
}

void Show(const std::string& path) {
  const FrameGraph graph = LoadFrameGraph(path);
  std::map<std::string, std::vector<Link>> links;
  std::set<std::string> children;
  for (const auto& e : graph.static_edges()) {
    links[e.parent].push_back({e.child, DescribeStatic(e, true)});
    links[e.child].push_back({e.parent, DescribeStatic(e, false)});
    children.insert(e.child);
  }
  for (const auto& e : graph.dynamic_edges()) {
    const std::string text = "dynamic " + e.parent + "_from_" + e.child + ": robot '" + e.robot +
                             "' (" + graph.Robot(e.robot).TypeName() + ", " +
                             std::to_string(graph.Robot(e.robot).NumJoints()) + " joints)";
    links[e.parent].push_back({e.child, text});
    links[e.child].push_back({e.parent, text + " (reversed)"});
    children.insert(e.child);
  }
  std::printf("cell %s: %zu frames, %zu static edges, %zu dynamic edges, robots:", path.c_str(),
              graph.Frames().size(), graph.static_edges().size(), graph.dynamic_edges().size());
  for (const auto& r : graph.Robots()) std::printf(" %s", r.c_str());
  std::printf("\n");
  std::set<std::string> seen;
  // Roots first (frames that are nobody's child), then anything left (other trees).
  std::vector<std::string> order;
  for (const auto& f : graph.Frames())
    if (!children.count(f)) order.push_back(f);
  for (const auto& f : graph.Frames()) order.push_back(f);
  for (const auto& f : order) {
    if (seen.count(f)) continue;
    seen.insert(f);
    std::printf("%s\n", f.c_str());
    PrintTree(graph, f, "", links, seen);
  }
}

std::vector<double> ParseNumberList(const std::string& text, const std::string& what) {
  std::vector<double> values;
  const char* p = text.data();
  const char* end = p + text.size();
  while (p < end) {
    double v = 0;
    const auto [next, ec] = std::from_chars(p, end, v);
    if (ec != std::errc() || !std::isfinite(v)) {
      throw InputError(what + " '" + text + "': expected comma-separated numbers (radians)");
    }
    values.push_back(v);
    p = next;
    if (p < end) {
      if (*p != ',') throw InputError(what + " '" + text + "': expected ',' between numbers");
      ++p;
    }
  }
  return values;
}

struct GetArgs {
  std::string path, to, from;
  std::vector<std::string> joints;
  bool matrix = false;
};

void Get(const GetArgs& args) {
  const FrameGraph graph = LoadFrameGraph(args.path);
  const std::vector<std::string> robots = graph.RobotsOnPath(args.to, args.from);
  JointValues joints;
  for (const std::string& spec : args.joints) {
    const auto eq = spec.find('=');
    if (eq == std::string::npos) {
      if (robots.size() != 1) {
        throw InputError("--joints '" + spec + "': " + std::to_string(robots.size()) +
                         " robots lie on the path; write --joints ROBOT=j1,j2,...");
      }
      joints[robots[0]] = ParseNumberList(spec, "--joints");
    } else {
      joints[spec.substr(0, eq)] = ParseNumberList(spec.substr(eq + 1), "--joints");
    }
  }
  const Eigen::Isometry3d pose = graph.Transform(args.to, args.from, joints);
  std::printf("%s_from_%s: %s\n", args.to.c_str(), args.from.c_str(),
              PoseToFileNotation(pose).c_str());
  if (args.matrix) {
    const Eigen::Matrix4d m = pose.matrix();
    for (int r = 0; r < 4; ++r) {
      std::printf("  [%s, %s, %s, %s]\n", FormatDouble(m(r, 0)).c_str(),
                  FormatDouble(m(r, 1)).c_str(), FormatDouble(m(r, 2)).c_str(),
                  FormatDouble(m(r, 3)).c_str());
    }
  }
}

}  // namespace

void AddFramesCommands(CLI::App& app) {
  CLI::App* frames = app.add_subcommand("frames", "Inspect the cell's frame graph (cell.yaml)");
  frames->require_subcommand(1);

  CLI::App* show = frames->add_subcommand("show", "Print the frame tree with edge provenance");
  auto show_path = std::make_shared<std::string>();
  show->add_option("CELL", *show_path, "cell.yaml")->required();
  show->callback([show_path] { Show(*show_path); });

  CLI::App* get = frames->add_subcommand(
      "get", "Print TO_from_FROM (p_in_TO = T * p_in_FROM) in the file notation");
  auto args = std::make_shared<GetArgs>();
  get->add_option("CELL", args->path, "cell.yaml")->required();
  get->add_option("--to", args->to, "Target frame")->required();
  get->add_option("--from", args->from, "Source frame")->required();
  get->add_option("--joints", args->joints,
                  "Joint values in rad: j1,j2,... or ROBOT=j1,j2,... (repeat per robot)");
  get->add_flag("--matrix", args->matrix, "Also print the 4x4 matrix (mm)");
  get->callback([args] { Get(*args); });
}

}  // namespace lasercell::tools
