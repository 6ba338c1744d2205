// `lasercell calibrate joints` (joint-offset identification of the vision robot
// from sphere sweeps, calib/joint_identification.hpp) and `lasercell calibrate
// handeye-laser` (eye-in-hand laser variant, calib/laser_hand_eye.hpp). Both
// load their problem with triangulation::LoadSphereSweepProblem (the sweep list
// triangulated by the exact path of `scan triangulate`, the robot and the
// flange <-> sensor edge of the cell, optionally the handling robot's touches of
// the sphere tops; up = +z of handling_base unless --up), solve, and update only
// their own parts of CELL.yaml: the robot's DH table (joints) or the
// vision_flange <-> sensor edge (handeye-laser, or joints --with-handeye). JSON
// and report: calib/joint_report.hpp.
//
// The laser plane: --laser-plane nx,ny,nz,d (sensor frame, n . p + d = 0, mm),
// else the cell's calibrated `laser` plane.
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "calib/joint_identification.hpp"
#include "calib/joint_report.hpp"
#include "calib/laser_hand_eye.hpp"
#include "calib/robot_in_cell.hpp"
#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/json_io.hpp"
#include "core/number_list.hpp"
#include "tools/cmd_calibrate_handeye_sections.hpp"
#include "tools/commands.hpp"
#include "triangulation/sphere_sweeps.hpp"

