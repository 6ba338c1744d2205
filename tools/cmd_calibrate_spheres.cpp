// `lasercell calibrate spheres --cell CELL.yaml (--sweep SWEEP.ply | --profiles SPHERES.lcp
//  --camera CAM.cameramodel --velocity-mm-s VX,VY,VZ [--t0-ns T0] [--laser NAME])
//  --touches touches.yaml [--radius-mm R] [--free-radius] [--sweep-frame NAME] [--touch-sigma-mm S]
//  [--radius-tolerance-mm T] [--up X,Y,Z]
//  [--report FILE.html] [--json FILE.json]`
//
// Half-sphere calibration (Skotheim et al. 2012, calibration step 3): segments the half spheres
// out of the sweep, fits them, matches them with the handling robot's touches of their tops and
// sets the static edge handling_base <- SWEEP_FRAME in CELL.yaml (only that edge). SWEEP_FRAME
// defaults to `sensor`: the sweep cloud of a linear sweep is in the sensor frame at the sweep
// start, so the edge is handling_base_from_sensor valid for that sweep trajectory
// (ARCHITECTURE.md, data path 1). The composition, JSON and report are calib's
// (calib/half_sphere_calibration.hpp, calib/half_sphere_report.hpp).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "calib/camera_model.hpp"
#include "calib/half_sphere_calibration.hpp"
#include "calib/half_sphere_report.hpp"
#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/html_report.hpp"
#include "core/io/file_util.hpp"
#include "core/io/point_cloud_io.hpp"
#include "core/json_io.hpp"
#include "tools/commands.hpp"
#include "triangulation/half_sphere_profiles.hpp"
#include "triangulation/profile_io.hpp"

