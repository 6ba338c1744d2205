// `lasercell scan triangulate`: laser profiles (.lcp) + camera model + laser plane -> a sweep
// point cloud (PLY, binary little-endian) in the sensor frame, the sensor frame at t0 (linear
// constant-velocity sweep) or a frame of the cell (robot joints in the profiles + cell.yaml).
//
// Laser plane, first found of: --laser-plane 'nx,ny,nz,d' (sensor frame, n . p + d = 0, mm);
// --sensor-truth FILE (the simulator's truth/sensor.yaml: laser_plane_in_sensor {normal,
// d_mm}); cell.yaml's `laser_planes: {version: 1, planes: {NAME: {frame: sensor, normal,
// point_mm}}}` section (written by `lasercell calibrate laser`; NAME from --laser, default
// "laser"). The section is read here with yaml-cpp and stripped before the frame graph is
// parsed, so this works whether or not core's cell reader knows the section.
#include <yaml-cpp/yaml.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "calib/camera_model.hpp"
#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/io/file_util.hpp"
#include "core/io/point_cloud_io.hpp"
#include "tools/commands.hpp"
#include "triangulation/profile_io.hpp"
#include "triangulation/sweep.hpp"
#include "triangulation/triangulator.hpp"

namespace lasercell::tools {
namespace {

struct ScanArgs {
  std::string cell, camera, profiles, out, sensor_truth, frame, laser = "laser";
  std::vector<double> laser_plane, velocity;
  long long t0_ns = 0;
  bool have_t0 = false;
  bool fast = false, exact = false, quiet = false;
  int threads = 1;
};

std::string ReadText(const std::string& path) { return io::ReadFileBytes(path); }

Eigen::Vector3d Vec3(const YAML::Node& node, const std::string& file, const std::string& what) {
  if (!node || !node.IsSequence() || node.size() != 3) {
    throw FileError(file, what + " must be a list of 3 numbers");
  }
  try {
    return {node[0].as<double>(), node[1].as<double>(), node[2].as<double>()};
  } catch (const YAML::Exception&) {
    throw FileError(file, what + " must hold numbers");
  }
}

YAML::Node LoadYaml(const std::string& path) {
  try {
    return YAML::Load(ReadText(path));
  } catch (const YAML::Exception& e) {
    throw FileError(path, std::string("is not valid YAML: ") + e.what());
  }
}

// (n, d) from the simulator's truth/sensor.yaml.
Eigen::Vector4d PlaneFromSensorTruth(const std::string& path) {
  const YAML::Node root = LoadYaml(path);
  if (!root["format"] || root["format"].as<std::string>() != "lasercell.sim_sensor") {
    throw FileError(path, "is not a simulator sensor truth file (format: lasercell.sim_sensor)");
  }
  const YAML::Node plane = root["laser_plane_in_sensor"];
  if (!plane || !plane["d_mm"]) {
    throw FileError(path, "has no laser_plane_in_sensor {normal, d_mm}");
  }
  const Eigen::Vector3d n = Vec3(plane["normal"], path, "laser_plane_in_sensor.normal");
  return {n.x(), n.y(), n.z(), plane["d_mm"].as<double>()};
}

// (n, d) from cell.yaml's laser_planes section (core FrameGraph reads and checks it).
Eigen::Vector4d PlaneFromCell(const FrameGraph& graph, const std::string& path,
                              const std::string& name) {
  const auto it = graph.laser_planes().find(name);
  if (it == graph.laser_planes().end()) {
    throw FileError(path, graph.laser_planes().empty()
                              ? std::string("has no laser_planes section; run `lasercell "
                                            "calibrate laser` or give --laser-plane nx,ny,nz,d")
                              : "has no laser plane named '" + name + "' in laser_planes.planes");
  }
  const LaserPlaneEntry& plane = it->second;
  if (plane.frame != "sensor") {
    throw FileError(path, "laser plane '" + name + "' is given in frame '" + plane.frame +
                              "'; scan triangulate needs it in 'sensor' (the camera frame)");
  }
  return {plane.normal.x(), plane.normal.y(), plane.normal.z(), plane.OffsetMm()};
}

void RunTriangulate(const ScanArgs& args) {
  if (args.fast && args.exact) throw OptionError("--fast and --exact exclude each other");
  if (!args.velocity.empty() && args.velocity.size() != 3) {
    throw OptionError("--velocity-mm-s takes three numbers vx,vy,vz (mm/s, sensor frame at t0)");
  }
  FrameGraph graph;
  if (!args.cell.empty()) graph = LoadFrameGraph(args.cell);

  Eigen::Vector4d plane;
  std::string plane_source;
  if (!args.laser_plane.empty()) {
    if (args.laser_plane.size() != 4) {
      throw OptionError(
          "--laser-plane takes four numbers nx,ny,nz,d (n . p + d = 0, sensor frame, mm)");
    }
    plane = Eigen::Vector4d(args.laser_plane[0], args.laser_plane[1], args.laser_plane[2],
                            args.laser_plane[3]);
    plane_source = "--laser-plane";
  } else if (!args.sensor_truth.empty()) {
    plane = PlaneFromSensorTruth(args.sensor_truth);
    plane_source = args.sensor_truth;
  } else if (!args.cell.empty()) {
    plane = PlaneFromCell(graph, args.cell, args.laser);
    plane_source = args.cell;
  } else {
    throw OptionError(
        "no laser plane: give --cell CELL.yaml (with a calibrated laser plane), "
        "--laser-plane nx,ny,nz,d or --sensor-truth truth/sensor.yaml");
  }

  const calib::CameraModel camera = calib::LoadCameraModel(args.camera);
  const triangulation::ProfileSet profiles = triangulation::ReadProfiles(args.profiles);
  const triangulation::Triangulator tri(camera, plane);

  triangulation::SweepOptions options;
  options.path = args.exact ? triangulation::TriangulationPath::kExact
                            : triangulation::TriangulationPath::kFast;
  options.threads = args.threads;
  if (args.have_t0) options.t0_ns = args.t0_ns;
  if (!args.frame.empty() && args.cell.empty()) {
    throw OptionError("--frame needs --cell CELL.yaml (the frame graph)");
  }
  // A linear sweep placed in a cell frame goes through static edges only (e.g. the
  // handling_base <- sensor edge of `calibrate spheres`, valid for this sweep trajectory).
  std::optional<Eigen::Isometry3d> frame_from_sensor_t0;
  if (!args.velocity.empty()) {
    options.motion = triangulation::SweepMotion::kLinear;
    options.velocity_mm_s = Eigen::Vector3d(args.velocity[0], args.velocity[1], args.velocity[2]);
    if (!args.frame.empty()) {
      const std::vector<std::string> robots = graph.RobotsOnPath(args.frame, "sensor");
      if (!robots.empty()) {
        throw OptionError("--frame " + args.frame + " with --velocity-mm-s: the path from 'sensor' "
                          "passes robot '" + robots.front() + "'; a linear sweep is placed "
                          "through static edges only (calibrate spheres writes one)");
      }
      frame_from_sensor_t0 = graph.Transform(args.frame, "sensor");
    }
  } else if (!args.frame.empty()) {
    options.motion = triangulation::SweepMotion::kRobot;
    options.target_frame = args.frame;
  }
  const auto start = std::chrono::steady_clock::now();
  triangulation::SweepResult result = triangulation::AssembleSweep(
      profiles, tri, options,
      options.motion == triangulation::SweepMotion::kRobot ? &graph : nullptr);
  if (frame_from_sensor_t0) {
    for (Eigen::Vector3d& p : result.cloud.positions) p = *frame_from_sensor_t0 * p;
    for (Eigen::Vector3d& n : result.cloud.normals) n = frame_from_sensor_t0->linear() * n;
  }
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  io::WritePointCloud(args.out, result.cloud);
  if (!args.quiet) {
    const std::string placed =
        frame_from_sensor_t0 ? "; placed in '" + args.frame + "' through static edges" : "";
    std::printf("%s%s; laser plane from %s; %s path, %.1f ms -> %s\n", result.Summary().c_str(),
                placed.c_str(), plane_source.c_str(), args.exact ? "exact" : "fast", ms,
                args.out.c_str());
  }
}

}  // namespace

void AddScanCommands(CLI::App& app) {
  CLI::App* scan = app.add_subcommand("scan", "Turn laser profiles into calibrated 3D sweeps");
  scan->require_subcommand(1);
  CLI::App* tri = scan->add_subcommand(
      "triangulate",
      "Profiles (.lcp) + camera + laser plane -> point cloud (PLY) in the sensor frame, the "
      "sensor frame at t0 (--velocity-mm-s) or a cell frame (--frame, robot joints)");
  auto args = std::make_shared<ScanArgs>();
  tri->add_option("--camera", args->camera, "Camera model (.cameramodel, mrcal)")->required();
  tri->add_option("--profiles", args->profiles, "Laser profiles (.lcp)")->required();
  tri->add_option("--out", args->out, "Output point cloud (.ply binary LE, or .pcd)")->required();
  tri->add_option("--cell", args->cell,
                  "cell.yaml: frame graph (for --frame) and laser plane (laser_planes section)");
  tri->add_option("--laser", args->laser, "Name of the laser plane in cell.yaml")
      ->capture_default_str();
  tri->add_option("--laser-plane", args->laser_plane,
                  "Laser plane nx,ny,nz,d (n . p + d = 0 in the sensor frame, mm; write "
                  "--laser-plane=... when nx is negative); overrides --cell")
      ->delimiter(',');
  tri->add_option("--sensor-truth", args->sensor_truth,
                  "Laser plane from the simulator's truth/sensor.yaml; overrides --cell");
  tri->add_option("--velocity-mm-s", args->velocity,
                  "Linear sweep: sensor velocity vx,vy,vz in mm/s (sensor frame at t0; write "
                  "--velocity-mm-s=... when vx is negative)")
      ->delimiter(',');
  tri->add_option("--frame", args->frame,
                  "Express points in this cell frame: robot sweep (each profile posed by its joints "
                  "through cell.yaml, e.g. vision_base), or with --velocity-mm-s a linear sweep "
                  "placed through static edges (e.g. handling_base after calibrate spheres)");
  tri->add_option("--t0-ns", args->t0_ns,
                  "Linear sweep time origin (sensor clock, ns); default: the first profile's")
      ->each([args](const std::string&) { args->have_t0 = true; });
  tri->add_flag("--fast", args->fast, "Lookup-table triangulation (default)");
  tri->add_flag("--exact", args->exact, "mrcal unprojection of every peak");
  tri->add_option("--threads", args->threads, "Worker threads (0 = all cores)")
      ->check(CLI::NonNegativeNumber);
  tri->add_flag("--quiet", args->quiet, "No summary line");
  tri->callback([args] { RunTriangulate(*args); });
}

}  // namespace lasercell::tools
