#include "tools/cmd_calibrate_handeye_sections.hpp"

#include <cstdio>

#include "calib/sphere_section_hand_eye.hpp"
#include "calib/sphere_section_report.hpp"
#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/json_io.hpp"
#include "triangulation/foreign_profiles.hpp"

namespace lasercell::tools {

void AddHandEyeSectionOptions(CLI::App* cmd, HandEyeSectionArgs& a) {
  cmd->add_option("--profiles", a.profiles,
                  "Sections variant: one calibrated profile per robot pose across a fixed sphere "
                  "(OpenCV YAML with a scan_line key, x 0 z triples in mm), in pose order");
  cmd->add_option("--poses", a.poses,
                  "Sections variant: base_from_flange of each profile (see --pose-format)");
  cmd->add_option("--pose-format", a.pose_format,
                  "Pose file format: xyzwpr (Fanuc, R = Rz(r) Ry(p) Rx(w), deg), xyzabc (KUKA, "
                  "R = Rz(A) Ry(B) Rx(C), deg), kuka (4x4, metres) or yaml; required for Euler "
                  "angles: a file does not say its convention");
  cmd->add_option("--sphere-side", a.sphere_side,
                  "Sections variant: side of the laser plane the sphere centre lies on, +y or -y "
                  "(sensor frame; required)");
  cmd->add_flag("--estimate-radius", a.estimate_radius,
                "Sections variant: estimate the sphere radius too (default: held at "
                "--sphere-radius)");
}

bool HandEyeSectionsRequested(const HandEyeSectionArgs& a) {
  return !a.profiles.empty() || !a.poses.empty();
}

void RunHandEyeSections(const HandEyeSectionArgs& a) {
  if (a.profiles.empty() || a.poses.empty()) {
    throw OptionError("calibrate handeye-laser: the sections variant needs --profiles and --poses");
  }
  if (a.pose_format.empty()) {
    throw OptionError(
        "calibrate handeye-laser: --pose-format is required with --profiles (xyzwpr, xyzabc, "
        "kuka or yaml)");
  }
  if (a.sphere_side != "+y" && a.sphere_side != "-y") {
    throw OptionError("calibrate handeye-laser: --sphere-side must be +y or -y (got '" +
                      a.sphere_side + "'): the side of the laser plane the sphere centre is on");
  }
  if (!(a.radius_mm > 0)) {
    throw OptionError("calibrate handeye-laser: --sphere-radius (mm) is required with --profiles");
  }
  if (a.cell.empty() && a.json.empty()) {
    throw OptionError(
        "calibrate handeye-laser: give --cell (the edge is updated) and/or --json (the result)");
  }
  const std::vector<calib::SphereSectionProfile> profiles =
      triangulation::LoadSphereSections(a.profiles, a.poses, a.pose_format);
  calib::SphereSectionRun run{a.poses, a.pose_format, a.profiles, {}};
  run.options.sphere_radius_mm = a.radius_mm;
  run.options.estimate_radius = a.estimate_radius;
  run.options.sphere_side = a.sphere_side == "+y" ? 1 : -1;
  const calib::SphereSectionHandEyeResult r =
      calib::CalibrateHandEyeFromSphereSections(profiles, run.options);
  json::WriteFile(a.json, calib::SphereSectionHandEyeJson(r, run));
  if (!a.report.empty()) {
    report::WriteHtmlReport(a.report, calib::SphereSectionHandEyeReport(r, run));
  }
  std::string written = a.json;
  if (!a.cell.empty()) {
    FrameGraph graph = LoadFrameGraph(a.cell);
    graph.SetStaticEdge(calib::SphereSectionEdge(graph, a.cell, a.robot, a.sensor_frame, r));
    written = a.output.empty() ? a.cell : a.output;
    SaveFrameGraph(written, graph);
  }
  std::printf("%s -> %s\n", r.Summary().c_str(), written.c_str());
}

}  // namespace lasercell::tools