namespace lasercell::tools {
namespace {

// The library's problem spec, its fields bound to the flags, and what only the CLI parses.
struct JointsArgs {
  triangulation::SphereSweepProblemSpec spec;
  std::string report, json, output, laser_plane, up = "0,0,1";
  bool with_handeye = false, dh_deltas = false;
};

// The problem spec with what only the CLI parses (--laser-plane, --up) filled in.
triangulation::SphereSweepProblemSpec Spec(const JointsArgs& a) {
  triangulation::SphereSweepProblemSpec spec = a.spec;
  if (!a.laser_plane.empty()) {
    const std::vector<double> v = ParseNumberList(a.laser_plane, "--laser-plane", 4);
    if (!(Eigen::Vector3d(v[0], v[1], v[2]).norm() > 0)) {
      throw OptionError("--laser-plane: the normal must be non-zero");
    }
    spec.laser_plane = Eigen::Vector4d(v[0], v[1], v[2], v[3]);
  }
  const std::vector<double> up = ParseNumberList(a.up, "--up", 3);
  spec.up = Eigen::Vector3d(up[0], up[1], up[2]);
  return spec;
}

void RunJoints(const JointsArgs& a) {
  const triangulation::JointCalibration c =
      triangulation::CalibrateJointsFromSweeps(Spec(a), a.with_handeye, a.dh_deltas);
  const std::string out = a.output.empty() ? a.spec.cell : a.output;
  SaveFrameGraph(out, c.cell);
  json::WriteFile(a.json, calib::JointCalibrationJson(c.result, c.run));
  if (!a.report.empty())
    report::WriteHtmlReport(a.report, calib::JointCalibrationReport(c.result, c.run));
  std::printf("%s -> %s\n", c.result.Summary().c_str(), out.c_str());
  for (const auto& w : c.result.warnings) std::printf("warning: %s\n", w.c_str());
}

void RunHandEyeLaser(const JointsArgs& a) {
  const triangulation::LaserHandEyeCalibration c =
      triangulation::CalibrateLaserHandEyeFromSweeps(Spec(a));
  const std::string out = a.output.empty() ? a.spec.cell : a.output;
  SaveFrameGraph(out, c.cell);
  json::WriteFile(a.json, calib::LaserHandEyeJson(c.result, c.run));
  if (!a.report.empty())
    report::WriteHtmlReport(a.report, calib::LaserHandEyeReport(c.result, c.run));
  std::printf("%s -> %s\n", c.result.Summary().c_str(), out.c_str());
}

// `required`: --cell, --camera and --sweeps are CLI-required (joints); handeye-laser checks them
// itself because its sections variant needs none of them.
void AddShared(CLI::App* cmd, JointsArgs& a, bool required = true) {
  CLI::Option* cell = cmd->add_option("--cell", a.spec.cell,
                                      "cell.yaml with the robot and the flange<->sensor edge");
  CLI::Option* camera =
      cmd->add_option("--camera", a.spec.camera, "Sensor camera model (.cameramodel)");
  CLI::Option* sweeps =
      cmd->add_option("--sweeps", a.spec.sweeps, "Sphere-sweep list (records/sphere_sweeps.yaml)");
  if (required) {
    cell->required();
    camera->required();
    sweeps->required();
  }
  cmd->add_option("--laser-plane", a.laser_plane,
                  "Laser plane nx,ny,nz,d in the sensor frame (n.p + d = 0, mm); default: the "
                  "cell's calibrated 'laser' plane");
  cmd->add_option("--touches", a.spec.touches,
                  "Sphere tops touched by the handling robot (records/touches.yaml): fixes the "
                  "sphere centres (mapped through the cell), making joint 1 identifiable");
  cmd->add_option("--up", a.up,
                  "With --touches: direction against gravity in handling_base (default 0,0,1); "
                  "centre = touched top - radius * up");
  cmd->add_option("--robot", a.spec.robot, "Robot name in the cell (default vision_robot)");
  cmd->add_option("--sensor-frame", a.spec.sensor_frame, "Sensor frame name (default sensor)");
  cmd->add_option("--point-sigma", a.spec.point_sigma_mm, "A-priori point noise, mm (default 0.1)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--sphere-radius", a.spec.radius_mm,
                  "Initial sphere radius, mm (0: from the data)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option(
         "--max-points", a.spec.max_points_per_sweep,
         "Points per sweep used (default " + std::to_string(a.spec.max_points_per_sweep) + ")")
      ->check(CLI::Range(10, 100000));
  cmd->add_option("--output", a.output, "Write the updated cell here (default: --cell in place)");
  cmd->add_option("--report", a.report, "HTML report");
  cmd->add_option("--json", a.json, "JSON result");
}

}  // namespace

void AddCalibrateJointsCommands(CLI::App& calibrate) {
  CLI::App* joints = calibrate.add_subcommand(
      "joints",
      "Joint offsets (and optionally DH deltas, hand-eye) of the vision robot "
      "from sphere sweeps; updates only the robot model in CELL.yaml");
  auto ja = std::make_shared<JointsArgs>();
  AddShared(joints, *ja);
  joints->add_option("--set", ja->spec.set, "Sweep set in the list (default joint_poses)");
  joints->add_flag("--with-handeye", ja->with_handeye,
                   "Also estimate vision_flange_from_sensor (updates that edge too)");
  joints->add_flag("--dh-deltas", ja->dh_deltas, "Also estimate a, d, alpha of every joint");
  joints->callback([ja] { RunJoints(*ja); });

  CLI::App* he = calibrate.add_subcommand(
      "handeye-laser",
      "Eye-in-hand laser sensor: vision_flange_from_sensor from sphere sweeps "
      "taken from several robot poses (robot model held)");
  auto ha = std::make_shared<JointsArgs>();
  ha->spec = triangulation::LaserHandEyeSpecDefaults();
  AddShared(he, *ha, /*required=*/false);
  he->add_option("--set", ha->spec.set, "Sweep set in the list (default eye_in_hand)");
  auto sa = std::make_shared<HandEyeSectionArgs>();
  AddHandEyeSectionOptions(he, *sa);
  he->callback([ha, sa] {
    if (HandEyeSectionsRequested(*sa)) {
      sa->cell = ha->spec.cell;
      sa->output = ha->output;
      sa->json = ha->json;
      sa->report = ha->report;
      sa->robot = ha->spec.robot;
      sa->sensor_frame = ha->spec.sensor_frame;
      sa->radius_mm = ha->spec.radius_mm;
      RunHandEyeSections(*sa);
      return;
    }
    if (ha->spec.cell.empty() || ha->spec.camera.empty() || ha->spec.sweeps.empty()) {
      throw OptionError(
          "calibrate handeye-laser: give --cell, --camera and --sweeps (sphere sweeps), or "
          "--profiles, --poses, --pose-format, --sphere-side and --sphere-radius (one "
          "calibrated profile per robot pose)");
    }
    RunHandEyeLaser(*ha);
  });
}

}  // namespace lasercell::tools