namespace lasercell::tools {
namespace {

struct SpheresArgs {
  std::string cell, sweep, touches, report, json;
  std::string profiles, camera, laser = "laser";  // the sweep as profiles (instead of --sweep)
  std::vector<double> velocity;
  long long t0_ns = 0;
  bool have_t0 = false;
  std::string sweep_frame = "sensor";
  calib::HalfSphereSweepOptions options;  // radius_mm, touch_sigma_mm: 0 = from the touches file
  std::vector<double> up = {0, 0, 1};
};

void Run(SpheresArgs a) {
  FrameGraph graph = LoadFrameGraph(a.cell);
  FrameGraph().AddFrame(a.sweep_frame);  // throws for a name that is not lower snake case
  if (a.up.size() != 3) throw InputError("--up: expected X,Y,Z");
  a.options.up_in_handling_base = Eigen::Vector3d(a.up[0], a.up[1], a.up[2]);
  if (a.sweep.empty() == a.profiles.empty()) {
    throw OptionError("give the sweep as --sweep CLOUD or as --profiles FILE.lcp (one of them)");
  }
  if (!a.profiles.empty() && (a.camera.empty() || a.velocity.size() != 3)) {
    throw OptionError(
        "--profiles needs --camera CAMERA.cameramodel and --velocity-mm-s vx,vy,vz (the linear "
        "sweep, as for scan triangulate)");
  }
  const calib::HalfSphereInputNames names{a.cell, a.sweep.empty() ? a.profiles : a.sweep, a.touches,
                                          a.sweep_frame};
  triangulation::SpheresSweep sweep;
  sweep.laser = a.laser;
  sweep.file = names.sweep;
  PointCloud cloud;
  triangulation::ProfileSet profiles;
  std::optional<calib::CameraModel> camera;
  if (a.sweep.empty()) {  // triangulated through the cell's plane, with its error modes
    sweep.motion.motion = triangulation::SweepMotion::kLinear;
    sweep.motion.velocity_mm_s = Eigen::Vector3d(a.velocity[0], a.velocity[1], a.velocity[2]);
    if (a.have_t0) sweep.motion.t0_ns = a.t0_ns;
    camera = calib::LoadCameraModel(a.camera);
    profiles = triangulation::ReadProfiles(a.profiles);
    sweep.camera = &*camera;
    sweep.profiles = &profiles;
  } else {
    io::ReadReport read;
    cloud = io::ReadPointCloud(a.sweep, &read);
    a.options.sweep_unit_hint = read.unit_hint;
    sweep.cloud = &cloud;
  }
  const triangulation::SpheresInCell out = triangulation::CalibrateSpheresInCell(
      graph, sweep, io::ReadFileBytes(a.touches), a.options, names);
  const calib::HalfSphereSweepResult& run = out.run;
  const StaticEdge& edge = out.edge;
  const bool modes = out.modes_propagated;
  const calib::HalfSphereCalibrationResult& result = run.calibration;
  json::WriteFile(a.json, calib::HalfSphereResultJson(run, names, edge));
  if (!a.report.empty()) report::WriteHtmlReport(a.report, calib::HalfSphereReport(run, names));
  graph.SetStaticEdge(edge);
  SaveFrameGraph(a.cell, graph);
  std::printf("%s\nhandling_base_from_%s: %s\n", result.Summary().c_str(), a.sweep_frame.c_str(),
              PoseToFileNotation(result.handling_base_from_sweep).c_str());
  std::printf("camera and laser plane error modes: %s\n",
              edge.sensor_response ? "propagated (the edge keeps its response to them)"
              : modes              ? "propagated, without a response"
                      : "not propagated (give --profiles and --camera, and a plane with modes)");
  for (const auto& w : result.warnings) std::printf("warning: %s\n", w.c_str());
}

}  // namespace

void AddCalibrateSpheresCommand(CLI::App& calibrate) {
  CLI::App* cmd = calibrate.add_subcommand(
      "spheres",
      "Half spheres: sweep + handling-robot touches of their tops -> handling_base <- sweep "
      "frame in CELL.yaml");
  auto a = std::make_shared<SpheresArgs>();
  cmd->add_option("--cell", a->cell, "cell.yaml to update (only its handling_base edge)")
      ->required();
  cmd->add_option("--sweep", a->sweep, "Sweep cloud (PLY/PCD, mm) in the sweep frame");
  cmd->add_option("--profiles", a->profiles,
                  "Or the sweep's profiles (.lcp), triangulated through --camera and the cell's "
                  "laser plane: the edge then keeps its response to their error modes");
  cmd->add_option("--camera", a->camera, "Camera model (.cameramodel), with --profiles");
  cmd->add_option("--laser", a->laser, "Laser plane of the cell, with --profiles")
      ->capture_default_str();
  cmd->add_option("--velocity-mm-s", a->velocity,
                  "Linear sweep velocity vx,vy,vz (mm/s, sensor frame at t0), with --profiles")
      ->delimiter(',')
      ->expected(3);
  cmd->add_option("--t0-ns", a->t0_ns, "Sweep start (ns; default: the first profile's time)")
      ->each([a](const std::string&) { a->have_t0 = true; });
  cmd->add_option("--touches", a->touches, "Touches file (format lasercell.touches)")->required();
  cmd->add_option("--radius-mm", a->options.radius_mm,
                  "Sphere radius (default: the touches file's sphere_radius_mm)");
  cmd->add_flag("--free-radius", a->options.free_radius,
                "Fit each sphere's radius instead of fixing it to the nominal radius");
  cmd->add_option("--sweep-frame", a->sweep_frame,
                  "Frame of the sweep cloud (default sensor: the sensor at the start of a "
                  "linear sweep)");
  cmd->add_option("--touch-sigma-mm", a->options.touch_sigma_mm,
                  "Per-axis 1-sigma of a touch (default: the file's stated_sigma_mm)");
  cmd->add_option("--radius-tolerance-mm", a->options.radius_tolerance_mm,
                  "+- tolerance of the spheres' radii about the nominal one, counted in the "
                  "covariance (default: the file's sphere_radius_tolerance_mm, else none)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--up", a->up, "Up (against gravity) in handling_base, X,Y,Z (default 0,0,1)")
      ->delimiter(',')
      ->expected(3);
  cmd->add_option("--report", a->report, "HTML report to write");
  cmd->add_option("--json", a->json, "JSON result to write");
  cmd->callback([a] { Run(*a); });
}

}  // namespace lasercell::tools
