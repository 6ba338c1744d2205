// `lasercell scan triangulate`: laser profiles (.lcp) + camera model + laser plane -> a sweep
// point cloud (PLY, binary little-endian) in the sensor frame (a static sensor, or for a linear
// constant-velocity sweep the sensor frame at the sweep's t0) or a frame of the cell (robot
// joints in the profiles, or a linear sweep placed through static edges of cell.yaml).
//
// Laser plane, first found of: --laser-plane 'nx,ny,nz,d' (sensor frame, n . p + d = 0, mm);
// --sensor-truth FILE (the simulator's truth/sensor.yaml, datasets ReadSensorTruth); cell.yaml's
// `laser_planes` section (written by `lasercell calibrate laser`; NAME from --laser, default
// "laser"). The choice and the frame checks are triangulation::ScanSetupFromCell.
#include <chrono>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "calib/camera_model.hpp"
#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/io/point_cloud_io.hpp"
#include "datasets/simulate_records.hpp"
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

// The laser plane given on the command line or by the simulator's truth, if any.
triangulation::LaserPlaneSource PlaneSource(const ScanArgs& args) {
  triangulation::LaserPlaneSource source;
  source.laser = args.laser;
  if (!args.laser_plane.empty()) {
    if (args.laser_plane.size() != 4) {
      throw OptionError(
          "--laser-plane takes four numbers nx,ny,nz,d (n . p + d = 0, sensor frame, mm)");
    }
    source.plane = Eigen::Vector4d(args.laser_plane[0], args.laser_plane[1], args.laser_plane[2],
                                   args.laser_plane[3]);
    source.plane_label = "--laser-plane";
  } else if (!args.sensor_truth.empty()) {
    source.plane = datasets::ReadSensorTruth(args.sensor_truth).LaserPlane();
    source.plane_label = args.sensor_truth;
  } else if (args.cell.empty()) {
    throw OptionError(
        "no laser plane: give --cell CELL.yaml (with a calibrated laser plane), "
        "--laser-plane nx,ny,nz,d or --sensor-truth truth/sensor.yaml");
  }
  return source;
}

void RunTriangulate(const ScanArgs& args) {
  if (args.fast && args.exact) throw OptionError("--fast and --exact exclude each other");
  if (!args.velocity.empty() && args.velocity.size() != 3) {
    throw OptionError("--velocity-mm-s takes three numbers vx,vy,vz (mm/s, sensor frame at t0)");
  }
  if (!args.frame.empty() && args.cell.empty()) {
    throw OptionError("--frame needs --cell CELL.yaml (the frame graph)");
  }
  std::optional<FrameGraph> graph;
  if (!args.cell.empty()) graph = LoadFrameGraph(args.cell);

  triangulation::SweepOptions options;
  options.path = args.exact ? triangulation::TriangulationPath::kExact
                            : triangulation::TriangulationPath::kFast;
  options.threads = args.threads;
  if (args.have_t0) options.t0_ns = args.t0_ns;
  options.target_frame = args.frame;
  if (!args.velocity.empty()) {
    options.motion = triangulation::SweepMotion::kLinear;
    options.velocity_mm_s = Eigen::Vector3d(args.velocity[0], args.velocity[1], args.velocity[2]);
  } else if (!args.frame.empty()) {
    options.motion = triangulation::SweepMotion::kRobot;
  }
  const FrameGraph* cell = graph ? &*graph : nullptr;
  const triangulation::ScanSetup setup =
      triangulation::ScanSetupFromCell(cell, args.cell, PlaneSource(args), options);

  const calib::CameraModel camera = calib::LoadCameraModel(args.camera);
  const triangulation::ProfileSet profiles = triangulation::ReadProfiles(args.profiles);
  const triangulation::Triangulator tri(camera, setup.laser_plane);
  const auto start = std::chrono::steady_clock::now();
  const triangulation::SweepResult result =
      triangulation::AssembleSweep(profiles, tri, setup.options, cell);
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  io::WritePointCloud(args.out, result.cloud);
  if (!args.quiet) {
    std::printf("%s; laser plane from %s; %s path, %.1f ms -> %s\n", result.Summary().c_str(),
                setup.laser_plane_source.c_str(), args.exact ? "exact" : "fast", ms,
                args.out.c_str());
  }
}

}  // namespace

void AddScanCommands(CLI::App& app) {
  CLI::App* scan = app.add_subcommand("scan", "Turn laser profiles into calibrated 3D sweeps");
  scan->require_subcommand(1);
  CLI::App* tri = scan->add_subcommand(
      "triangulate",
      "Profiles (.lcp) + camera + laser plane -> point cloud (PLY) in the sensor frame (with "
      "--velocity-mm-s: the sensor at t0) or a cell frame (--frame)");
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
  tri->add_option(
      "--frame", args->frame,
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
  AddScanRecordCommand(*scan);
}

}  // namespace lasercell::tools
